#include "machine_models/p4/bend_step.h"

#include "machine_models/p4/content_hash.h"

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

std::uint64_t BendStep::hash() const {
  return ContentHash()
      .add({static_cast<double>(kind), bend_point_mm.x(), bend_point_mm.y(), bend_direction.x(), bend_direction.y(),
            target_angle_deg, rotate_angle_deg, travel_mm.x(), travel_mm.y(), travel_mm.z(), lateral_shift_mm, retract_mm})
      .value();
}

Result<bool> validate_step(const MachineModel& model, const BendStep& step) {
  if (!step.bend_point_mm.allFinite()) return invalid_argument("bend_line.point_mm", "not finite");
  if (!step.bend_direction.allFinite() || !(step.bend_direction.norm() > 1e-9))
    return invalid_argument("bend_line.direction", "zero-length bend line direction");
  if (!std::isfinite(step.lateral_shift_mm) || std::fabs(step.lateral_shift_mm) > model.max_bend_length_mm)
    return invalid_argument("lateral_shift_mm", "must be finite and within the machine's bend length");
  if (step.kind == StepKind::kBendUp || step.kind == StepKind::kBendDown) {
    if (!std::isfinite(step.target_angle_deg) || !(step.target_angle_deg > 0.0) ||
        step.target_angle_deg > model.max_bend_angle_deg)
      return invalid_argument("target_angle_deg", "must be in (0, " + std::to_string(model.max_bend_angle_deg) +
                                                      "] degrees for this machine");
  }
  if (step.kind == StepKind::kRotate) {
    if (!std::isfinite(step.rotate_angle_deg) || step.rotate_angle_deg == 0.0 || std::fabs(step.rotate_angle_deg) > 360.0)
      return invalid_argument("rotate_angle_deg", "must be non-zero and within [-360, 360] degrees");
    if (!std::isfinite(step.retract_mm) || step.retract_mm < 0.0) return invalid_argument("retract_mm", "must be >= 0");
  }
  if (step.kind == StepKind::kApproach || step.kind == StepKind::kRetract) {
    if (!step.travel_mm.allFinite() || !(step.travel_mm.norm() > 0.0) || step.travel_mm.norm() > 10000.0)
      return invalid_argument("travel_mm", "must be a finite, non-zero travel of at most 10 m");
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
