#include "engine/machines/machine_registry.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace gk::engine {

Result<std::unique_ptr<MachineRegistry>> MachineRegistry::create(const std::string& models_dir) {
  std::unique_ptr<MachineRegistry> registry(new MachineRegistry());
  registry->models_dir_ = models_dir;
  auto model = p4::default_machine_model();
  if (!model.ok()) return model.error();
  Machine m;
  m.snapshot.id = kDefaultMachine;
  m.snapshot.model = model.value();
  m.snapshot.model_toml = p4::embedded_default_model_toml();
  m.snapshot.state.engaged_segments.assign(model.value().aba.segment_widths_mm.size(), true);
  registry->machines_[kDefaultMachine] = std::move(m);
  if (!models_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(models_dir, ec);
    if (ec) return Error{ErrorCode::kInternal, "storage", "cannot create " + models_dir};
    for (const auto& entry : std::filesystem::directory_iterator(models_dir, ec)) {
      if (entry.path().extension() != ".toml") continue;
      std::ifstream in(entry.path());
      std::stringstream text;
      text << in.rdbuf();
      auto installed = registry->install(entry.path().stem().string(), text.str());
      if (!installed.ok()) return Error{installed.error().code, entry.path().string(), installed.error().message};
    }
  }
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

Result<MachineVersion> MachineRegistry::current(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = machines_.find(resolve(id));
  if (it == machines_.end()) return Error{ErrorCode::kNotFound, "machine_id", "no machine '" + id + "'"};
  const MachineSnapshot& m = it->second.snapshot;
  return MachineVersion{m.id, m.version, m.state};
}

std::uint64_t MachineRegistry::next_instance() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
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
  if (id.empty() || id.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") != std::string::npos ||
      id[0] == '.')
    return invalid_argument("machine_id", "must be letters, digits, '-', '_' or '.'");
  auto model = p4::parse_machine_model(model_toml);
  if (!model.ok()) return invalid_argument("model_toml." + model.error().field, model.error().message);
  if (!models_dir_.empty()) {
    const std::string tmp = models_dir_ + "/." + id + ".toml.tmp", final_path = models_dir_ + "/" + id + ".toml";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) return Error{ErrorCode::kInternal, "storage", "cannot write the model file"};
    const bool written = ::write(fd, model_toml.data(), model_toml.size()) == static_cast<ssize_t>(model_toml.size()) &&
                         ::fsync(fd) == 0;
    ::close(fd);
    if (!written || std::rename(tmp.c_str(), final_path.c_str()) != 0)
      return Error{ErrorCode::kInternal, "storage", "cannot store the model file"};
    const int dir = ::open(models_dir_.c_str(), O_RDONLY | O_DIRECTORY);
    if (dir >= 0) {
      ::fsync(dir);
      ::close(dir);
    }
  }
  return install(id, model_toml);
}

Result<MachineSnapshot> MachineRegistry::install(const std::string& id, const std::string& model_toml) {
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
  auto machine = current(id);
  if (!machine.ok()) return machine.error();
  // One validator per (thread, registry, machine, model version): built on the thread's first
  // request, the model copied only then.
  struct Local {
    std::unique_ptr<p4::StepValidator> validator;
  };
  thread_local std::unordered_map<std::string, Local> locals;
  const std::string key = std::to_string(instance_) + "/" + machine.value().id + "/" + std::to_string(machine.value().version);
  Local& local = locals[key];
  if (!local.validator) {
    auto snapshot = get(id);
    if (!snapshot.ok()) return snapshot.error();
    // A model replaced since current(): start again with the newer one (never file its validator
    // under the older version).
    if (snapshot.value().version != machine.value().version) {
      locals.erase(key);
      return validator(id, state);
    }
    auto scene = p4::MachineScene::build(snapshot.value().model);
    if (!scene.ok()) return scene.error();
    // Answers are cached once, for every thread, by the engine (engine/steps/step_answers).
    p4::ValidatorOptions options;
    options.memoize_answers = false;
    local.validator = std::make_unique<p4::StepValidator>(scene.value(), options);
  }
  const p4::MachineState& wanted = state ? *state : machine.value().state;
  if (local.validator->scene().state() != wanted) {
    auto applied = local.validator->set_state(wanted);
    if (!applied.ok()) return applied.error();
  }
  return local.validator.get();
}

}  // namespace gk::engine
