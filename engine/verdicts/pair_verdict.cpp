#include "engine/verdicts/pair_verdict.h"

#include "engine/verdicts/number_text.h"

#include "kernel/query/mesh_distance.h"
#include "kernel/core/tolerances.h"
#include "occt_adapters/brep_contact.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace gk::engine {
namespace {

// Beyond this many face pairs within reach, the exact distance runs on the whole shapes
// (BRepExtrema prunes by boxes itself) instead of pair by pair.
constexpr std::size_t kMaxExactFacePairs = 400;
// Triangle pairs gathered within reach of the exact decision, at most. [pairs]
constexpr std::size_t kMaxWindowPairs = 200000;
// A CAD part against a mesh: mesh triangles measured against the exact faces, at most. [triangles]
constexpr std::size_t kMaxPatchTriangles = 4000;
// Surface points classified against the other solid to prove a collision, at most: from the
// crossing triangles... [points]
constexpr std::size_t kMaxCertificatePoints = 64;
// ...and from all triangles within reach. [points]
constexpr std::size_t kMaxWindowPoints = 256;

double elapsed_ms(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Rounding of the triangle distances: a few ulps of the largest coordinate involved.
double rounding_bound(const PosedPart& a, const PosedPart& b) {
  const Aabb wa = a.part->mesh->bounds(), wb = b.part->mesh->bounds();
  const double scale = std::max({wa.min.cwiseAbs().maxCoeff(), wa.max.cwiseAbs().maxCoeff(), wb.min.cwiseAbs().maxCoeff(),
                                 wb.max.cwiseAbs().maxCoeff(), a.pose.translation.cwiseAbs().maxCoeff(),
                                 b.pose.translation.cwiseAbs().maxCoeff(), 1.0});
  return 1e-12 * scale;
}

// Distinct vertices (world) of one side's triangles among the mesh contacts, plus the mesh's
// containment point: every one lies on that side's exact surface.
std::vector<Vec3> contact_vertices(const PosedPart& side, bool side_is_a, const VerdictResult& mesh) {
  std::vector<Vec3> out;
  std::set<std::uint32_t> seen;
  const TriangleMesh& m = *side.part->mesh;
  for (const Contact& c : mesh.contacts) {
    const std::uint32_t t = side_is_a ? c.triangle_a : c.triangle_b;
    for (int k = 0; k < 3 && out.size() < kMaxCertificatePoints; ++k) {
      const std::uint32_t v = m.faces()[t][static_cast<std::size_t>(k)];
      if (seen.insert(v).second) out.push_back(side.pose.apply(m.vertices()[v]));
    }
    if (out.size() >= kMaxCertificatePoints) break;
  }
  if (mesh.contained) out.push_back(mesh.containment_point);
  return out;
}

// One vertex of every connected body of a mesh, world coordinates.
std::vector<Vec3> body_points(const PosedPart& side) {
  std::vector<Vec3> out;
  for (std::uint32_t seed : side.part->mesh->body_seeds()) out.push_back(side.pose.apply(side.part->mesh->vertices()[seed]));
  return out;
}

void set_collision(PairVerdict& out, const Vec3& point, const std::string& reason) {
  out.result.verdict = Verdict::kCollision;
  out.result.inconclusive_reason = InconclusiveReason::kNone;
  out.result.reason = reason;
  out.result.distance_mm = 0.0;
  out.result.distance_is_lower_bound = false;
  out.result.point_a = out.result.point_b = point;
  out.decided_on_brep = true;
}

void set_clear(PairVerdict& out, double distance_mm, const Vec3& point_a, const Vec3& point_b, const std::string& reason) {
  VerdictResult& r = out.result;
  r.verdict = Verdict::kClear;
  r.inconclusive_reason = InconclusiveReason::kNone;
  r.reason = reason;
  r.distance_mm = distance_mm;
  r.distance_is_lower_bound = false;
  r.point_a = point_a;
  r.point_b = point_b;
  r.contacts.clear();
  r.crossing_pairs = 0;
  r.first_crossing = -1;
  r.contained = false;
  out.decided_on_brep = true;
}

void set_touching(PairVerdict& out, const Vec3& point_a, const Vec3& point_b, const std::string& reason) {
  VerdictResult& r = out.result;
  r.verdict = Verdict::kTouching;
  r.inconclusive_reason = InconclusiveReason::kNone;
  r.reason = reason;
  r.distance_mm = 0.0;
  r.distance_is_lower_bound = false;
  r.point_a = point_a;
  r.point_b = point_b;
  r.crossing_pairs = 0;
  r.first_crossing = -1;
  r.contained = false;
  out.decided_on_brep = true;
}

void set_inconclusive(PairVerdict& out, InconclusiveReason why, const std::string& reason) {
  out.result.verdict = Verdict::kInconclusive;
  out.result.inconclusive_reason = why;
  out.result.reason = reason;
}

// The B-Rep faces of the triangle pairs within `window` of each other; `complete` false when
// there were too many to measure pair by pair.
struct FacePairs {
  std::vector<std::pair<int, int>> pairs;
  bool complete = true;
};
Result<FacePairs> face_pairs_within(const PosedPart& a, const PosedPart& b, double window) {
  auto near = pairs_within(*a.part->bvh, a.pose, *b.part->bvh, b.pose, window, kMaxWindowPairs);
  if (!near.ok()) return near.error();
  FacePairs out;
  if (near.value().truncated) {
    out.complete = false;
    return out;
  }
  std::set<std::pair<int, int>> faces;
  for (const ProximityPair& p : near.value().pairs) {
    faces.insert({a.part->face_of_triangle[p.triangle_a], b.part->face_of_triangle[p.triangle_b]});
    if (faces.size() > kMaxExactFacePairs) {
      out.complete = false;
      return out;
    }
  }
  out.pairs.assign(faces.begin(), faces.end());
  return out;
}

// Distinct vertices (world) of one side's triangles among the given pairs: points of its exact
// surface (tessellation vertices lie on the faces).
std::vector<Vec3> window_vertices(const PosedPart& side, bool side_is_a, const std::vector<ProximityPair>& pairs,
                                  std::vector<Vec3> out) {
  std::set<std::uint32_t> seen;
  const TriangleMesh& m = *side.part->mesh;
  for (const ProximityPair& p : pairs) {
    const std::uint32_t t = side_is_a ? p.triangle_a : p.triangle_b;
    for (int k = 0; k < 3 && out.size() < kMaxWindowPoints; ++k) {
      const std::uint32_t v = m.faces()[t][static_cast<std::size_t>(k)];
      if (seen.insert(v).second) out.push_back(side.pose.apply(m.vertices()[v]));
    }
    if (out.size() >= kMaxWindowPoints) break;
  }
  return out;
}

// Two CAD parts. `mesh_says_apart`: the triangles are farther apart than the window, so only the
// distance is refined (and only when the face pairs are few, unless `must_measure`).
void decide_cad_pair(const PosedPart& a, const PosedPart& b, double window, double rounding, bool mesh_says_apart,
                     bool must_measure, PairVerdict& out) {
  const VerdictResult mesh = out.result;
  const Vec3 origin = 0.5 * (mesh.point_a + mesh.point_b);
  auto near = pairs_within(*a.part->bvh, a.pose, *b.part->bvh, b.pose, std::max(mesh.distance_mm, 0.0) + 2.0 * window,
                           kMaxWindowPairs);
  if (!mesh_says_apart && near.ok()) {
    // A point of one part's exact surface (a tessellation vertex of a crossing or of a triangle
    // within reach) strictly inside the other solid proves the collision.
    for (int side = 0; side < 2; ++side) {
      const PosedPart& from = side == 0 ? a : b;
      const PosedPart& into = side == 0 ? b : a;
      const std::vector<Vec3> points = window_vertices(from, side == 0, near.value().pairs, contact_vertices(from, side == 0, mesh));
      if (points.empty()) continue;
      auto inside = occt::first_point_inside(into.part->shape, into.pose, points, origin, tolerances::kContactMm);
      if (inside.ok() && inside.value() >= 0) {
        set_collision(out, points[static_cast<std::size_t>(inside.value())],
                      "a point of " + std::string(side == 0 ? "a" : "b") + "'s exact surface lies inside " +
                          std::string(side == 0 ? "b" : "a") + "'s solid");
        out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
        return;
      }
    }
  }
  auto faces = face_pairs_within(a, b, std::max(mesh.distance_mm, 0.0) + 2.0 * window);
  if (!faces.ok()) {
    if (mesh_says_apart) return;  // the mesh answer and its bound stand
    return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + faces.error().to_string());
  }
  if (mesh_says_apart && !faces.value().complete && !must_measure) return;
  const std::vector<std::pair<int, int>> pairs = faces.value().complete ? faces.value().pairs : std::vector<std::pair<int, int>>{};
  auto exact = occt::decide_brep_contact(a.part->shape, a.pose, b.part->shape, b.pose, origin, pairs, tolerances::kContactMm);
  if (!exact.ok()) {
    if (mesh_says_apart) return;
    return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + exact.error().to_string());
  }
  const occt::BrepContact& c = exact.value();
  out.face_a = c.face_a;
  out.face_b = c.face_b;
  out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
  switch (c.relation) {
    case occt::BrepRelation::kApart: {
      // BRepExtrema's face-pair extrema can stop in a local minimum: a second search from the
      // mesh witnesses, and the tessellation's own interval, must agree.
      double d = c.distance_mm;
      Vec3 pa = c.point_a, pb = c.point_b;
      double disagreement = 0.0;
      auto second = occt::closest_by_projection(a.part->shape, a.pose, b.part->shape, b.pose, origin, mesh.point_a, mesh.point_b, 6);
      if (second.ok()) {
        disagreement = std::fabs(second.value().distance_mm - d);
        if (second.value().distance_mm < d - tolerances::kBrepDistanceErrorMm) {  // else keep BRepExtrema's faces
          d = second.value().distance_mm;
          pa = second.value().point_a;
          pb = second.value().point_b;
          out.face_a = out.face_b = 0;
        }
      }
      if (disagreement > tolerances::kBrepDistanceErrorMm) {
        // BRepExtrema stopped in a local minimum the second search went below (it does, at
        // factory coordinates): descend from BRepExtrema's own witnesses too. Both starts reaching
        // the same minimum settle it; otherwise the difference stays in the bound.
        auto again = occt::closest_by_projection(a.part->shape, a.pose, b.part->shape, b.pose, origin, c.point_a, c.point_b, 0);
        if (again.ok()) {
          if (again.value().distance_mm < d - tolerances::kBrepDistanceErrorMm) {
            d = again.value().distance_mm;
            pa = again.value().point_a;
            pb = again.value().point_b;
          }
          disagreement = std::min(disagreement, std::fabs(again.value().distance_mm - second.value().distance_mm));
        }
      }
      if (!mesh.distance_is_lower_bound && d > std::max(mesh.distance_mm, 0.0) + window + rounding + tolerances::kBrepDistanceErrorMm) {
        if (mesh_says_apart) {  // keep the mesh answer and its bound
          out.face_a = out.face_b = 0;
          out.error_bound_mm = window + rounding;
          return;
        }
        return set_inconclusive(out, InconclusiveReason::kBrepUndecided,
                                "the exact distance (" + number_text(d) + " mm) lies outside the tessellation's interval");
      }
      if (d <= tolerances::kContactMm) {
        // Real surface points within the contact tolerance (the second search reached the
        // tangency BRepExtrema stopped short of): touching, unless the solids share volume.
        auto shared = occt::shared_volume(a.part->shape, a.pose, b.part->shape, b.pose, origin);
        if (!shared.ok())
          return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + shared.error().to_string());
        if (shared.value().crossing())
          return set_collision(out, pa, "exact solids share " + number_text(shared.value().volume_mm3) + " mm^3 (Boolean common)");
        return set_touching(out, pa, pb, "exact faces within the contact tolerance, no shared volume (Boolean common)");
      }
      if (disagreement > tolerances::kBrepDistanceErrorMm) out.error_bound_mm += disagreement;
      if (!mesh_says_apart && d <= window) {
        // Closer than the tessellation can tell: no shared volume must confirm that they are apart.
        auto shared = occt::shared_volume(a.part->shape, a.pose, b.part->shape, b.pose, origin);
        if (!shared.ok())
          return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + shared.error().to_string());
        if (shared.value().crossing())
          return set_collision(out, pa, "exact solids share " + number_text(shared.value().volume_mm3) + " mm^3 (Boolean common)");
      }
      return set_clear(out, d, pa, pb, "exact faces apart");
    }
    case occt::BrepRelation::kTouching:
      return set_touching(out, c.point_a, c.point_b, "exact faces touch without a shared volume");
    case occt::BrepRelation::kOverlapping:
      if (c.nested) {
        set_collision(out, c.point_a, "one solid lies inside the other (exact faces)");
        out.result.contained = true;
        out.result.containment_point = c.point_a;
      } else {
        set_collision(out, c.point_a, "exact solids share " + number_text(c.shared_volume_mm3) + " mm^3 (Boolean common)");
      }
      return;
  }
}

