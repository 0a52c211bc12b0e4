#include "kernel/measure/exact_interference_volume.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <exception>
#include <string>
#include <vector>

namespace gk {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

constexpr const char* kNoVolume =
    "the mesh does not bound a volume: its shells intersect themselves or each other, or are nested with the wrong "
    "orientation";
using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using ExactFT = Kernel::Exact_kernel::FT;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// The mesh's own coordinates (doubles, exact predicates), wound outward as a whole.
using FilteredKernel = CGAL::Exact_predicates_inexact_constructions_kernel;

// CGAL's corefinement cannot be cancelled; its visitor is called at every step of its phases, and
// an exception thrown there unwinds out of it (the meshes are this call's own copies).
struct CorefinementStopped {};
struct StoppingVisitor : PMP::Corefinement::Default_visitor<Mesh> {
  const StopToken* stop = nullptr;
  mutable unsigned long long steps = 0;
  explicit StoppingVisitor(const StopToken* s) : stop(s) {}
  void ask() const {
    if ((steps++ & 255) == 0 && stop->stop_requested()) throw CorefinementStopped{};
  }
  void progress_filtering_intersections(double) const { ask(); }
  void triangulating_faces_step() const { ask(); }
  void intersection_of_coplanar_faces_step() const { ask(); }
  void edge_face_intersections_step() const { ask(); }
  void build_output_step() const { ask(); }
};
using LocalMesh = CGAL::Surface_mesh<FilteredKernel::Point_3>;

Result<LocalMesh> local_mesh(const TriangleMesh& m, const char* side) {
  const bool inward = m.signed_volume() < 0.0;
  LocalMesh out;
  std::vector<LocalMesh::Vertex_index> index;
  index.reserve(m.vertices().size());
  for (const Vec3& v : m.vertices()) index.push_back(out.add_vertex(FilteredKernel::Point_3(v.x(), v.y(), v.z())));
  for (const auto& f : m.faces())
    if (out.add_face(index[f[0]], index[f[inward ? 2 : 1]], index[f[inward ? 1 : 2]]) == LocalMesh::null_face())
      return Error{ErrorCode::kFailedPrecondition, side, "a non-manifold vertex or edge: the mesh has no well-defined inside"};
  return out;
}

// The posed mesh with every coordinate R v + t carried exactly, its faces wound outward.
Result<Mesh> exact_posed(const TriangleMesh& m, const RigidTransform& pose, const char* side) {
  const bool inward = m.signed_volume() < 0.0;
  Mesh out;
  std::vector<Mesh::Vertex_index> index;
  index.reserve(m.vertices().size());
  const Mat3& r = pose.rotation;
  const Vec3& t = pose.translation;
  for (const Vec3& v : m.vertices()) {
    Kernel::FT c[3];
    for (int i = 0; i < 3; ++i)
      c[i] = Kernel::FT(r(i, 0)) * v.x() + Kernel::FT(r(i, 1)) * v.y() + Kernel::FT(r(i, 2)) * v.z() + Kernel::FT(t(i));
    index.push_back(out.add_vertex(Point(c[0], c[1], c[2])));
  }
  for (const auto& f : m.faces())
    if (out.add_face(index[f[0]], index[f[inward ? 2 : 1]], index[f[inward ? 1 : 2]]) == Mesh::null_face())
      return Error{ErrorCode::kFailedPrecondition, side, "a non-manifold vertex or edge: the mesh has no well-defined inside"};
  if (!CGAL::is_closed(out)) return Error{ErrorCode::kFailedPrecondition, side, "the mesh is not closed"};
  return out;
}

struct FaceCorners {
  Point p[3];
};

FaceCorners corners(const Mesh& m, Mesh::Face_index f) {
  FaceCorners out;
  int k = 0;
  for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) out.p[k++] = m.point(v);
  return out;
}

// p0 . (p1 x p2) / 6: the signed volume of the tetrahedron from the origin to the face.
ExactFT signed_tetra(const FaceCorners& c) {
  const auto e0 = CGAL::exact(c.p[0]), e1 = CGAL::exact(c.p[1]), e2 = CGAL::exact(c.p[2]);
  const ExactFT det = e0.x() * (e1.y() * e2.z() - e1.z() * e2.y()) - e0.y() * (e1.x() * e2.z() - e1.z() * e2.x()) +
                      e0.z() * (e1.x() * e2.y() - e1.y() * e2.x());
  return det / 6;
}

