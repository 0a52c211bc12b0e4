// The cylindrical faces of a B-Rep part, as fixture features (seed 004: holes and pins): where a
// pin fits a hole the two are matched on these, not on their tessellations.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <vector>

namespace gk::occt {

// One cylinder of the part: the faces lying on it (a cylinder is often split into two half faces),
// its axis through origin (unit axis), the extent of those faces along it either side of origin,
// and whether it bounds a hole (the material outside the cylinder) or a pin (the material inside).
struct CylindricalFace {
  std::vector<int> faces;  // 1-based, in the shape's face map order (TopExp::MapShapes), ascending
  Vec3 origin = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double radius_mm = 0.0;
  double half_length_mm = 0.0;
  bool hole = false;
};

// Every cylinder of the shape's faces, in the order of their first face.
Result<std::vector<CylindricalFace>> cylindrical_faces(const Shape& shape);

}  // namespace gk::occt
