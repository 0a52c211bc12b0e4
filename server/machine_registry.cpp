#include "server/machine_registry.h"

#include <unordered_map>

namespace gk::server {

Result<std::unique_ptr<MachineRegistry>> MachineRegistry::create() {
  std::unique_ptr<MachineRegistry> registry(new MachineRegistry());
  auto model = p4::default_machine_model();
  if (!model.ok()) return model.error();
  Machine m;
  m.snapshot.id = kDefaultMachine;
  m.snapshot.model = model.value();
  m.snapshot.model_toml = p4::embedded_default_model_toml();
  m.snapshot.state.engaged_segments.assign(model.value().aba.segment_widths_mm.size(), true);
  registry->machines_[kDefaultMachine] = std::move(m);
  return registry;
}

std::vector<MachineSnapshot> MachineRegistry::list() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<MachineSnapshot> out;
  for (const auto& [id, m] : machines_) out.push_back(m.snapshot);
  return out;
}

Result<MachineSnapshot> MachineRegistry::get(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = machines_.find(resolve(id));
  if (it == machines_.end()) return Error{ErrorCode::kNotFound, "machine_id", "no machine '" + id + "'"};
  return it->second.snapshot;
}

Result<bool> MachineRegistry::set_state(const std::string& id, const p4::MachineState& state) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = machines_.find(resolve(id));
  if (it == machines_.end()) return Error{ErrorCode::kNotFound, "machine_id", "no machine '" + id + "'"};
  auto valid = p4::validate_state(it->second.snapshot.model, state);
  if (!valid.ok()) return valid;
  it->second.snapshot.state = state;
  return true;
}

Result<MachineSnapshot> MachineRegistry::put_model(const std::string& id, const std::string& model_toml) {
  if (id.empty()) return invalid_argument("machine_id", "must not be empty");
  auto model = p4::parse_machine_model(model_toml);
  if (!model.ok()) return invalid_argument("model_toml." + model.error().field, model.error().message);
  std::lock_guard<std::mutex> lock(mutex_);
  Machine& m = machines_[id];
  m.snapshot.id = id;
  m.snapshot.model = model.value();
  m.snapshot.model_toml = model_toml;
  m.snapshot.state = p4::MachineState{};
  m.snapshot.state.engaged_segments.assign(model.value().aba.segment_widths_mm.size(), true);
  m.snapshot.version += 1;
  return m.snapshot;
}

Result<p4::StepValidator*> MachineRegistry::validator(const std::string& id, const p4::MachineState* state) {
  auto snapshot = get(id);
  if (!snapshot.ok()) return snapshot.error();
  // One validator per (thread, registry, machine): built on the thread's first request.
  struct Local {
    std::unique_ptr<p4::StepValidator> validator;
  };
  thread_local std::unordered_map<std::string, Local> locals;
  const std::string key = std::to_string(reinterpret_cast<std::uintptr_t>(this)) + "/" + snapshot.value().id + "/" +
                          std::to_string(snapshot.value().version);
  Local& local = locals[key];
  if (!local.validator) {
    auto scene = p4::MachineScene::build(snapshot.value().model);
    if (!scene.ok()) return scene.error();
    local.validator = std::make_unique<p4::StepValidator>(scene.value());
  }
  const p4::MachineState& wanted = state ? *state : snapshot.value().state;
  if (local.validator->scene().state().hash() != wanted.hash()) {
    auto applied = local.validator->set_state(wanted);
    if (!applied.ok()) return applied.error();
  }
  return local.validator.get();
}

}  // namespace gk::server
