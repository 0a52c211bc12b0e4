#include "occt_adapters/brep_contact.h"

#include "kernel/core/tolerances.h"
#include "kernel/query/triangle_distance.h"

#include "occt_adapters/face_pair_descent.h"
#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_impl.h"
#include "occt_adapters/solid_volume.h"

#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepAlgoAPI_Section.hxx>
#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <Bnd_Box.hxx>
#include <gp_Pln.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepGProp.hxx>
#include <BRepGProp_Face.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <gp_Pnt2d.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <Poly_Triangulation.hxx>
#include <TopLoc_Location.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gk::occt {
namespace {

// The pose followed by the shift that brings frame_origin to the origin.
RigidTransform in_local_frame(const RigidTransform& pose, const Vec3& frame_origin) {
  RigidTransform local = pose;
  local.translation = pose.translation - frame_origin;
  return local;
}

Vec3 vec(const gp_Pnt& p) { return Vec3(p.X(), p.Y(), p.Z()); }

// Both shapes moved into the frame local to frame_origin.
Result<std::pair<Shape, Shape>> place_pair(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                           const RigidTransform& pose_b, const Vec3& frame_origin) {
  if (a.is_null()) return invalid_argument("a", "is empty");
  if (b.is_null()) return invalid_argument("b", "is empty");
  auto placed_a = place(a, in_local_frame(pose_a, frame_origin));
  if (!placed_a.ok()) return placed_a.error();
  auto placed_b = place(b, in_local_frame(pose_b, frame_origin));
  if (!placed_b.ok()) return placed_b.error();
  return std::make_pair(placed_a.value(), placed_b.value());
}

struct Measured {
  double distance = std::numeric_limits<double>::infinity();
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();  // local frame
  int face_a = 0, face_b = 0;
};

// BRepExtrema between two (sub)shapes; false when it found no solution.
bool measure(const TopoDS_Shape& a, const TopoDS_Shape& b, Measured& out) {
  BRepExtrema_DistShapeShape dist(a, b);
  if (!dist.IsDone() || dist.NbSolution() < 1) return false;
  out.distance = dist.Value();
  out.a = vec(dist.PointOnShape1(1));
  out.b = vec(dist.PointOnShape2(1));
  return true;
}

// Is the point strictly inside one of the shape's solids (beyond tolerance_mm from its boundary)?
bool inside_a_solid(const TopoDS_Shape& shape, const gp_Pnt& p, double tolerance_mm) {
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) {
    BRepClass3d_SolidClassifier classifier(e.Current());
    classifier.Perform(p, tolerance_mm);
    if (classifier.State() == TopAbs_IN) return true;
  }
  return false;
}

// A point on each solid's boundary (its first vertex), local frame.
std::vector<gp_Pnt> one_point_per_solid(const TopoDS_Shape& shape) {
  std::vector<gp_Pnt> out;
  for (TopExp_Explorer s(shape, TopAbs_SOLID); s.More(); s.Next()) {
    TopExp_Explorer v(s.Current(), TopAbs_VERTEX);
    if (v.More()) out.push_back(BRep_Tool::Pnt(TopoDS::Vertex(v.Current())));
  }
  return out;
}

// The solids of a shape (the shape itself when it holds none).
std::vector<TopoDS_Shape> solids_of(const TopoDS_Shape& shape) {
  std::vector<TopoDS_Shape> out;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) out.push_back(e.Current());
  if (out.empty()) out.push_back(shape);
  return out;
}

// The nearest point of a shape to a point (a vertex against the shape: point-surface extrema,
// reliable for a point this close to the surface).
bool nearest_point_on(const TopoDS_Shape& shape, const gp_Pnt& p, gp_Pnt& q) {
  BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(p).Vertex(), shape);
  if (!dist.IsDone() || dist.NbSolution() < 1) return false;
  q = dist.PointOnShape2(1);
  return true;
}