// A CAD part against a mesh (its triangles exact): the exact faces against the mesh's triangles
// within reach. `cad_is_a` says which side the CAD part is on.
void decide_cad_mesh(const PosedPart& a, const PosedPart& b, bool cad_is_a, double window, double rounding,
                     bool mesh_says_apart, PairVerdict& out) {
  const PosedPart& cad = cad_is_a ? a : b;
  const PosedPart& mesh_side = cad_is_a ? b : a;
  const VerdictResult mesh = out.result;
  const Vec3 origin = 0.5 * (mesh.point_a + mesh.point_b);
  auto near = pairs_within(*a.part->bvh, a.pose, *b.part->bvh, b.pose, std::max(mesh.distance_mm, 0.0) + 2.0 * window,
                           kMaxWindowPairs);
  std::set<std::uint32_t> patch_ids;
  if (near.ok() && !near.value().truncated)
    for (const ProximityPair& p : near.value().pairs) patch_ids.insert(cad_is_a ? p.triangle_b : p.triangle_a);
  const bool patch_known = near.ok() && !near.value().truncated && patch_ids.size() <= kMaxPatchTriangles;
  if (!patch_known) {
    if (mesh_says_apart) return;
    return set_inconclusive(out, InconclusiveReason::kTessellationUnresolved,
                            "a CAD part within its tessellation's deflection of a mesh, over more than " +
                                std::to_string(kMaxPatchTriangles) + " of the mesh's triangles");
  }
  const TriangleMesh& m = *mesh_side.part->mesh;
  std::vector<Triangle> patch;
  std::vector<Vec3> patch_vertices;
  std::set<std::uint32_t> seen;
  for (std::uint32_t t : patch_ids) {
    Triangle tri = m.triangle(t);
    for (std::size_t k = 0; k < 3; ++k) {
      tri[k] = mesh_side.pose.apply(tri[k]);
      if (seen.insert(m.faces()[t][k]).second && patch_vertices.size() < kMaxCertificatePoints)
        patch_vertices.push_back(tri[k]);
    }
    patch.push_back(tri);
  }
  // Points of the CAD part's exact surface (tessellation vertices): one inside the closed mesh puts
  // the CAD part inside it.
  auto cad_point_inside_mesh = [&](const std::vector<Vec3>& points, const char* reason) {
    if (!m.is_closed_oriented()) return false;
    const RigidTransform to_mesh = mesh_side.pose.inverse();
    for (const Vec3& p : points) {
      if (!inside_closed_mesh(*mesh_side.part->bvh, to_mesh.apply(p))) continue;
      set_collision(out, p, reason);
      out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
      out.result.contained = true;
      out.result.containment_point = p;
      return true;
    }
    return false;
  };
  auto set_mesh_point_inside = [&](const Vec3& p) {
    set_collision(out, p, "a point of the mesh lies inside the CAD part's solid (exact faces)");
    out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
  };
  if (!mesh_says_apart && !patch_vertices.empty()) {
    auto inside = occt::first_point_inside(cad.part->shape, cad.pose, patch_vertices, origin, tolerances::kContactMm);
    if (inside.ok() && inside.value() >= 0) return set_mesh_point_inside(patch_vertices[static_cast<std::size_t>(inside.value())]);
  }
  // No mesh triangle within reach (the mesh wholly inside the solid, or far apart): only nesting
  // is left to decide.
  occt::TriangleSetDistance d;
  d.distance_mm = std::numeric_limits<double>::infinity();
  if (!patch.empty()) {
    auto exact = occt::distance_to_triangles(cad.part->shape, cad.pose, patch, origin);
    if (!exact.ok()) {
      if (mesh_says_apart) return;
      return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + exact.error().to_string());
    }
    d = exact.value();
  }
  if (d.distance_mm <= tolerances::kContactMm) {
    if (mesh_says_apart) return;
    // The exact faces meet the triangles with no mesh vertex inside the solid: do the triangles
    // enter it between their vertices (a face cutting a cap off a sphere)?
    auto entering = occt::triangles_against_solid(cad.part->shape, cad.pose, patch, origin, tolerances::kContactMm);
    if (!entering.ok()) return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + entering.error().to_string());
    if (entering.value().relation == occt::TrianglesRelation::kEntering) {
      set_collision(out, entering.value().point_inside, "the mesh's triangles enter the CAD part's solid (a point of them classified inside the exact solid)");
      out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
      return;
    }
    if (entering.value().relation == occt::TrianglesRelation::kUndecided)
      return set_inconclusive(out, InconclusiveReason::kBrepUndecided,
                              "the CAD part's exact faces meet the mesh's triangles, and the Boolean common of the solid "
                              "and the triangles could not be classified");
    // Touching from outside, unless the CAD part lies inside a closed mesh touching it from within.
    // The mesh's surface does not enter the solid, so each solid's interior is wholly inside the
    // mesh or wholly outside: one interior point of each tells (its surface points may all lie on
    // the mesh's walls, a cylinder whose caps are flush with a box's faces).
    if (m.is_closed_oriented()) {
      auto interior = occt::points_inside_solids(cad.part->shape, cad.pose, origin, tolerances::kContactMm);
      if (!interior.ok())
        return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + interior.error().to_string());
      if (cad_point_inside_mesh(interior.value(), "the CAD part lies inside the closed mesh, touching it from within")) return;
      if (interior.value().empty())
        return set_inconclusive(out, InconclusiveReason::kBrepUndecided,
                                "no point inside the CAD part's solid was found to tell it inside or outside the closed mesh");
    }
    out.face_a = cad_is_a ? d.face : 0;
    out.face_b = cad_is_a ? 0 : d.face;
    out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
    return set_touching(out, cad_is_a ? d.point_shape : d.point_triangles, cad_is_a ? d.point_triangles : d.point_shape,
                        "the mesh's triangles meet the CAD part's exact faces without entering its solid (Boolean common)");
  }
  // Boundaries apart: nested, or disjoint.
  const std::vector<Vec3> bodies = body_points(mesh_side);
  auto inside = occt::first_point_inside(cad.part->shape, cad.pose, bodies, origin, tolerances::kContactMm);
  if (!inside.ok()) {
    if (mesh_says_apart) return;
    return set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + inside.error().to_string());
  }
  if (inside.value() >= 0) return set_mesh_point_inside(bodies[static_cast<std::size_t>(inside.value())]);
  if (cad_point_inside_mesh(body_points(cad), "the CAD part lies inside the closed mesh")) return;
  if (!std::isfinite(d.distance_mm)) {  // apart beyond reach: the mesh answer stands
    if (mesh_says_apart || mesh.verdict == Verdict::kClear) return;
    return set_inconclusive(out, InconclusiveReason::kTessellationUnresolved,
                            "the mesh collides with the CAD part's tessellation but not with its exact faces, and no point "
                            "of either lies inside the other");
  }
  out.face_a = cad_is_a ? d.face : 0;
  out.face_b = cad_is_a ? 0 : d.face;
  out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
  set_clear(out, d.distance_mm, cad_is_a ? d.point_shape : d.point_triangles, cad_is_a ? d.point_triangles : d.point_shape,
            "exact faces apart from the mesh");
}

