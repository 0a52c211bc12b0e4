// The slots of a B-Rep part, as fixture features (seed 004: a bolt in a T-slot): pairs of parallel
// planar faces facing each other across empty space, the material beyond both.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <vector>

namespace gk::occt {

// Two walls of a slot: their mid-plane through origin with unit normal `across`, `width_mm` apart;
// the part of them that faces the other, a rectangle half_length_mm either side of origin along
// `along` and half_depth_mm along across x along.
struct PlanarSlot {
  int face_a = 0, face_b = 0;  // 1-based, in the shape's face map order (TopExp::MapShapes)
  Vec3 origin = Vec3::Zero();
  Vec3 across = Vec3::UnitY();
  Vec3 along = Vec3::UnitX();
  double width_mm = 0.0;
  double half_length_mm = 0.0;
  double half_depth_mm = 0.0;
};

// Every pair of planar faces whose outward normals are opposite and point at each other, and whose
// rectangles overlap when one is seen along the normal on the other, in the order of the first face.
Result<std::vector<PlanarSlot>> planar_slots(const Shape& shape);

}  // namespace gk::occt