// Where the two boundaries cross, the section curve rings the region each solid pushes into the
// other; the deepest point of that region lies under the ring's middle. The middle of each ring
// (and of the whole section) is projected onto both surfaces, and a projection the classifier puts
// inside the other solid by more than half the contact tolerance proves the crossing — when the Boolean
// common comes back empty (it does, for a small ball a few micrometres into a torus).
bool surface_point_inside_where_crossing(const TopoDS_Shape& a, const TopoDS_Shape& b, gp_Pnt& found) {
  BRepAlgoAPI_Section section(a, b, false);
  section.ComputePCurveOn1(false);
  section.ComputePCurveOn2(false);
  section.Approximation(false);
  section.Build();
  if (!section.IsDone() || section.HasErrors()) return false;
  std::vector<gp_XYZ> middles;
  gp_XYZ all(0, 0, 0);
  int all_count = 0;
  for (TopExp_Explorer e(section.Shape(), TopAbs_EDGE); e.More(); e.Next()) {
    BRepAdaptor_Curve curve(TopoDS::Edge(e.Current()));
    gp_XYZ sum(0, 0, 0);
    constexpr int kSamples = 16;
    for (int k = 0; k < kSamples; ++k) {
      const double t = curve.FirstParameter() + (curve.LastParameter() - curve.FirstParameter()) * (k + 0.5) / kSamples;
      sum += curve.Value(t).XYZ();
    }
    middles.push_back(sum / kSamples);
    all += sum;
    all_count += kSamples;
  }
  if (all_count == 0) return false;  // the boundaries do not cross (tangent, or apart)
  middles.push_back(all / all_count);
  for (const gp_XYZ& m : middles) {
    for (int side = 0; side < 2; ++side) {
      const TopoDS_Shape& on = side == 0 ? a : b;
      const TopoDS_Shape& into = side == 0 ? b : a;
      gp_Pnt q;
      if (!nearest_point_on(on, gp_Pnt(m), q)) continue;
      // Half the tolerance: the overlap's depth is shared between the two caps, so one of them
      // reaches at least half of it into the other solid.
      if (inside_a_solid(into, q, 0.25 * tolerances::kContactMm)) {
        found = q;
        return true;
      }
    }
  }
  return false;
}

// The solids of `shape` whose boxes meet `near`, those of them that overlap each other fused
// into one: the solids of an assembly may interpenetrate (a bolt modelled through its plate), and a
// volume summed solid by solid would count their shared part twice.
bool solids_near(const TopoDS_Shape& shape, const Bnd_Box& near, std::vector<TopoDS_Shape>& out) {
  out.clear();
  std::vector<Bnd_Box> boxes;
  for (const TopoDS_Shape& s : solids_of(shape)) {
    Bnd_Box box;
    BRepBndLib::Add(s, box);
    if (box.IsOut(near)) continue;
    out.push_back(s);
    boxes.push_back(box);
  }
  bool boxes_meet = false;
  for (std::size_t i = 0; i < boxes.size() && !boxes_meet; ++i)
    for (std::size_t j = i + 1; j < boxes.size() && !boxes_meet; ++j) boxes_meet = !boxes[i].IsOut(boxes[j]);
  if (!boxes_meet) return true;
  TopTools_ListOfShape arguments, tools;
  arguments.Append(out.front());
  for (std::size_t i = 1; i < out.size(); ++i) tools.Append(out[i]);
  BRepAlgoAPI_Fuse fuse;
  fuse.SetArguments(arguments);
  fuse.SetTools(tools);
  fuse.Build();
  if (!fuse.IsDone() || fuse.HasErrors()) return false;
  out = solids_of(fuse.Shape());
  return true;
}

