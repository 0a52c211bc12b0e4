#include "engine/steps/step_answers.h"

#include <cmath>
#include <cstring>
#include <type_traits>

namespace gk::engine {
namespace {

using Clock = std::chrono::steady_clock;

// The question's bytes, field after field (lengths before strings and lists, so that no two
// questions give the same bytes).
class ExactKey {
 public:
  template <typename T>
  ExactKey& add(T v) {
    static_assert(std::is_arithmetic_v<T> || std::is_enum_v<T>);
    char bytes[sizeof v];
    std::memcpy(bytes, &v, sizeof v);
    key_.append(bytes, sizeof v);
    return *this;
  }
  ExactKey& add(const std::string& s) {
    add(s.size());
    key_ += s;
    return *this;
  }
  ExactKey& add(const Vec2& v) { return add(v.x()).add(v.y()); }
  ExactKey& add(const Vec3& v) { return add(v.x()).add(v.y()).add(v.z()); }
  std::string take() { return std::move(key_); }

 private:
  std::string key_;
};

void add_state(ExactKey& k, const p4::MachineState& s) {
  k.add(s.engaged_segments.size());
  for (bool e : s.engaged_segments) k.add(e);
  k.add(s.clamp_z_mm).add(s.manipulator_x_mm).add(s.manipulator_y_mm).add(s.manipulator_rotation_deg).add(s.lower_blade_z_offset_mm);
}

}  // namespace

std::string StepAnswers::key_of(const StepQuestion& q, const MachineVersion& machine) {
  ExactKey k;
  k.add(machine.id).add(machine.version).add(q.with_corrections);
  const p4::SheetPartSpec& p = q.part.spec;
  k.add(q.part.part_id).add(q.part.deflection_mm).add(p.width_mm).add(p.depth_mm).add(p.thickness_mm);
  k.add(p.flanges.size());
  for (const p4::FlangeSpec& f : p.flanges) k.add(f.side).add(f.height_mm).add(f.angle_deg).add(f.start_mm).add(f.length_mm);
  k.add(p.tabs.size());
  for (const p4::TabSpec& t : p.tabs) k.add(t.x_min_mm).add(t.x_max_mm).add(t.y_mm).add(t.height_mm);
  const p4::BendStep& s = q.step;
  k.add(s.kind).add(s.bend_point_mm).add(s.bend_direction).add(s.target_angle_deg).add(s.rotate_angle_deg).add(s.travel_mm);
  k.add(s.lateral_shift_mm).add(s.retract_mm).add(s.turned_deg);
  // Without a state of its own the question is asked in the machine's current one.
  k.add(q.state.has_value());
  add_state(k, q.state ? *q.state : machine.state);
  return k.take();
}

std::optional<StepReply> StepAnswers::lookup(const std::string& key, Clock::time_point t0, bool count_miss) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = answers_.find(key);
  if (it == answers_.end()) {
    if (count_miss) ++misses_;
    return std::nullopt;
  }
  ++hits_;
  StepReply reply{it->second, true};
  reply.answer.decided_by = p4::Stage::kCache;
  reply.answer.times = p4::StageTimes{};
  reply.answer.times.cache_us = reply.answer.times.total_us =
      std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  return reply;
}

std::optional<StepReply> StepAnswers::cached(const StepQuestion& question) const {
  const auto t0 = Clock::now();
  auto machine = machines_.current(question.machine_id);
  if (!machine.ok()) return std::nullopt;
  // A miss here is asked again in validate(), which counts it.
  return lookup(key_of(question, machine.value()), t0, false);
}

StepAnswers::CacheStats StepAnswers::cache_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {hits_, misses_, answers_.size()};
}

Result<StepReply> StepAnswers::validate(const StepQuestion& q) {
  const auto t0 = Clock::now();
  auto current = machines_.current(q.machine_id);
  if (!current.ok()) return Error{current.error().code, "machine_id", current.error().message};
  const MachineVersion& asked = current.value();
  const std::string key = key_of(q, asked);
  if (auto hit = lookup(key, t0, true)) return *hit;
  // A miss: the model is read for the checks (an answer of a model replaced meanwhile is not kept).
  auto machine = machines_.get(q.machine_id);
  if (!machine.ok()) return Error{machine.error().code, "machine_id", machine.error().message};
  if (!(q.part.deflection_mm >= 0.0) || !(q.part.deflection_mm <= 1000.0))
    return invalid_argument("part.deflection_mm", "must be in [0, 1000] mm (0: the default)");
  Result<p4::SheetPart> part = Error{};
  if (!q.part.part_id.empty()) {
    const double deflection = q.part.deflection_mm > 0.0 ? q.part.deflection_mm : kPartDeflectionMm;
    auto loaded = parts_.load(q.part.part_id, deflection);
    if (!loaded.ok()) return Error{loaded.error().code, "part.part_id", loaded.error().message};
    part = p4::SheetPart::from_surface(*loaded.value()->mesh, q.part.spec.thickness_mm, loaded.value()->deflection_mm);
  } else {
    part = p4::SheetPart::create(q.part.spec);
  }
  if (!part.ok()) return invalid_argument("part." + part.error().field, part.error().message);
  if (auto valid = p4::validate_step(machine.value().model, q.step); !valid.ok())
    return invalid_argument("step." + valid.error().field, valid.error().message);
  if (q.state)
    if (auto valid = p4::validate_state(machine.value().model, *q.state); !valid.ok())
      return invalid_argument("state." + valid.error().field, valid.error().message);
  // The state the key was made with, never the machine's state read again: a SetMachineState
  // between the two reads would store this state's answer under the other's key (a false CLEAR
  // once the machine is back in that state).
  const p4::MachineState& state = q.state ? *q.state : asked.state;
  auto validator = machines_.validator(asked.id, &state);
  if (!validator.ok()) return validator.error();
  auto answer = validator.value()->validate(part.value(), q.step, q.with_corrections);
  if (!answer.ok()) {
    // What the validator refuses is the step (its bend line, its motion): named as a field of it.
    Error e = answer.error();
    if (e.code == ErrorCode::kInvalidArgument && !e.field.empty() && e.field.rfind("step.", 0) != 0) e.field = "step." + e.field;
    return e;
  }
  // A model replaced meanwhile: the answer is this caller's, not the old version's to keep.
  auto now = machines_.current(q.machine_id);
  if (!now.ok() || now.value().version != asked.version) return StepReply{std::move(answer).value(), false};
  std::lock_guard<std::mutex> lock(mutex_);
  if (answers_.size() >= capacity_) answers_.clear();  // simple and bounded; a miss only costs time
  answers_[key] = answer.value();
  return StepReply{std::move(answer).value(), false};
}

}  // namespace gk::engine
