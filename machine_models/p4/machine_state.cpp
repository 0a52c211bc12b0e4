#include "machine_models/p4/machine_state.h"

#include "kernel/core/content_hash.h"
#include "machine_models/p4/machine_model.h"
#include "kernel/core/tolerances.h"

#include <cmath>

namespace gk::p4 {

Hash128 MachineState::hash() const {
  ContentHash h;
  h.add(static_cast<double>(engaged_segments.size()));
  for (bool e : engaged_segments) h.add(e ? 1.0 : 0.0);
  h.add({clamp_z_mm, manipulator_x_mm, manipulator_y_mm, manipulator_rotation_deg, lower_blade_z_offset_mm});
  return h.value();
}

MachineState MachineState::with_aba_span(const MachineModel& model, double x_min, double x_max, double clamp_z_mm) {
  MachineState s;
  s.clamp_z_mm = clamp_z_mm;
  s.engaged_segments.resize(model.aba.segment_widths_mm.size());
  const auto spans = model.slot_spans();
  for (std::size_t i = 0; i < s.engaged_segments.size(); ++i)
    s.engaged_segments[i] = spans[i].first >= x_min - tolerances::kMachineLengthSlackMm && spans[i].second <= x_max + tolerances::kMachineLengthSlackMm;
  return s;
}

Result<bool> validate_state(const MachineModel& model, const MachineState& state) {
  if (!state.engaged_segments.empty() && state.engaged_segments.size() != model.aba.segment_widths_mm.size())
    return invalid_argument("engaged_segments", "expected " + std::to_string(model.aba.segment_widths_mm.size()) +
                                                    " entries (one per ABA slot), got " +
                                                    std::to_string(state.engaged_segments.size()));
  if (!std::isfinite(state.clamp_z_mm) || state.clamp_z_mm < 0.0 || state.clamp_z_mm > 1000.0)
    return invalid_argument("clamp_z_mm", "must be within [0, 1000] mm");
  if (!std::isfinite(state.manipulator_x_mm) || state.manipulator_x_mm < model.manipulator.travel_x_mm[0] ||
      state.manipulator_x_mm > model.manipulator.travel_x_mm[1])
    return invalid_argument("manipulator_x_mm", "outside the manipulator's travel");
  if (!std::isfinite(state.manipulator_y_mm) || state.manipulator_y_mm < model.manipulator.travel_y_mm[0] ||
      state.manipulator_y_mm > model.manipulator.travel_y_mm[1])
    return invalid_argument("manipulator_y_mm", "outside the manipulator's travel");
  if (!std::isfinite(state.manipulator_rotation_deg) || std::fabs(state.manipulator_rotation_deg) > 360.0)
    return invalid_argument("manipulator_rotation_deg", "must be within [-360, 360] degrees");
  if (!std::isfinite(state.lower_blade_z_offset_mm) || std::fabs(state.lower_blade_z_offset_mm) > 500.0)
    return invalid_argument("lower_blade_z_offset_mm", "must be within [-500, 500] mm");
  return true;
}

bool MachineState::operator==(const MachineState& o) const {
  return engaged_segments == o.engaged_segments && clamp_z_mm == o.clamp_z_mm && manipulator_x_mm == o.manipulator_x_mm &&
         manipulator_y_mm == o.manipulator_y_mm && manipulator_rotation_deg == o.manipulator_rotation_deg &&
         lower_blade_z_offset_mm == o.lower_blade_z_offset_mm;
}

}  // namespace gk::p4