// The volume shared by the solids of a and of b, one Boolean per pair of solids whose boxes meet:
// OCCT's Booleans assume each argument is free of self-interference, which an assembly of
// overlapping solids is not (one common of the whole compounds called a shared 8000 mm^3 a touch),
// so each side's overlapping solids are fused first. False when a Boolean failed.
bool common_volume(const TopoDS_Shape& a, const TopoDS_Shape& b, SharedVolume& out, bool bound_error = false) {
  out = SharedVolume{};
  Bnd_Box whole_a, whole_b;
  BRepBndLib::Add(a, whole_a);
  BRepBndLib::Add(b, whole_b);
  std::vector<TopoDS_Shape> solids_a, solids_b;
  if (!solids_near(a, whole_b, solids_a) || !solids_near(b, whole_a, solids_b)) return false;
  for (const TopoDS_Shape& sa : solids_a) {
    Bnd_Box box_a;
    BRepBndLib::Add(sa, box_a);
    for (const TopoDS_Shape& sb : solids_b) {
      Bnd_Box box_b;
      BRepBndLib::Add(sb, box_b);
      if (box_a.IsOut(box_b)) continue;
      BRepAlgoAPI_Common common(sa, sb);
      if (!common.IsDone() || common.HasErrors()) return false;
      for (TopExp_Explorer e(common.Shape(), TopAbs_SOLID); e.More(); e.Next()) {
        const SolidVolume measured = bound_error ? solid_volume_with_bound(e.Current()) : solid_volume(e.Current());
        out.volume_mm3 += measured.volume_mm3;
        out.error_bound_mm3 += measured.error_bound_mm3;
        if (measured.area_mm2 > 0.0) out.thickness_mm = std::max(out.thickness_mm, 2.0 * measured.volume_mm3 / measured.area_mm2);
      }
      if (!out.crossing()) {
        gp_Pnt p;
        if (surface_point_inside_where_crossing(sa, sb, p)) {
          out.surface_point_inside = true;
          out.point_inside = vec(p);
        }
      }
    }
  }
  return true;
}

// World triangles as planar faces in the local frame. A sliver that makes no face is kept as its
// wire when `keep_slivers` (its edges still count for a distance); a zero-length edge drops it
// (its points are on the neighbours' edges).
TopoDS_Compound triangle_faces(const std::vector<Triangle>& triangles, const Vec3& frame_origin, bool keep_slivers) {
  TopoDS_Compound patch;
  BRep_Builder builder;
  builder.MakeCompound(patch);
  for (const Triangle& t : triangles) {
    BRepBuilderAPI_MakePolygon polygon;
    for (const Vec3& v : t) {
      const Vec3 p = v - frame_origin;
      polygon.Add(gp_Pnt(p.x(), p.y(), p.z()));
    }
    polygon.Close();
    if (!polygon.IsDone()) continue;
    BRepBuilderAPI_MakeFace face(polygon.Wire(), true);
    if (face.IsDone()) builder.Add(patch, face.Face());
    else if (keep_slivers) builder.Add(patch, polygon.Wire());
  }
  return patch;
}