// The kernel tests containment only in closed meshes. A CAD part is a closed solid even where its
// tessellation is not (solids of an assembly sharing edges): whether a body of the other part lies
// inside it is asked of the solid, for the bodies whose point lies within its box.
Result<bool> contained_in_open_tessellation(const PosedPart& a, const PosedPart& b, PairVerdict& out) {
  for (int side = 0; side < 2; ++side) {
    const PosedPart& container = side == 0 ? a : b;
    const PosedPart& body = side == 0 ? b : a;
    if (!container.part->is_cad() || container.part->mesh->is_closed_oriented()) continue;
    const Aabb box = transformed_box(container.part->mesh->bounds(), container.pose).expanded(container.part->deflection_mm);
    std::vector<Vec3> points;
    for (const Vec3& p : body_points(body))
      if (box.contains(Aabb{p, p})) points.push_back(p);
    if (points.empty()) continue;
    auto inside = occt::first_point_inside(container.part->shape, container.pose, points, points.front(), tolerances::kContactMm);
    if (!inside.ok()) return inside.error();
    if (inside.value() < 0) continue;
    const Vec3& p = points[static_cast<std::size_t>(inside.value())];
    set_collision(out, p, std::string(side == 0 ? "b" : "a") + " lies inside " + (side == 0 ? "a" : "b") + "'s solid (exact faces)");
    out.result.contained = true;
    out.result.containment_point = p;
    return true;
  }
  return false;
}

}  // namespace

