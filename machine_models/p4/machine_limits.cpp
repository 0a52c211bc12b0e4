#include "machine_models/p4/machine_limits.h"

#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>

namespace gk::p4 {

const char* to_string(MachineLimit limit) {
  switch (limit) {
    case MachineLimit::kNone: return "NONE";
    case MachineLimit::kManipulatorTravelX: return "MANIPULATOR_TRAVEL_X";
    case MachineLimit::kManipulatorTravelY: return "MANIPULATOR_TRAVEL_Y";
    case MachineLimit::kGripNotOnPart: return "GRIP_NOT_ON_PART";
    case MachineLimit::kNoClampingSegment: return "NO_CLAMPING_SEGMENT";
    case MachineLimit::kBendAngle: return "BEND_ANGLE";
    case MachineLimit::kThickness: return "THICKNESS";
    case MachineLimit::kBendLength: return "BEND_LENGTH";
  }
  return "?";
}

namespace {

using Polygon = std::vector<Vec2>;

// Sutherland-Hodgman: the convex polygon clipped to the half-plane side(p) >= 0.
template <class Side>
Polygon clip(const Polygon& poly, Side side) {
  Polygon out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    const double sa = side(a), sb = side(b);
    if (sa >= 0.0) out.push_back(a);
    if ((sa >= 0.0) != (sb >= 0.0)) out.push_back(a + (b - a) * (sa / (sa - sb)));
  }
  return out;
}

double area(const Polygon& poly) {
  double twice = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::fabs(twice);
}

double overlap_with_rectangle(const Polygon& poly, const Vec2& lo, const Vec2& hi) {
  Polygon p = clip(poly, [&](const Vec2& q) { return q.x() - lo.x(); });
  p = clip(p, [&](const Vec2& q) { return hi.x() - q.x(); });
  p = clip(p, [&](const Vec2& q) { return q.y() - lo.y(); });
  p = clip(p, [&](const Vec2& q) { return hi.y() - q.y(); });
  return p.size() < 3 ? 0.0 : area(p);
}

bool contains(const Polygon& poly, const Vec2& q) {
  // Convex, either orientation: q is inside when it is on the same side of every edge.
  int sign = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    const double c = (b - a).x() * (q - a).y() - (b - a).y() * (q - a).x();
    const int s = c > 0.0 ? 1 : (c < 0.0 ? -1 : 0);
    if (s == 0) continue;
    if (sign == 0) sign = s;
    if (s != sign) return false;
  }
  return true;
}

// The upper faces of the held side at height top_z (or, with at_or_above, at any height from
// top_z up), as convex polygons in XY.
std::vector<Polygon> upper_faces(const HeldSide& held, double top_z, bool at_or_above) {
  const double tol = tolerances::kIntendedContactMm;
  std::vector<Polygon> faces;
  if (held.plates) {
    for (const Plate& p : *held.plates) {
      // A horizontal plate: two edges in the XY plane, the third vertical.
      int vertical = -1;
      for (int e = 0; e < 3; ++e)
        if (std::fabs(p.edge[e].z()) > tolerances::kComparisonSlackRelative * std::max(1.0, p.edge[e].norm())) vertical = vertical < 0 ? e : 3;
      if (vertical < 0 || vertical > 2) continue;
      const Vec3& u = p.edge[(vertical + 1) % 3];
      const Vec3& v = p.edge[(vertical + 2) % 3];
      const double top = std::max(p.origin.z(), p.origin.z() + p.edge[vertical].z());
      if (at_or_above ? top < top_z - tol : std::fabs(top - top_z) > tol) continue;
      const Vec2 o(p.origin.x(), p.origin.y()), du(u.x(), u.y()), dv(v.x(), v.y());
      faces.push_back({o, o + du, o + du + dv, o + dv});
    }
  }
  if (held.vertices && held.faces) {
    for (const TriangleMesh::Face& f : *held.faces) {
      const Vec3& a = (*held.vertices)[f[0]];
      const Vec3& b = (*held.vertices)[f[1]];
      const Vec3& c = (*held.vertices)[f[2]];
      auto off = [&](const Vec3& v) { return at_or_above ? v.z() < top_z - tol : std::fabs(v.z() - top_z) > tol; };
      if (off(a) || off(b) || off(c)) continue;
      faces.push_back({Vec2(a.x(), a.y()), Vec2(b.x(), b.y()), Vec2(c.x(), c.y())});
    }
  }
  return faces;
}

}  // namespace

bool point_on_upper_face(const HeldSide& held, const Vec2& point, double top_z) {
  for (const Polygon& face : upper_faces(held, top_z, false))
    if (area(face) > 0.0 && contains(face, point)) return true;
  return false;
}

double clamped_area_mm2(const MachineModel& model, const MachineState& state, const HeldSide& held, double clamp_z) {
  // The footprint of a segment's lower face: the profile's lowest edge, across the slot's width.
  double low = std::numeric_limits<double>::infinity();
  for (const Vec2& q : model.aba.profile_yz_mm) low = std::min(low, q.y());
  double y0 = std::numeric_limits<double>::infinity(), y1 = -y0;
  for (const Vec2& q : model.aba.profile_yz_mm)
    if (q.y() == low) {
      y0 = std::min(y0, q.x());
      y1 = std::max(y1, q.x());
    }
  if (!(y1 > y0)) return 0.0;  // a segment with no flat lower face presses on a line at most
  const std::vector<Polygon> faces = upper_faces(held, clamp_z + low, true);
  double total = 0.0;
  const auto spans = model.slot_spans();
  for (std::size_t i = 0; i < spans.size(); ++i) {
    if (!state.engaged_segments.empty() && !state.engaged_segments[i]) continue;
    for (const Polygon& face : faces) total += overlap_with_rectangle(face, Vec2(spans[i].first, y0), Vec2(spans[i].second, y1));
  }
  return total;
}

}  // namespace gk::p4
