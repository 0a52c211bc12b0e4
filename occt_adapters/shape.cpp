#include "occt_adapters/shape.h"

#include "occt_adapters/shape_impl.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepGProp.hxx>
#include <Bnd_Box.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <TopAbs_ShapeEnum.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>

namespace gk::occt {

Shape::Shape() = default;
Shape::Shape(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

bool Shape::is_null() const { return !impl_ || impl_->shape.IsNull(); }

namespace {
int count(const TopoDS_Shape& s, TopAbs_ShapeEnum kind) {
  int n = 0;
  for (TopExp_Explorer e(s, kind); e.More(); e.Next()) ++n;
  return n;
}
}  // namespace

int Shape::face_count() const { return is_null() ? 0 : count(impl_->shape, TopAbs_FACE); }
int Shape::solid_count() const { return is_null() ? 0 : count(impl_->shape, TopAbs_SOLID); }

Aabb Shape::bounds() const {
  Aabb out;
  if (is_null()) return out;
  Bnd_Box box;
  BRepBndLib::Add(impl_->shape, box, false);
  if (box.IsVoid()) return out;
  double x0, y0, z0, x1, y1, z1;
  box.Get(x0, y0, z0, x1, y1, z1);
  return {Vec3(x0, y0, z0), Vec3(x1, y1, z1)};
}

double Shape::volume() const {
  if (is_null() || solid_count() == 0) return 0.0;
  GProp_GProps props;
  BRepGProp::VolumeProperties(impl_->shape, props);
  return props.Mass();
}

bool Shape::is_polyhedral() const {
  if (is_null()) return false;
  try {
    for (TopExp_Explorer e(impl_->shape, TopAbs_FACE); e.More(); e.Next())
      if (BRepAdaptor_Surface(TopoDS::Face(e.Current())).GetType() != GeomAbs_Plane) return false;
    for (TopExp_Explorer e(impl_->shape, TopAbs_EDGE); e.More(); e.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(e.Current());
      if (BRep_Tool::Degenerated(edge)) continue;
      if (BRepAdaptor_Curve(edge).GetType() != GeomAbs_Line) return false;
    }
  } catch (const Standard_Failure&) {
    return false;  // not provably polyhedral: its tessellation keeps its deflection
  }
  return true;
}

}  // namespace gk::occt
