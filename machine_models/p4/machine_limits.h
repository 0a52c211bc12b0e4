// What the machine cannot do, whatever the geometry: travel, grip, clamp and range limits. A step
// beyond one is denied (INCONCLUSIVE with the limit named), never answered CLEAR.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/mesh/triangle_mesh.h"
#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/machine_state.h"
#include "machine_models/p4/sheet_part.h"

#include <string>
#include <vector>

namespace gk::p4 {

enum class MachineLimit {
  kNone,
  kManipulatorTravelX,  // the manipulator would leave its X travel
  kManipulatorTravelY,  // the manipulator would leave its Y travel
  kGripNotOnPart,       // the manipulator point is not on the part's upper face (the held side, in a bend)
  kNoClampingSegment,   // no engaged ABA segment presses the part's upper face
  kBendAngle,           // the bend angle is beyond the machine's range
  kThickness,           // the sheet thickness is outside the machine's range
  kBendLength,          // the bend line across the part is longer than the machine bends
};
const char* to_string(MachineLimit limit);

struct LimitCheck {
  MachineLimit limit = MachineLimit::kNone;
  std::string detail;  // for people: the values involved
};

// The held side of the part, in machine coordinates: plates, or (for a part given by its surface)
// triangles. Only faces whose top lies at `top_z` count as its upper face.
struct HeldSide {
  const std::vector<Plate>* plates = nullptr;
  const std::vector<Vec3>* vertices = nullptr;
  const std::vector<TriangleMesh::Face>* faces = nullptr;
};

// Is the point (x, y) on the held side's upper face at height top_z?
bool point_on_upper_face(const HeldSide& held, const Vec2& point, double top_z);

// The area of the held side's faces at or above the segments' lower face (clamp_z) lying under the
// engaged segments: what they press, or press into (a collision the geometry then reports). [mm^2]
double clamped_area_mm2(const MachineModel& model, const MachineState& state, const HeldSide& held, double clamp_z);

}  // namespace gk::p4