// Points inside a face: the centroids of the triangles of its triangulation (at most
// kMaxPoints, largest first); none when the face cannot be triangulated.
std::vector<gp_Pnt> points_in_face(const TopoDS_Face& face) {
  constexpr std::size_t kMaxPoints = 64;
  BRepMesh_IncrementalMesh mesher(face, 1e-3, false, 0.5, false);
  TopLoc_Location location;
  const Handle(Poly_Triangulation) triangulation = BRep_Tool::Triangulation(face, location);
  std::vector<std::pair<double, gp_Pnt>> found;
  if (triangulation.IsNull()) return {};
  for (int i = 1; i <= triangulation->NbTriangles(); ++i) {
    int n1, n2, n3;
    triangulation->Triangle(i).Get(n1, n2, n3);
    const gp_Pnt p1 = triangulation->Node(n1).Transformed(location.Transformation());
    const gp_Pnt p2 = triangulation->Node(n2).Transformed(location.Transformation());
    const gp_Pnt p3 = triangulation->Node(n3).Transformed(location.Transformation());
    const double area = gp_Vec(p1, p2).Crossed(gp_Vec(p1, p3)).Magnitude();
    if (area > 0.0) found.emplace_back(area, gp_Pnt((p1.XYZ() + p2.XYZ() + p3.XYZ()) / 3.0));
  }
  std::sort(found.begin(), found.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<gp_Pnt> out;
  for (std::size_t i = 0; i < found.size() && i < kMaxPoints; ++i) out.push_back(found[i].second);
  return out;
}

// For each triangle (local frame after subtracting frame_origin), on either side of its plane: the
// point of the shape farthest beyond the plane, found as the shape's nearest point to a large
// parallel plane face far out on that side; if it lies beyond by more than tolerance_mm, its foot
// on the plane, clamped into the triangle, is classified. True with that point when it lies inside
// a solid of the shape beyond tolerance_mm: a point of the triangles inside, proven by the classifier.
bool foot_of_extreme_point_inside(const TopoDS_Shape& shape, const std::vector<Triangle>& triangles, const Vec3& frame_origin,
                                  double tolerance_mm, gp_Pnt& found) {
  constexpr std::size_t kMaxTriangles = 64;
  Bnd_Box box;
  BRepBndLib::Add(shape, box);
  const double reach = std::sqrt(box.SquareExtent()) + 1.0;
  for (std::size_t t = 0; t < triangles.size() && t < kMaxTriangles; ++t) {
    const Vec3 p0 = triangles[t][0] - frame_origin, p1 = triangles[t][1] - frame_origin, p2 = triangles[t][2] - frame_origin;
    Vec3 n = (p1 - p0).cross(p2 - p0);
    if (!(n.norm() > 0.0)) continue;
    n.normalize();
    for (double side : {1.0, -1.0}) {
      const Vec3 far_origin = p0 + side * (2.0 * reach) * n;
      const gp_Pln far_plane(gp_Pnt(far_origin.x(), far_origin.y(), far_origin.z()), gp_Dir(n.x(), n.y(), n.z()));
      BRepBuilderAPI_MakeFace far_face(far_plane, -4.0 * reach, 4.0 * reach, -4.0 * reach, 4.0 * reach);
      if (!far_face.IsDone()) continue;
      BRepExtrema_DistShapeShape dist(shape, far_face.Face());
      if (!dist.IsDone() || dist.NbSolution() < 1) continue;
      const Vec3 e = vec(dist.PointOnShape1(1));
      const double beyond = side * n.dot(e - p0);
      if (beyond <= tolerance_mm) continue;
      const Vec3 foot = closest_point_on_triangle(e - n.dot(e - p0) * n, Triangle{p0, p1, p2});
      BRepClass3d_SolidClassifier classifier;
      for (TopExp_Explorer s(shape, TopAbs_SOLID); s.More(); s.Next()) {
        classifier.Load(s.Current());
        classifier.Perform(gp_Pnt(foot.x(), foot.y(), foot.z()), tolerance_mm);
        if (classifier.State() == TopAbs_IN) {
          found = gp_Pnt(foot.x(), foot.y(), foot.z());
          return true;
        }
      }
    }
  }
  return false;
}

}  // namespace

bool SharedVolume::crossing() const {
  return surface_point_inside || volume_mm3 > tolerances::kBrepOverlapVolumeMm3 ||
         (volume_mm3 > 0.0 && thickness_mm > tolerances::kBrepCrossingThicknessMm);
}

