#include "occt_adapters/planar_slots.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepTools.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <gp_Pln.hxx>

#include <algorithm>
#include <cmath>

namespace gk::occt {
namespace {

// Two walls are parallel when their normals are opposite to this (1 - |cos|), and a slot has a
// width of at least this fraction of the part's size (faces that touch are no slot).
constexpr double kOppositeNormals = 1e-12;
constexpr double kLeastWidthRelative = 1e-9;

Vec3 vec(const gp_XYZ& p) { return Vec3(p.X(), p.Y(), p.Z()); }

struct PlanarFace {
  int index;
  Vec3 normal;           // outward (out of the material)
  Vec3 point;            // the plane's origin
  Vec3 x, y;             // the plane's axes
  double u0, u1, v0, v1;  // the face's extent along them
};

}  // namespace

Result<std::vector<PlanarSlot>> planar_slots(const Shape& shape) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  std::vector<PlanarFace> faces;
  auto done = guarded("shape", "reading planar faces", [&] {
    TopTools_IndexedMapOfShape map;
    TopExp::MapShapes(shape.impl().shape, TopAbs_FACE, map);
    for (int i = 1; i <= map.Extent(); ++i) {
      const TopoDS_Face& face = TopoDS::Face(map(i));
      const BRepAdaptor_Surface surface(face);
      if (surface.GetType() != GeomAbs_Plane) continue;
      const gp_Pln plane = surface.Plane();
      Vec3 normal = vec(plane.Axis().Direction().XYZ());
      // The plane's own normal is X x Y; a face reversed in its solid, or on a left-handed plane,
      // faces the other way.
      const bool direct = plane.Direct();
      if ((face.Orientation() == TopAbs_REVERSED) == direct) normal = -normal;
      double u0, u1, v0, v1;
      BRepTools::UVBounds(face, u0, u1, v0, v1);
      faces.push_back({i, normal, vec(plane.Location().XYZ()), vec(plane.XAxis().Direction().XYZ()),
                       vec(plane.YAxis().Direction().XYZ()), u0, u1, v0, v1});
    }
  });
  if (!done.ok()) return done.error();
  const Aabb box = shape.bounds();
  const double least_width = kLeastWidthRelative * std::max(1.0, (box.max - box.min).norm());
  std::vector<PlanarSlot> out;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const PlanarFace& a = faces[i];
    for (std::size_t j = i + 1; j < faces.size(); ++j) {
      const PlanarFace& b = faces[j];
      if (a.normal.dot(b.normal) > -1.0 + kOppositeNormals) continue;
      const double width = a.normal.dot(b.point - a.point);  // a faces b across empty space
      if (!(width > least_width)) continue;
      // b's rectangle seen on a's plane, in a's axes: its four corners' range.
      double bu0 = INFINITY, bu1 = -INFINITY, bv0 = INFINITY, bv1 = -INFINITY;
      for (double u : {b.u0, b.u1})
        for (double v : {b.v0, b.v1}) {
          const Vec3 c = b.point + u * b.x + v * b.y - a.point;
          bu0 = std::min(bu0, c.dot(a.x));
          bu1 = std::max(bu1, c.dot(a.x));
          bv0 = std::min(bv0, c.dot(a.y));
          bv1 = std::max(bv1, c.dot(a.y));
        }
      const double lu0 = std::max(a.u0, bu0), lu1 = std::min(a.u1, bu1), lv0 = std::max(a.v0, bv0), lv1 = std::min(a.v1, bv1);
      if (!(lu1 > lu0) || !(lv1 > lv0)) continue;
      PlanarSlot s;
      s.face_a = a.index;
      s.face_b = b.index;
      s.across = a.normal;
      s.width_mm = width;
      const bool u_longer = lu1 - lu0 >= lv1 - lv0;
      s.along = u_longer ? a.x : a.y;
      s.half_length_mm = 0.5 * (u_longer ? lu1 - lu0 : lv1 - lv0);
      s.half_depth_mm = 0.5 * (u_longer ? lv1 - lv0 : lu1 - lu0);
      s.origin = a.point + 0.5 * (lu0 + lu1) * a.x + 0.5 * (lv0 + lv1) * a.y + 0.5 * width * a.normal;
      out.push_back(s);
    }
  }
  return out;
}

}  // namespace gk::occt
