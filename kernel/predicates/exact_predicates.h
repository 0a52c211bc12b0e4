// Adaptive exact orientation predicates after Shewchuk (1997), "Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates". A cheap floating-point evaluation is trusted
// when it clears a proven error bound; otherwise the determinant is evaluated exactly with
// floating-point expansions. The sign returned is always the sign of the exact determinant of the
// given double coordinates.
#pragma once

#include "kernel/core/geometry_types.h"

namespace gk::exact {

// Sign of ((b - a) x (c - a)) . (d - a): +1 when d lies on the side the right-handed normal of the
// triangle (a, b, c) points to, -1 on the other side, 0 when the four points are coplanar.
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Sign of (b - a) x (c - a) in the plane: +1 counter-clockwise, -1 clockwise, 0 collinear.
int orient2d(double ax, double ay, double bx, double by, double cx, double cy);

// True when the three points are exactly collinear (every axis projection has zero area).
bool collinear(const Vec3& a, const Vec3& b, const Vec3& c);

// How often the exact fallback ran since start (per thread): tells tests and benchmarks how often
// the fast filter was unsure.
long long exact_fallback_count();

}  // namespace gk::exact