Result<BrepContact> decide_brep_contact(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                        const RigidTransform& pose_b, const Vec3& frame_origin,
                                        const std::vector<std::pair<int, int>>& face_pairs, double touch_mm) {
  if (!frame_origin.allFinite()) return invalid_argument("frame_origin", "must be finite");
  auto placed = place_pair(a, pose_a, b, pose_b, frame_origin);
  if (!placed.ok()) return placed.error();
  const TopoDS_Shape& sa = placed.value().first.impl().shape;
  const TopoDS_Shape& sb = placed.value().second.impl().shape;

  BrepContact out;
  std::string failure;
  auto ran = guarded("shapes", "deciding the contact on the B-Rep", [&] {
    Measured best;
    if (face_pairs.empty()) {
      if (!measure(sa, sb, best)) return void(failure = "BRepExtrema_DistShapeShape found no solution");
    } else {
      TopTools_IndexedMapOfShape faces_a, faces_b;
      TopExp::MapShapes(sa, TopAbs_FACE, faces_a);
      TopExp::MapShapes(sb, TopAbs_FACE, faces_b);
      for (const auto& [fa, fb] : face_pairs) {
        if (fa < 1 || fa > faces_a.Extent() || fb < 1 || fb > faces_b.Extent())
          return void(failure = "face pair (" + std::to_string(fa) + ", " + std::to_string(fb) + ") is not in the shapes");
        Measured m;
        if (!measure(faces_a(fa), faces_b(fb), m)) return void(failure = "BRepExtrema found no solution for a face pair");
        if (m.distance < best.distance) best = {m.distance, m.a, m.b, fa, fb};
      }
    }
    out.point_a = best.a + frame_origin;
    out.point_b = best.b + frame_origin;
    out.face_a = best.face_a;
    out.face_b = best.face_b;
    if (best.distance > touch_mm) {
      // Boundaries apart: disjoint, unless one solid lies inside the other.
      for (const gp_Pnt& p : one_point_per_solid(sa))
        if (inside_a_solid(sb, p, touch_mm)) {
          out.nested = true;
          out.point_a = out.point_b = vec(p) + frame_origin;
        }
      for (const gp_Pnt& p : one_point_per_solid(sb))
        if (!out.nested && inside_a_solid(sa, p, touch_mm)) {
          out.nested = true;
          out.point_a = out.point_b = vec(p) + frame_origin;
        }
      out.relation = out.nested ? BrepRelation::kOverlapping : BrepRelation::kApart;
      out.distance_mm = out.nested ? 0.0 : best.distance;
      return;
    }
    // Boundaries meet: a shared volume means they cross.
    out.used_boolean = true;
    SharedVolume shared;
    if (!common_volume(sa, sb, shared)) return void(failure = "BRepAlgoAPI_Common failed");
    out.shared_volume_mm3 = shared.volume_mm3;
    out.relation = shared.crossing() ? BrepRelation::kOverlapping : BrepRelation::kTouching;
    if (shared.surface_point_inside) out.point_a = out.point_b = shared.point_inside + frame_origin;
    out.distance_mm = 0.0;
  });
  if (!ran.ok()) return ran.error();
  if (!failure.empty()) return Error{ErrorCode::kInternal, "shapes", failure};
  return out;
}

Result<SharedVolume> shared_volume(const Shape& a, const RigidTransform& pose_a, const Shape& b, const RigidTransform& pose_b,
                                   const Vec3& frame_origin, bool bound_error) {
  auto placed = place_pair(a, pose_a, b, pose_b, frame_origin);
  if (!placed.ok()) return placed.error();
  const TopoDS_Shape& placed_a = placed.value().first.impl().shape;
  const TopoDS_Shape& placed_b = placed.value().second.impl().shape;
  SharedVolume out;
  bool failed = false;
  auto ran = guarded("shapes", "Boolean common", [&] {
    failed = !common_volume(placed_a, placed_b, out, bound_error);
    if (out.surface_point_inside) out.point_inside += frame_origin;
  });
  if (!ran.ok()) return ran.error();
  if (failed) return Error{ErrorCode::kInternal, "shapes", "BRepAlgoAPI_Common failed"};
  return out;
}

