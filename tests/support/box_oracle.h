// Oriented boxes for tests: random boxes, and an independent separating-axis oracle that projects
// all eight corners of both boxes (computed here, not with OrientedBox::corners) onto the 15
// candidate axes.
#pragma once

#include "kernel/mesh/oriented_box.h"

#include <array>
#include <limits>
#include <random>

namespace gk::testing {

using Rng = std::mt19937_64;

Mat3 random_rotation(Rng& rng);
Vec3 random_vector(Rng& rng, double lo, double hi);
OrientedBox make_box(const Vec3& center, const Mat3& axes, const Vec3& half_extent);
std::array<Vec3, 8> corners_of(const OrientedBox& b);

// The largest gap between the projections of the two boxes over the 15 axes (unit length), negative
// when every projection overlaps (then minus the smallest overlap depth). Cross products shorter
// than 1e-6 are skipped: their axes are within 1e-6 rad of a face axis already tested.
struct SatResult {
  double gap = -std::numeric_limits<double>::infinity();
  bool face_axis_separates = false;
};
SatResult oracle_sat(const OrientedBox& a, const OrientedBox& b);

}  // namespace gk::testing
