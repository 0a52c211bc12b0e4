#include "occt_adapters/exact_measures.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_impl.h"

#include <BRepAlgoAPI_Common.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

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

Result<ShapeDistance> face_distance(const Shape& a, int face_a, const RigidTransform& pose_a, const Shape& b, int face_b,
                                    const RigidTransform& pose_b) {
  if (a.is_null()) return invalid_argument("a", "is empty");
  if (b.is_null()) return invalid_argument("b", "is empty");
  TopoDS_Shape fa, fb;
  auto pick = guarded("faces", "selecting faces", [&] {
    TopTools_IndexedMapOfShape map_a, map_b;
    TopExp::MapShapes(a.impl().shape, TopAbs_FACE, map_a);
    TopExp::MapShapes(b.impl().shape, TopAbs_FACE, map_b);
    if (face_a >= 1 && face_a <= map_a.Extent()) fa = map_a(face_a);
    if (face_b >= 1 && face_b <= map_b.Extent()) fb = map_b(face_b);
  });
  if (!pick.ok()) return pick.error();
  if (fa.IsNull()) return invalid_argument("face_a", "no face " + std::to_string(face_a));
  if (fb.IsNull()) return invalid_argument("face_b", "no face " + std::to_string(face_b));
  auto placed_a = place(wrap(fa), pose_a);
  if (!placed_a.ok()) return placed_a.error();
  auto placed_b = place(wrap(fb), pose_b);
  if (!placed_b.ok()) return placed_b.error();
  return exact_distance(placed_a.value(), placed_b.value());
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
