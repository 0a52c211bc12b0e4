// ValidateStep through the engine: the question in the machine model's terms, answered by the
// machine's validator (machine_models/p4) and kept in the one answer cache. Each thread has its
// own validator, so a repeated question may land on a thread that has not seen it: the cache is
// shared, keyed by the question's exact bytes (never a hash: two questions that differ in one bit
// never share an answer).
#pragma once

#include "engine/machines/machine_registry.h"
#include "engine/parts/part_registry.h"
#include "machine_models/p4/step_validator.h"

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace gk::engine {

// The part of a question: a parametric sheet part, or an uploaded part's surface.
struct StepPart {
  p4::SheetPartSpec spec;       // parametric: every field; uploaded: thickness_mm only
  std::string part_id;          // set: an uploaded part (mesh or CAD)
  double deflection_mm = 0.0;   // an uploaded CAD part's tessellation [mm] (0: kPartDeflectionMm)
};

struct StepQuestion {
  std::string machine_id;                 // empty: the default machine
  StepPart part;
  p4::BendStep step;
  std::optional<p4::MachineState> state;  // none: the machine's current state
  bool with_corrections = true;           // a denied step gets a validated correction
};

struct StepReply {
  p4::StepAnswer answer;
  bool from_cache = false;  // answered from the cache (answer.times then hold only the lookup)
};

class StepAnswers {
 public:
  StepAnswers(MachineRegistry& machines, PartRegistry& parts, std::size_t cache_capacity = 100000)
      : machines_(machines), parts_(parts), capacity_(cache_capacity) {}

  // A question answered before, from the cache alone (cheap: no part is built, nothing waits on
  // a validator); nullopt otherwise, or when the question is malformed (validate() says why).
  std::optional<StepReply> cached(const StepQuestion& question) const;
  // The answer: from the cache, else validated (fields checked first, each error naming it).
  Result<StepReply> validate(const StepQuestion& question);

  // Lookups answered from the cache and not, and the answers kept (what /metrics reports).
  struct CacheStats {
    std::uint64_t hits = 0, misses = 0;
    std::size_t entries = 0;
  };
  CacheStats cache_stats() const;

 private:
  static std::string key_of(const StepQuestion& question, const MachineVersion& machine);
  std::optional<StepReply> lookup(const std::string& key, std::chrono::steady_clock::time_point t0, bool count_miss) const;

  MachineRegistry& machines_;
  PartRegistry& parts_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, p4::StepAnswer> answers_;
  mutable std::uint64_t hits_ = 0, misses_ = 0;  // mutex_ held
};

}  // namespace gk::engine
