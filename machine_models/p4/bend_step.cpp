#include "machine_models/p4/bend_step.h"

#include "kernel/core/tolerances.h"
#include "kernel/core/content_hash.h"

#include <cmath>
#include <limits>

namespace gk::p4 {

const char* to_string(StepKind kind) {
  switch (kind) {
    case StepKind::kClamp: return "CLAMP";
    case StepKind::kBendUp: return "BEND_UP";
    case StepKind::kBendDown: return "BEND_DOWN";
    case StepKind::kRotate: return "ROTATE";
    case StepKind::kApproach: return "APPROACH";
    case StepKind::kRetract: return "RETRACT";
  }
  return "?";
}

Hash128 BendStep::hash() const {
  return ContentHash()
      .add({static_cast<double>(kind), bend_point_mm.x(), bend_point_mm.y(), bend_direction.x(), bend_direction.y(),
            target_angle_deg, rotate_angle_deg, travel_mm.x(), travel_mm.y(), travel_mm.z(), lateral_shift_mm, retract_mm, turned_deg})
      .value();
}

Result<bool> validate_step(const MachineModel& model, const BendStep& step) {
  // Malformed or absurd values are errors naming the field; values the machine cannot reach but
  // that make sense (an angle past the machine's range, a travel past its end) are machine limits,
  // denied by the validator.
  constexpr double kMax = tolerances::kMaxMachineLengthMm;
  auto sane = [&](double v) { return std::isfinite(v) && std::fabs(v) <= kMax; };
  if (!sane(step.bend_point_mm.x()) || !sane(step.bend_point_mm.y()))
    return invalid_argument("bend_point", "must be finite and within 1e5 mm");
  if (!sane(step.bend_direction.x()) || !sane(step.bend_direction.y()) || !(step.bend_direction.norm() > 1e-9))
    return invalid_argument("bend_direction", "must be a finite, non-zero direction");
  if (!std::isfinite(step.lateral_shift_mm) || std::fabs(step.lateral_shift_mm) > model.max_bend_length_mm)
    return invalid_argument("lateral_shift_mm", "must be finite and within the machine's bend length");
  // Every field is checked whatever the step's kind: a malformed value is an error even where it
  // would not be used.
  if (!std::isfinite(step.target_angle_deg) || std::fabs(step.target_angle_deg) >= 180.0)
    return invalid_argument("target_angle_deg", "must be a finite angle below 180 degrees");
  if (!std::isfinite(step.rotate_angle_deg) || std::fabs(step.rotate_angle_deg) > 360.0)
    return invalid_argument("rotate_angle_deg", "must be within [-360, 360] degrees");
  if (!sane(step.travel_mm.x()) || !sane(step.travel_mm.y()) || !sane(step.travel_mm.z()))
    return invalid_argument("travel", "must be finite and within 1e5 mm");
  if (step.kind == StepKind::kBendUp || step.kind == StepKind::kBendDown) {
    if (!(step.target_angle_deg > 0.0)) return invalid_argument("target_angle_deg", "must be a magnitude in (0, 180) degrees");
  }
  if (!sane(step.retract_mm) || step.retract_mm < 0.0) return invalid_argument("retract_mm", "must be >= 0 and at most 1e5 mm");
  if (!std::isfinite(step.turned_deg) || std::fabs(step.turned_deg) > 360.0)
    return invalid_argument("turned_deg", "must be within [-360, 360] degrees");
  if (step.kind == StepKind::kRotate) {
    if (!std::isfinite(step.rotate_angle_deg) || step.rotate_angle_deg == 0.0 || std::fabs(step.rotate_angle_deg) > 360.0)
      return invalid_argument("rotate_angle_deg", "must be non-zero and within [-360, 360] degrees");
  }
  if (step.kind == StepKind::kApproach || step.kind == StepKind::kRetract) {
    if (!sane(step.travel_mm.x()) || !sane(step.travel_mm.y()) || !sane(step.travel_mm.z()) ||
        !(step.travel_mm.norm() > 0.0))
      return invalid_argument("travel", "must be a finite, non-zero travel within 1e5 mm");
    if (step.travel_mm.z() != 0.0)
      return invalid_argument("travel.z_mm", "must be 0: the manipulator moves the part in the table's plane");
  }
  return true;
}

RigidTransform part_placement(const SheetPart& part, const BendStep& step) {
  const Vec2 d2 = step.bend_direction.normalized();
  const Vec3 d(d2.x(), d2.y(), 0.0), n(-d2.y(), d2.x(), 0.0), q(step.bend_point_mm.x(), step.bend_point_mm.y(), 0.0);
  RigidTransform to_machine;
  to_machine.rotation.row(0) = d.transpose();
  to_machine.rotation.row(1) = n.transpose();
  to_machine.rotation.row(2) = Vec3::UnitZ().transpose();
  to_machine.translation = -(to_machine.rotation * q);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& c : part.extent_points()) {
    const double x = to_machine.apply(c).x();
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  to_machine.translation.x() += -0.5 * (lo + hi) + step.lateral_shift_mm;
  return to_machine;
}

}  // namespace gk::p4