Result<ProjectedPair> closest_by_projection(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                            const RigidTransform& pose_b, const Vec3& frame_origin, const Vec3& start_a,
                                            const Vec3& start_b, int iterations) {
  auto placed = place_pair(a, pose_a, b, pose_b, frame_origin);
  if (!placed.ok()) return placed.error();
  const TopoDS_Shape& placed_a = placed.value().first.impl().shape;
  const TopoDS_Shape& placed_b = placed.value().second.impl().shape;
  ProjectedPair out;
  std::string failure;
  auto ran = guarded("shapes", "projecting witnesses", [&] {
    const Vec3 la = start_a - frame_origin, lb = start_b - frame_origin;
    gp_Pnt qa, qb;
    if (!nearest_point_on(placed_a, gp_Pnt(la.x(), la.y(), la.z()), qa) ||
        !nearest_point_on(placed_b, gp_Pnt(lb.x(), lb.y(), lb.z()), qb))
      return void(failure = "a witness could not be projected");
    double best = qa.Distance(qb);
    out = {best, vec(qa) + frame_origin, vec(qb) + frame_origin};
    for (int i = 0; i < iterations; ++i) {
      gp_Pnt nb, na;
      if (!nearest_point_on(placed_b, qa, nb) || !nearest_point_on(placed_a, nb, na)) break;
      qa = na;
      qb = nb;
      const double d = qa.Distance(qb);
      if (d < best) out = {d, vec(qa) + frame_origin, vec(qb) + frame_origin};
      if (!(d < best - 1e-9)) break;
      best = d;
    }
    // Alternating projections crawl where the surfaces are nearly parallel (tangent spheres):
    // a descent on the two faces that hold the points, from their parameters.
    // The face holding a surface point; a point on an edge or vertex (a sphere's seam or pole,
    // where BRepExtrema often lands) is taken on the first face around it.
    auto face_at = [&](const TopoDS_Shape& shape, const gp_Pnt& p, PointOnFace& f) {
      BRepExtrema_DistShapeShape dist(BRepBuilderAPI_MakeVertex(p).Vertex(), shape);
      if (!dist.IsDone() || dist.NbSolution() < 1) return false;
      if (dist.SupportTypeShape2(1) == BRepExtrema_IsInFace) {
        f.face = TopoDS::Face(dist.SupportOnShape2(1));
        dist.ParOnFaceS2(1, f.u, f.v);
        return true;
      }
      const TopoDS_Shape support = dist.SupportOnShape2(1);
      TopTools_IndexedDataMapOfShapeListOfShape faces_around;
      TopExp::MapShapesAndAncestors(shape, support.ShapeType(), TopAbs_FACE, faces_around);
      const int index = faces_around.FindIndex(support);
      if (index < 1 || faces_around(index).IsEmpty()) return false;
      f.face = TopoDS::Face(faces_around(index).First());
      GeomAPI_ProjectPointOnSurf projection(dist.PointOnShape2(1), BRep_Tool::Surface(f.face));
      if (!projection.IsDone() || projection.NbPoints() < 1) return false;
      projection.LowerDistanceParameters(f.u, f.v);
      return true;
    };
    const gp_Pnt pa(out.point_a.x() - frame_origin.x(), out.point_a.y() - frame_origin.y(), out.point_a.z() - frame_origin.z());
    const gp_Pnt pb(out.point_b.x() - frame_origin.x(), out.point_b.y() - frame_origin.y(), out.point_b.z() - frame_origin.z());
    PointOnFace fa, fb;
    if (face_at(placed_a, pa, fa) && face_at(placed_b, pb, fb)) {
      const FacePairClosest closest = descend_to_closest(fa, fb);
      if (closest.found && closest.distance_mm < out.distance_mm)
        out = {closest.distance_mm, vec(closest.point_a) + frame_origin, vec(closest.point_b) + frame_origin};
    }
  });
  if (!ran.ok()) return ran.error();
  if (!failure.empty()) return Error{ErrorCode::kInternal, "shapes", failure};
  return out;
}