double deflection_window(const PosedPart& a, const PosedPart& b) { return a.part->deflection_mm + b.part->deflection_mm; }

Result<PairVerdict> decide_pair(const PosedPart& a, const PosedPart& b, const PairVerdictOptions& options) {
  if (!a.part || !a.part->bvh) return invalid_argument("a", "has no geometry");
  if (!b.part || !b.part->bvh) return invalid_argument("b", "has no geometry");
  if (!std::isfinite(options.clearance_mm) || options.clearance_mm < 0.0)
    return invalid_argument("clearance_mm", "must be a finite, non-negative distance");
  const double window = deflection_window(a, b);
  VerdictOptions mesh_options = options.mesh;
  // The caller does not care beyond its bound; the triangles must then be measured a window further.
  if (std::isfinite(mesh_options.distance_upper_bound_mm)) mesh_options.distance_upper_bound_mm += window;
  auto mesh = assess(*a.part->bvh, a.pose, *b.part->bvh, b.pose, mesh_options);
  if (!mesh.ok()) return mesh.error();
  const double rounding = rounding_bound(a, b);
  PairVerdict out;
  out.result = std::move(mesh).value();
  out.error_bound_mm = window + rounding;
  const VerdictResult& m = out.result;
  if (m.verdict == Verdict::kClear) {
    const auto t_nest = std::chrono::steady_clock::now();
    auto nested = contained_in_open_tessellation(a, b, out);
    out.brep_ms += elapsed_ms(t_nest);
    if (!nested.ok()) {
      set_inconclusive(out, InconclusiveReason::kBrepUndecided, "exact faces: " + nested.error().to_string());
      return out;
    }
    if (nested.value()) {
      out.error_bound_mm = tolerances::kBrepDistanceErrorMm + rounding;
      return out;
    }
  }
  if (window == 0.0) return out;  // the triangles are both parts: the kernel's answer is exact
  const bool mesh_says_apart = m.verdict == Verdict::kClear && m.distance_mm > out.error_bound_mm;
  const bool near_clearance = std::fabs(m.distance_mm - options.clearance_mm) <= out.error_bound_mm;
  if (mesh_says_apart && m.distance_is_lower_bound) return out;  // beyond what the caller asked about
  if (mesh_says_apart && !near_clearance && !options.measure_on_brep) return out;
  const auto t0 = std::chrono::steady_clock::now();
  if (a.part->is_cad() && b.part->is_cad())
    decide_cad_pair(a, b, window, rounding, mesh_says_apart, near_clearance, out);
  else
    decide_cad_mesh(a, b, a.part->is_cad(), window, rounding, mesh_says_apart, out);
  out.brep_ms += elapsed_ms(t0);
  // Never CLEAR with a distance the bound cannot separate from contact.
  if (out.result.verdict == Verdict::kClear && out.result.distance_mm <= out.error_bound_mm)
    set_inconclusive(out, InconclusiveReason::kBrepUndecided,
                     "the distance (" + number_text(out.result.distance_mm) + " mm) is within its error bound");
  return out;
}

Result<std::optional<PairVerdict>> decide_contact(const PosedPart& a, const PosedPart& b, double clearance_mm,
                                                  const StopToken& stop) {
  PairVerdictOptions options;
  options.clearance_mm = clearance_mm;
  options.mesh.stop = &stop;
  options.mesh.distance_upper_bound_mm = clearance_mm;
  auto v = decide_pair(a, b, options);
  if (!v.ok()) return v.error();
  const VerdictResult& r = v.value().result;
  if (r.verdict == Verdict::kClear && r.distance_mm >= clearance_mm) return std::optional<PairVerdict>{};
  return std::optional<PairVerdict>{std::move(v).value()};
}

}  // namespace gk::engine
