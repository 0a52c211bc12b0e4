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

#include <limits>

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

Result<ClosestFacePair> closest_face_pair(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                          const RigidTransform& pose_b, const std::vector<std::pair<int, int>>& face_pairs) {
  if (a.is_null()) return invalid_argument("a", "is empty");
  if (b.is_null()) return invalid_argument("b", "is empty");
  if (face_pairs.empty()) return invalid_argument("face_pairs", "is empty");
  auto placed_a = place(a, pose_a);
  if (!placed_a.ok()) return placed_a.error();
  auto placed_b = place(b, pose_b);
  if (!placed_b.ok()) return placed_b.error();
  TopTools_IndexedMapOfShape map_a, map_b;
  auto mapped = guarded("shapes", "mapping faces", [&] {
    TopExp::MapShapes(placed_a.value().impl().shape, TopAbs_FACE, map_a);
    TopExp::MapShapes(placed_b.value().impl().shape, TopAbs_FACE, map_b);
  });
  if (!mapped.ok()) return mapped.error();
  ClosestFacePair best;
  best.distance.distance_mm = std::numeric_limits<double>::infinity();
  for (const auto& [fa, fb] : face_pairs) {
    if (fa < 1 || fa > map_a.Extent()) return invalid_argument("face_pairs", "no face " + std::to_string(fa) + " in a");
    if (fb < 1 || fb > map_b.Extent()) return invalid_argument("face_pairs", "no face " + std::to_string(fb) + " in b");
    auto d = exact_distance(wrap(map_a(fa)), wrap(map_b(fb)));
    if (!d.ok()) return d.error();
    if (d.value().distance_mm < best.distance.distance_mm) best = {d.value(), fa, fb};
  }
  return best;
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
