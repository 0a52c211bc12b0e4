#include "occt_adapters/cylindrical_faces.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <gp_Cylinder.hxx>

#include <algorithm>
#include <cmath>

namespace gk::occt {
namespace {

// Faces lie on one cylinder when their radii, axis directions and axis lines agree to these
// (relative to the radius, and to the part's size for the line) - the same surface written twice.
constexpr double kSameRadiusRelative = 1e-9;
constexpr double kSameAxisSine = 1e-9;
constexpr double kSameLineRelative = 1e-9;

Vec3 vec(const gp_XYZ& p) { return Vec3(p.X(), p.Y(), p.Z()); }

struct OneFace {
  int index;
  Vec3 location, axis;
  double radius, v0, v1;  // along the axis from location
  bool hole;
};

}  // namespace

Result<std::vector<CylindricalFace>> cylindrical_faces(const Shape& shape) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  std::vector<OneFace> found;
  auto done = guarded("shape", "reading cylindrical faces", [&] {
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(shape.impl().shape, TopAbs_FACE, faces);
    for (int i = 1; i <= faces.Extent(); ++i) {
      const TopoDS_Face& face = TopoDS::Face(faces(i));
      const BRepAdaptor_Surface surface(face);
      if (surface.GetType() != GeomAbs_Cylinder) continue;
      const gp_Cylinder cylinder = surface.Cylinder();
      double u0, u1, v0, v1;
      BRepTools::UVBounds(face, u0, u1, v0, v1);
      // Which side the material is on: the face's outward normal (the surface's, reversed with the
      // face) against the direction away from the axis, at the middle of the face.
      gp_Pnt p;
      gp_Vec du, dv;
      surface.D1(0.5 * (u0 + u1), 0.5 * (v0 + v1), p, du, dv);
      gp_Vec normal = du.Crossed(dv);
      if (face.Orientation() == TopAbs_REVERSED) normal.Reverse();
      const gp_Ax1 axis = cylinder.Axis();
      const Vec3 location = vec(axis.Location().XYZ()), direction = vec(axis.Direction().XYZ());
      const Vec3 at = vec(p.XYZ()) - location;
      const Vec3 radial = at - direction * direction.dot(at);
      const bool hole = Vec3(normal.X(), normal.Y(), normal.Z()).dot(radial) < 0.0;
      found.push_back({i, location, direction, cylinder.Radius(), v0, v1, hole});
    }
  });
  if (!done.ok()) return done.error();
  const Aabb box = shape.bounds();
  const double size = std::max(1.0, (box.max - box.min).norm());

  std::vector<CylindricalFace> out;
  std::vector<std::pair<double, double>> extents;  // per cylinder: along its axis from its first face's location
  for (const OneFace& f : found) {
    const Vec3 a0 = f.location + f.axis * f.v0, a1 = f.location + f.axis * f.v1;
    std::size_t k = 0;
    for (; k < out.size(); ++k) {
      const CylindricalFace& c = out[k];
      const Vec3 off = f.location - c.origin;
      if (c.hole == f.hole && std::abs(c.radius_mm - f.radius) <= kSameRadiusRelative * std::max(1.0, f.radius) &&
          c.axis.cross(f.axis).norm() <= kSameAxisSine && (off - c.axis * c.axis.dot(off)).norm() <= kSameLineRelative * size)
        break;
    }
    if (k == out.size()) {
      out.push_back({{}, f.location, f.axis, f.radius, 0.0, f.hole});
      extents.emplace_back(INFINITY, -INFINITY);
    }
    CylindricalFace& c = out[k];
    c.faces.push_back(f.index);
    for (const Vec3& end : {a0, a1}) {
      const double t = c.axis.dot(end - c.origin);
      extents[k].first = std::min(extents[k].first, t);
      extents[k].second = std::max(extents[k].second, t);
    }
  }
  for (std::size_t k = 0; k < out.size(); ++k) {
    CylindricalFace& c = out[k];
    const double mid = 0.5 * (extents[k].first + extents[k].second);
    c.origin += c.axis * mid;
    c.half_length_mm = 0.5 * (extents[k].second - extents[k].first);
  }
  return out;
}

}  // namespace gk::occt
