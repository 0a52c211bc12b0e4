// The machines the daemon serves: their models and current states, and for each calling thread
// its own validator (validators are not thread-safe; scenes are cheap to build per thread).
#pragma once

#include "machine_models/p4/step_validator.h"

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace gk::engine {

struct MachineSnapshot {
  std::string id;
  p4::MachineModel model;
  std::string model_toml;
  p4::MachineState state;
  unsigned long long version = 0;  // bumps when the model is replaced
};

// What identifies a machine's answers: its id, model version and current state (no model copy).
struct MachineVersion {
  std::string id;
  unsigned long long version = 0;
  p4::MachineState state;
};

class MachineRegistry {
 public:
  static constexpr const char* kDefaultMachine = "p4-default";

  // Starts with the embedded default P4 model as "p4-default", then the models stored in
  // models_dir (one <id>.toml each; empty: none are stored).
  static Result<std::unique_ptr<MachineRegistry>> create(const std::string& models_dir = "");

  std::vector<MachineSnapshot> list() const;
  Result<MachineSnapshot> get(const std::string& id) const;  // "" means the default
  // The same without copying the model: what a cache lookup needs.
  Result<MachineVersion> current(const std::string& id) const;
  Result<bool> set_state(const std::string& id, const p4::MachineState& state);
  // Adds or replaces a machine from its model file, acknowledged once the file is on disk (written
  // to a temporary file, fsync'd, renamed); the state resets to all segments engaged.
  Result<MachineSnapshot> put_model(const std::string& id, const std::string& model_toml);

  // The calling thread's validator for the machine, set to `state` (or the machine's current state).
  Result<p4::StepValidator*> validator(const std::string& id, const p4::MachineState* state);

 private:
  struct Machine {
    MachineSnapshot snapshot;
  };
  MachineRegistry() = default;
  std::string resolve(const std::string& id) const { return id.empty() ? kDefaultMachine : id; }
  Result<MachineSnapshot> install(const std::string& id, const std::string& model_toml);

  std::string models_dir_;
  // Names this registry's validators in each thread's table (an address could be reused by a later
  // registry whose machine has the same id and version but another model).
  const std::uint64_t instance_ = next_instance();
  static std::uint64_t next_instance();

  mutable std::mutex mutex_;
  std::map<std::string, Machine> machines_;
};

}  // namespace gk::engine
