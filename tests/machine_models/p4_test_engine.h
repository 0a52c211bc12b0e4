// A P4 engine on the default model for tests: the scene, a validator, and small part and step
// builders. The manipulator stands 400 mm behind the bend line, on the held side of the parts the
// tests use and clear of the blankholder.
#pragma once

#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/step_validator.h"

#include <memory>

namespace gk::p4::testing_engine {

struct Engine {
  std::shared_ptr<MachineScene> scene;
  std::unique_ptr<StepValidator> validator;
  MachineModel model;
};

inline MachineState default_state(double clamp_z) {
  MachineState s;
  s.clamp_z_mm = clamp_z;
  s.manipulator_y_mm = -400.0;
  return s;
}

inline Engine make_engine(double clamp_z, ValidatorOptions options = {}, const MachineModel* model = nullptr) {
  Engine e;
  e.model = model ? *model : default_machine_model().value();
  e.scene = MachineScene::build(e.model).value();
  e.validator = std::make_unique<StepValidator>(e.scene, options);
  (void)e.validator->set_state(default_state(clamp_z));
  return e;
}

inline SheetPart flat_part(double width, double depth, double t) { return SheetPart::create({width, depth, t, {}, {}}).value(); }

inline BendStep bend(StepKind kind, double y_line, double angle) {
  BendStep s;
  s.kind = kind;
  s.bend_point_mm = Vec2(0.0, y_line);
  s.bend_direction = Vec2(1.0, 0.0);  // the moving side (left of +X) is +Y: y > y_line
  s.target_angle_deg = angle;
  return s;
}

}  // namespace gk::p4::testing_engine
