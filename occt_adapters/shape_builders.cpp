#include "occt_adapters/shape_builders.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <gp_Ax3.hxx>
#include <gp_Pln.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeRevol.hxx>
#include <BRep_Builder.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax1.hxx>
#include <gp_Trsf.hxx>

#include <cmath>

namespace gk::occt {
namespace {

gp_Pnt pnt(const Vec3& v) { return gp_Pnt(v.x(), v.y(), v.z()); }

// OCCT sweeps faces and shells but not solids ("Solids are not Processed"): a solid is swept through
// its boundary shells. For collision this loses nothing: an obstacle inside the swept solid meets
// the swept boundary, or lies inside the part at its start or end position.
TopoDS_Shape boundary_of_solids(const TopoDS_Shape& shape) {
  bool has_solid = false;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More() && !has_solid; e.Next()) has_solid = true;
  if (!has_solid) return shape;
  TopoDS_Compound shells;
  BRep_Builder builder;
  builder.MakeCompound(shells);
  for (TopExp_Explorer e(shape, TopAbs_SHELL); e.More(); e.Next()) builder.Add(shells, e.Current());
  for (TopExp_Explorer e(shape, TopAbs_FACE, TopAbs_SHELL); e.More(); e.Next()) builder.Add(shells, e.Current());
  return shells;
}

}  // namespace

Result<Shape> make_box(const Vec3& min, const Vec3& max) {
  if (!min.allFinite() || !max.allFinite()) return invalid_argument("box", "corners must be finite");
  if (!((max - min).array() > 0.0).all()) return invalid_argument("box", "max must exceed min on every axis");
  TopoDS_Shape s;
  auto ran = guarded("box", "making a box", [&] { s = BRepPrimAPI_MakeBox(pnt(min), pnt(max)).Shape(); });
  if (!ran.ok()) return ran.error();
  return wrap(s);
}

Result<Shape> make_rectangle(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v) {
  if (!corner.allFinite() || !edge_u.allFinite() || !edge_v.allFinite())
    return invalid_argument("rectangle", "corner and edges must be finite");
  if (!(edge_u.norm() > 0.0) || !(edge_v.norm() > 0.0) || std::fabs(edge_u.normalized().dot(edge_v.normalized())) > 1e-12)
    return invalid_argument("rectangle", "edges must be non-zero and perpendicular");
  TopoDS_Shape s;
  auto ran = guarded("rectangle", "making a face", [&] {
    const Vec3 n = edge_u.cross(edge_v).normalized();
    const Vec3 u = edge_u.normalized();
    const gp_Pln plane(gp_Ax3(pnt(corner), gp_Dir(n.x(), n.y(), n.z()), gp_Dir(u.x(), u.y(), u.z())));
    s = BRepBuilderAPI_MakeFace(plane, 0.0, edge_u.norm(), 0.0, edge_v.norm()).Shape();
  });
  if (!ran.ok()) return ran.error();
  return wrap(s);
}

Result<Shape> make_prism_yz(const std::vector<Eigen::Vector2d>& profile_yz, double x_min, double x_max) {
  if (profile_yz.size() < 3) return invalid_argument("profile_yz", "needs at least three points");
  if (!(x_max > x_min)) return invalid_argument("x_range", "max must exceed min");
  TopoDS_Shape s;
  bool done = false;
  auto ran = guarded("profile_yz", "making a prism", [&] {
    BRepBuilderAPI_MakePolygon polygon;
    for (const auto& p : profile_yz) polygon.Add(gp_Pnt(x_min, p.x(), p.y()));
    polygon.Close();
    BRepBuilderAPI_MakeFace face(polygon.Wire(), true);
    if (!face.IsDone()) return;
    BRepPrimAPI_MakePrism prism(face.Face(), gp_Vec(x_max - x_min, 0.0, 0.0), true, true);
    done = prism.IsDone();
    if (done) s = prism.Shape();
  });
  if (!ran.ok()) return ran.error();
  if (!done) return invalid_argument("profile_yz", "OCCT could not build the prism");
  return wrap(s);
}

Result<Shape> place(const Shape& shape, const RigidTransform& pose) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (!pose.is_rigid()) return invalid_argument("pose", "not a finite rigid transform");
  TopoDS_Shape s;
  auto ran = guarded("pose", "placing a shape", [&] {
    gp_Trsf t;
    const Mat3& r = pose.rotation;
    const Vec3& p = pose.translation;
    t.SetValues(r(0, 0), r(0, 1), r(0, 2), p.x(), r(1, 0), r(1, 1), r(1, 2), p.y(), r(2, 0), r(2, 1), r(2, 2), p.z());
    s = BRepBuilderAPI_Transform(shape.impl().shape, t, true).Shape();
  });
  if (!ran.ok()) return ran.error();
  return wrap(s);
}

Result<Shape> make_compound(const std::vector<Shape>& shapes) {
  if (shapes.empty()) return invalid_argument("shapes", "nothing to combine");
  TopoDS_Compound compound;
  BRep_Builder builder;
  builder.MakeCompound(compound);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    if (shapes[i].is_null()) return invalid_argument("shapes[" + std::to_string(i) + "]", "is empty");
    builder.Add(compound, shapes[i].impl().shape);
  }
  return wrap(compound);
}

Result<Shape> revolve(const Shape& shape, const Vec3& axis_point, const Vec3& axis_direction, double angle_deg) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (!std::isfinite(angle_deg) || angle_deg == 0.0 || std::fabs(angle_deg) > 360.0)
    return invalid_argument("angle_deg", "must be finite, non-zero and within [-360, 360] degrees (OCCT wraps larger angles)");
  if (!axis_point.allFinite()) return invalid_argument("axis_point", "must be finite");
  if (!axis_direction.allFinite() || !(axis_direction.norm() > 0.0))
    return invalid_argument("axis_direction", "must be a finite, non-zero vector");
  TopoDS_Shape s;
  bool done = false;
  auto ran = guarded("axis", "revolving a shape", [&] {
    const Vec3 d = axis_direction.normalized();
    BRepPrimAPI_MakeRevol revol(boundary_of_solids(shape.impl().shape), gp_Ax1(pnt(axis_point), gp_Dir(d.x(), d.y(), d.z())),
                                angle_deg * M_PI / 180.0, true);
    done = revol.IsDone();
    if (done) s = revol.Shape();
  });
  if (!ran.ok()) return ran.error();
  if (!done) return invalid_argument("axis", "OCCT could not revolve the shape (does the axis cross it?)");
  return wrap(s);
}

Result<Shape> extrude(const Shape& shape, const Vec3& travel) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (!travel.allFinite() || !(travel.norm() > 0.0)) return invalid_argument("travel", "must be a finite, non-zero vector");
  TopoDS_Shape s;
  bool done = false;
  auto ran = guarded("travel", "extruding a shape", [&] {
    BRepPrimAPI_MakePrism prism(boundary_of_solids(shape.impl().shape), gp_Vec(travel.x(), travel.y(), travel.z()), true, true);
    done = prism.IsDone();
    if (done) s = prism.Shape();
  });
  if (!ran.ok()) return ran.error();
  if (!done) return invalid_argument("travel", "OCCT could not extrude the shape");
  return wrap(s);
}

}  // namespace gk::occt