Result<int> first_point_inside(const Shape& shape, const RigidTransform& pose, const std::vector<Vec3>& points,
                               const Vec3& frame_origin, double tolerance_mm) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  auto placed = place(shape, in_local_frame(pose, frame_origin));
  if (!placed.ok()) return placed.error();
  int found = -1;
  auto ran = guarded("points", "classifying points against a solid", [&] {
    for (std::size_t i = 0; i < points.size() && found < 0; ++i) {
      const Vec3 p = points[i] - frame_origin;
      if (inside_a_solid(placed.value().impl().shape, gp_Pnt(p.x(), p.y(), p.z()), tolerance_mm)) found = static_cast<int>(i);
    }
  });
  if (!ran.ok()) return ran.error();
  return found;
}

Result<TriangleSetDistance> distance_to_triangles(const Shape& shape, const RigidTransform& pose,
                                                  const std::vector<Triangle>& triangles, const Vec3& frame_origin) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (triangles.empty()) return invalid_argument("triangles", "is empty");
  auto placed = place(shape, in_local_frame(pose, frame_origin));
  if (!placed.ok()) return placed.error();
  TriangleSetDistance out;
  std::string failure;
  auto ran = guarded("triangles", "measuring a shape against triangles", [&] {
    const TopoDS_Compound patch = triangle_faces(triangles, frame_origin, true);
    TopTools_IndexedMapOfShape faces;
    TopExp::MapShapes(placed.value().impl().shape, TopAbs_FACE, faces);
    BRepExtrema_DistShapeShape dist(placed.value().impl().shape, patch);
    if (!dist.IsDone() || dist.NbSolution() < 1) return void(failure = "BRepExtrema_DistShapeShape found no solution");
    out.distance_mm = dist.Value();
    out.point_shape = vec(dist.PointOnShape1(1)) + frame_origin;
    out.point_triangles = vec(dist.PointOnShape2(1)) + frame_origin;
    if (dist.SupportTypeShape1(1) == BRepExtrema_IsInFace) out.face = faces.FindIndex(dist.SupportOnShape1(1));
  });
  if (!ran.ok()) return ran.error();
  if (!failure.empty()) return Error{ErrorCode::kInternal, "triangles", failure};
  return out;
}

Result<TrianglesAgainstSolid> triangles_against_solid(const Shape& shape, const RigidTransform& pose,
                                                     const std::vector<Triangle>& triangles, const Vec3& frame_origin,
                                                     double tolerance_mm) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  if (triangles.empty()) return invalid_argument("triangles", "is empty");
  auto placed = place(shape, in_local_frame(pose, frame_origin));
  if (!placed.ok()) return placed.error();
  TrianglesAgainstSolid out;
  std::string failure;
  auto ran = guarded("triangles", "the Boolean common of a solid and triangles", [&] {
    const TopoDS_Compound patch = triangle_faces(triangles, frame_origin, false);
    bool undecided = false;
    for (const TopoDS_Shape& solid : solids_of(placed.value().impl().shape)) {
      BRepAlgoAPI_Common common(solid, patch);
      if (!common.IsDone() || common.HasErrors()) return void(failure = "BRepAlgoAPI_Common failed");
      // The common holds the triangles' parts inside the solid or on its boundary; points inside
      // its pieces are classified (a piece inside the solid by less than tolerance_mm is a touch).
      for (TopExp_Explorer e(common.Shape(), TopAbs_FACE); e.More(); e.Next()) {
        const std::vector<gp_Pnt> points = points_in_face(TopoDS::Face(e.Current()));
        if (points.empty()) undecided = true;
        for (const gp_Pnt& p : points) {
          BRepClass3d_SolidClassifier classifier(solid);
          classifier.Perform(p, tolerance_mm);
          if (classifier.State() == TopAbs_IN) {
            out.relation = TrianglesRelation::kEntering;
            out.point_inside = vec(p) + frame_origin;
            return;
          }
          if (classifier.State() != TopAbs_ON) undecided = true;
        }
      }
    }
    // The Boolean can lose a shallow cut where a face's seams meet (a plane through a torus's
    // seams): where the triangles and the solid's boundary cross, the middles of the section rings
    // projected onto the triangles are classified too.
    for (const TopoDS_Shape& solid : solids_of(placed.value().impl().shape)) {
      gp_Pnt p;
      if (surface_point_inside_where_crossing(solid, patch, p)) {
        out.relation = TrianglesRelation::kEntering;
        out.point_inside = vec(p) + frame_origin;
        return;
      }
    }
    // Both can lose a shallow cap of a torus cut by a plane (the review found 0.049 mm missed): the
    // solid's extreme point beyond each triangle's plane (the nearest point to a far parallel
    // plane), dropped onto the triangle, is classified as well.
    gp_Pnt cap_point;
    if (foot_of_extreme_point_inside(placed.value().impl().shape, triangles, frame_origin, tolerance_mm, cap_point)) {
      out.relation = TrianglesRelation::kEntering;
      out.point_inside = vec(cap_point) + frame_origin;
      return;
    }
    out.relation = undecided ? TrianglesRelation::kUndecided : TrianglesRelation::kNotEntering;
  });
  if (!ran.ok()) return ran.error();
  if (!failure.empty()) return Error{ErrorCode::kInternal, "triangles", failure};
  return out;
}