// Adds the faces of `from` that bound the intersection: those inside `other`, and (when
// `count_shared`) those lying on `other`'s surface with the same outward side — both solids on the
// same side of a shared face, which therefore bounds their intersection once. Faces on `other`'s
// surface facing the opposite way are a touch: nothing of the intersection lies there.
//
// After corefinement the intersection edges (`constrained`) cut `from` into patches, each wholly
// inside, outside or on `other`: one face classifies its patch, except on `other`'s surface, where
// each face is compared with the face it lies on.
void add_boundary_of_intersection(Mesh& from, const Mesh::Property_map<Mesh::Edge_index, bool>& constrained,
                                  const Mesh& other, bool count_shared, ExactFT& sum) {
  Tree tree(faces(other).first, faces(other).second, other);
  CGAL::Side_of_triangle_mesh<Mesh, Kernel> side_of_other(tree);
  const CGAL::Bbox_3 other_box = tree.bbox();
  auto patch_of = from.add_property_map<Mesh::Face_index, std::size_t>("f:patch", 0).first;
  const std::size_t patches = PMP::connected_components(from, patch_of, CGAL::parameters::edge_is_constrained_map(constrained));
  std::vector<std::vector<Mesh::Face_index>> members(patches);
  for (Mesh::Face_index f : from.faces()) members[patch_of[f]].push_back(f);
  auto side_of = [&](const FaceCorners& c) { return side_of_other(CGAL::centroid(c.p[0], c.p[1], c.p[2])); };
  for (const std::vector<Mesh::Face_index>& patch : members) {
    CGAL::Bbox_3 patch_box;
    for (Mesh::Face_index f : patch) {
      const FaceCorners c = corners(from, f);
      patch_box += c.p[0].bbox() + c.p[1].bbox() + c.p[2].bbox();
    }
    if (!CGAL::do_overlap(patch_box, other_box)) continue;
    const CGAL::Bounded_side where = side_of(corners(from, patch.front()));
    if (where == CGAL::ON_UNBOUNDED_SIDE) continue;
    if (where == CGAL::ON_BOUNDED_SIDE) {
      for (Mesh::Face_index f : patch) sum += signed_tetra(corners(from, f));
      continue;
    }
    if (!count_shared) continue;
    for (Mesh::Face_index f : patch) {
      const FaceCorners c = corners(from, f);
      const Point centroid = CGAL::centroid(c.p[0], c.p[1], c.p[2]);
      if (side_of_other(centroid) != CGAL::ON_BOUNDARY) {
        if (side_of_other(centroid) == CGAL::ON_BOUNDED_SIDE) sum += signed_tetra(c);
        continue;
      }
      const auto nearest = tree.closest_point_and_primitive(centroid);
      const FaceCorners o = corners(other, nearest.second);
      const Kernel::Vector_3 n_from = CGAL::normal(c.p[0], c.p[1], c.p[2]);
      const Kernel::Vector_3 n_other = CGAL::normal(o.p[0], o.p[1], o.p[2]);
      if (CGAL::is_positive(n_from * n_other)) sum += signed_tetra(c);
    }
  }
}

}  // namespace

Result<bool> bounds_a_volume(const TriangleMesh& mesh, const char* side) {
  if (!mesh.is_closed_oriented()) return Error{ErrorCode::kFailedPrecondition, side, "the mesh is not closed and consistently oriented"};
  try {
    auto local = local_mesh(mesh, side);
    if (!local.ok()) return local.error();
    if (!CGAL::is_closed(local.value())) return Error{ErrorCode::kFailedPrecondition, side, "the mesh is not closed"};
    // Closed, free of self-intersections (between its shells too), and its shells nested with
    // alternating orientation (a cavity wound inward): only then is "inside" what its triangles say.
    if (PMP::does_self_intersect(local.value())) return false;
    return PMP::does_bound_a_volume(local.value());
  } catch (const std::exception& e) {
    return Error{ErrorCode::kInternal, side, std::string("checking the mesh bounds a volume: ") + e.what()};
  }
}

Result<ExactVolume> exact_interference_volume(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                              const RigidTransform& pose_b, const StopToken& stop) {
  for (const auto& [mesh, side] : {std::pair<const TriangleMesh*, const char*>{&a, "a"}, {&b, "b"}}) {
    auto valid = bounds_a_volume(*mesh, side);
    if (!valid.ok()) return valid.error();
    if (!valid.value()) return Error{ErrorCode::kFailedPrecondition, side, kNoVolume};
  }
  if (!pose_a.is_finite()) return invalid_argument("pose_a", "not finite");
  if (!pose_b.is_finite()) return invalid_argument("pose_b", "not finite");
  try {
    auto ma = exact_posed(a, pose_a, "a");
    if (!ma.ok()) return ma.error();
    auto mb = exact_posed(b, pose_b, "b");
    if (!mb.ok()) return mb.error();
    Mesh& ea = ma.value();
    Mesh& eb = mb.value();
    // Split both surfaces along their intersection curves: every face then lies inside, outside
    // or on the other surface as a whole.
    auto constrained_a = ea.add_property_map<Mesh::Edge_index, bool>("e:constrained", false).first;
    auto constrained_b = eb.add_property_map<Mesh::Edge_index, bool>("e:constrained", false).first;
    PMP::corefine(ea, eb,
                  CGAL::parameters::throw_on_self_intersection(true).edge_is_constrained_map(constrained_a).visitor(
                      StoppingVisitor{&stop}),
                  CGAL::parameters::edge_is_constrained_map(constrained_b));
    ExactFT sum = 0;
    add_boundary_of_intersection(ea, constrained_a, eb, true, sum);
    add_boundary_of_intersection(eb, constrained_b, ea, false, sum);
    ExactVolume out;
    const std::pair<double, double> interval = CGAL::to_interval(sum);
    out.volume_mm3 = CGAL::to_double(sum);
    out.error_bound_mm3 = std::max(interval.second - out.volume_mm3, out.volume_mm3 - interval.first);
    return out;
  } catch (const PMP::Corefinement::Self_intersection_exception&) {
    return Error{ErrorCode::kFailedPrecondition, "a, b", "a mesh intersects itself where the parts meet: no well-defined inside"};
  } catch (const CorefinementStopped&) {
    return stopped("the exact corefinement");
  } catch (const std::exception& e) {
    return Error{ErrorCode::kInternal, "a, b", std::string("exact corefinement failed: ") + e.what()};
  }
}

}  // namespace gk
