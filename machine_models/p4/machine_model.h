// The P4 machine model: what the data file (p4_default.toml) says, validated.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"

#include <string>
#include <vector>

namespace gk::p4 {


// A machine organ as a convex YZ profile extruded along X.
struct PrismOrganSpec {
  std::string name;
  bool relative_to_clamp = false;  // placed relative to the clamp height (rises with the blankholder)
  double x_min_mm = 0.0, x_max_mm = 0.0;
  std::vector<Vec2> profile_yz_mm;  // convex, counter-clockwise (normalised on load)
  bool support = false;             // the part rests on it: its contact is intended
};

struct AbaSpec {
  std::vector<double> segment_widths_mm;  // fixed slots, left to right, centred on X = 0
  double gap_mm = 0.0;
  std::vector<Vec2> profile_yz_mm;  // one segment, relative to the clamp line
  double retract_z_mm = 0.0;         // how far a disengaged segment rises
};

// The manipulator, from the sheet's upper face up: suction cups, the gripper frame on them, the
// rotator column on the frame's centre. Offsets are in the gripper's frame (x along the bend line).
struct ManipulatorSpec {
  double travel_x_mm[2] = {0, 0};
  double travel_y_mm[2] = {0, 0};
  double cup_half_width_mm = 0.0;
  double cup_height_mm = 0.0;
  std::vector<Vec2> cup_offsets_mm;
  Vec2 frame_half_size_mm = Vec2::Zero();
  double frame_thickness_mm = 0.0;
  double rotator_radius_mm = 0.0;
  double rotator_height_mm = 0.0;  // above the gripper frame
};

struct MachineModel {
  std::string name;
  double max_bend_length_mm = 0.0;
  double max_bend_height_mm = 0.0;
  double min_thickness_mm = 0.0, max_thickness_mm = 0.0;
  double max_bend_angle_deg = 0.0;
  double bend_zone_mm = 0.0;
  double aba_lift_for_rotation_mm = 0.0;
  AbaSpec aba;
  std::vector<PrismOrganSpec> organs;
  ManipulatorSpec manipulator;

  // X range [min, max] of ABA slot i.
  double slot_x_min(std::size_t i) const;
  double slot_x_max(std::size_t i) const;
  // Every slot's X range, in one pass (the loops over all segments use this).
  std::vector<std::pair<double, double>> slot_spans() const;
};

// Parses and validates a model; errors name the TOML key (e.g. "organ[3].profile_yz_mm").
Result<MachineModel> parse_machine_model(const std::string& toml_text);
Result<MachineModel> load_machine_model_file(const std::string& path);
// The model gatekeeperd starts with: machine_models/p4/p4_default.toml, embedded at build time.
const char* embedded_default_model_toml();
Result<MachineModel> default_machine_model();

}  // namespace gk::p4