Result<std::vector<Vec3>> points_inside_solids(const Shape& shape, const RigidTransform& pose, const Vec3& frame_origin,
                                               double tolerance_mm) {
  if (shape.is_null()) return invalid_argument("shape", "is empty");
  auto placed = place(shape, in_local_frame(pose, frame_origin));
  if (!placed.ok()) return placed.error();
  std::vector<Vec3> out;
  auto ran = guarded("shape", "finding points inside its solids", [&] {
    for (TopExp_Explorer s(placed.value().impl().shape, TopAbs_SOLID); s.More(); s.Next()) {
      Bnd_Box box;
      BRepBndLib::Add(s.Current(), box);
      const double size = std::sqrt(box.SquareExtent());
      bool found = false;
      // Points of the faces (inside their trimmed domains) moved inward along the outward normal,
      // kept when the classifier puts them inside by more than the tolerance.
      for (TopExp_Explorer f(s.Current(), TopAbs_FACE); f.More() && !found; f.Next()) {
        const TopoDS_Face face = TopoDS::Face(f.Current());
        double u0, u1, v0, v1;
        BRepTools::UVBounds(face, u0, u1, v0, v1);
        BRepTopAdaptor_FClass2d domain(face, 1e-9);
        BRepGProp_Face surface(face);
        constexpr int kGrid = 5;
        for (int i = 0; i < kGrid && !found; ++i)
          for (int j = 0; j < kGrid && !found; ++j) {
            const double u = u0 + (u1 - u0) * (i + 0.5) / kGrid, v = v0 + (v1 - v0) * (j + 0.5) / kGrid;
            if (domain.Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
            gp_Pnt p;
            gp_Vec normal;
            surface.Normal(u, v, p, normal);
            if (normal.Magnitude() <= 0.0) continue;
            normal.Normalize();
            for (double step : {1e-2, 1e-3, 1e-4}) {
              const gp_Pnt q = p.Translated(-normal * (step * size));
              if (step * size <= 2.0 * tolerance_mm) break;
              BRepClass3d_SolidClassifier classifier(s.Current());
              classifier.Perform(q, tolerance_mm);
              if (classifier.State() == TopAbs_IN) {
                out.push_back(vec(q) + frame_origin);
                found = true;
                break;
              }
            }
          }
      }
    }
  });
  if (!ran.ok()) return ran.error();
  return out;
}

}  // namespace gk::occt
