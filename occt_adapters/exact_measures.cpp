#include "occt_adapters/exact_measures.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"

#include <BRepAlgoAPI_Common.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>

namespace gk::occt {

Result<ShapeDistance> exact_distance(const Shape& a, const Shape& b) {
  if (a.is_null()) return invalid_argument("a", "is empty");
  if (b.is_null()) return invalid_argument("b", "is empty");
  ShapeDistance out;
  bool done = false;
  auto ran = guarded("shapes", "exact distance", [&] {
    BRepExtrema_DistShapeShape dist(a.impl().shape, b.impl().shape);
    done = dist.IsDone() && dist.NbSolution() > 0;
    if (!done) return;
    out.distance_mm = dist.Value();
    out.inner = dist.InnerSolution();
    const gp_Pnt pa = dist.PointOnShape1(1), pb = dist.PointOnShape2(1);
    out.point_a = Vec3(pa.X(), pa.Y(), pa.Z());
    out.point_b = Vec3(pb.X(), pb.Y(), pb.Z());
  });
  if (!ran.ok()) return ran.error();
  if (!done) return Error{ErrorCode::kInternal, "shapes", "BRepExtrema_DistShapeShape found no solution"};
  return out;
}

Result<double> interference_volume(const Shape& a, const Shape& b) {
  if (a.is_null()) return invalid_argument("a", "is empty");
  if (b.is_null()) return invalid_argument("b", "is empty");
  double volume = 0.0;
  bool failed = false;
  auto ran = guarded("shapes", "Boolean common", [&] {
    BRepAlgoAPI_Common common(a.impl().shape, b.impl().shape);
    if (!common.IsDone() || common.HasErrors()) {
      failed = true;
      return;
    }
    GProp_GProps props;
    BRepGProp::VolumeProperties(common.Shape(), props);
    volume = props.Mass();
  });
  if (!ran.ok()) return ran.error();
  if (failed) return Error{ErrorCode::kInternal, "shapes", "BRepAlgoAPI_Common failed"};
  return volume < 0.0 ? 0.0 : volume;
}

}  // namespace gk::occt
