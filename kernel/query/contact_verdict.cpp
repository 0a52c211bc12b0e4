#include "kernel/query/contact_verdict.h"

#include "kernel/predicates/exact_predicates.h"
#include "kernel/query/point_containment.h"
#include "kernel/query/triangle_intersection.h"
#include "kernel/core/units.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace gk {
namespace {


// Two coplanar triangles: do their interiors share area? Decided exactly on their projection to
// the coordinate plane their common normal is most nearly along (dropping a coordinate keeps the
// written values): the interiors are apart exactly when one of the six edge lines has the other
// triangle entirely on its outer side, boundary included.
bool coplanar_interiors_overlap(const Triangle& ta, const Triangle& tb) {
  const Vec3 n = (ta[1] - ta[0]).cross(ta[2] - ta[0]);
  int drop = 0;
  if (std::fabs(n.y()) > std::fabs(n[drop])) drop = 1;
  if (std::fabs(n.z()) > std::fabs(n[drop])) drop = 2;
  const int u = drop == 0 ? 1 : 0, w = drop == 2 ? 1 : 2;
  const auto separated_by_an_edge_of = [&](const Triangle& t, const Triangle& other) {
    for (int e = 0; e < 3; ++e) {
      const Vec3& p = t[e];
      const Vec3& q = t[(e + 1) % 3];
      const Vec3& r = t[(e + 2) % 3];
      const int inner = exact::orient2d(p[u], p[w], q[u], q[w], r[u], r[w]);
      if (inner == 0) return false;  // a degenerate projection: no verdict from it (stays a crossing)
      bool all_outside = true;
      for (const Vec3& v : other) all_outside = all_outside && exact::orient2d(p[u], p[w], q[u], q[w], v[u], v[w]) * inner <= 0;
      if (all_outside) return true;
    }
    return false;
  };
  return !separated_by_an_edge_of(ta, tb) && !separated_by_an_edge_of(tb, ta);
}

// Is the intersecting pair (ta, tb), both in A's frame and wound outward, a contact from outside?
// hit: their intersection in that frame when the caller has it (computed here when needed).
bool is_outside_contact(const Triangle& ta, const Triangle& tb, const TriangleIntersection* hit = nullptr) {
  int a_below_b = 0, b_below_a = 0, a_on_b = 0;
  for (const Vec3& v : ta) {
    const int s = exact::orient3d(tb[0], tb[1], tb[2], v);
    a_below_b += s < 0;
    a_on_b += s == 0;
  }
  for (const Vec3& v : tb) b_below_a += exact::orient3d(ta[0], ta[1], ta[2], v) < 0;
  if (a_on_b == 3) {
    const Vec3 na = (ta[1] - ta[0]).cross(ta[2] - ta[0]);
    const Vec3 nb = (tb[1] - tb[0]).cross(tb[2] - tb[0]);
    // Coplanar: opposite normals touch; equal normals overlap where their interiors share area
    // (both solids then lie on the same side of a shared piece of surface) and only touch where
    // they meet along an edge or at a corner (two boxes side by side, their faces flush).
    if (na.dot(nb) < 0.0) return true;
    return !coplanar_interiors_overlap(ta, tb);
  }
  if (a_below_b == 0 || b_below_a == 0) return true;
  // Each straddles the other's plane: a crossing unless they meet in a point. The segment is
  // measured on these triangles, in A's frame, never on a contact's world segment: 1e7 mm out, a
  // round trip through world coordinates rounds it by more than kPointContactMm (a review: a
  // corner 1e-9 mm into a face was COLLISION or TOUCHING by where the pair stood). Triangles that
  // do not meet here at all (the search met them in its own frame, a rounding away) do not cross.
  const TriangleIntersection here = hit ? *hit : intersect_triangles(ta, tb);
  return !here.intersects || (here.segment_end - here.segment_start).norm() <= tolerances::kPointContactMm;
}

// Triangle tb of B (mesh index) in A's frame.
Triangle b_triangle_in_a(const MeshBvh& b, const RigidTransform& b_in_a, std::uint32_t tb) {
  const Triangle t = b.mesh().triangle(tb);
  return {b_in_a.apply(t[0]), b_in_a.apply(t[1]), b_in_a.apply(t[2])};
}

// Where triangle ta of A and tb of B (mesh indices, neither zero-area) cross, in A's frame: their
// intersection when they meet and (oriented meshes) not as a contact from outside.
std::optional<TriangleIntersection> crossing_in_a(const MeshBvh& a, std::uint32_t ta, const MeshBvh& b, std::uint32_t tb,
                                                  const RigidTransform& b_in_a, bool oriented) {
  const Triangle tri_a = a.mesh().triangle(ta);
  const Triangle tri_b = b_triangle_in_a(b, b_in_a, tb);
  const TriangleIntersection hit = intersect_triangles(tri_a, tri_b);
  if (!hit.intersects || (oriented && is_outside_contact(tri_a, tri_b, &hit))) return std::nullopt;
  return hit;
}

}  // namespace

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::kClear: return "CLEAR";
    case Verdict::kTouching: return "TOUCHING";
    case Verdict::kCollision: return "COLLISION";
    case Verdict::kInconclusive: return "INCONCLUSIVE";
  }
  return "INCONCLUSIVE";
}

bool triangle_pair_crosses(const MeshBvh& a, const RigidTransform& pose_a, std::uint32_t ta, const MeshBvh& b,
                           const RigidTransform& pose_b, std::uint32_t tb, Vec3* point) {
  if (ta >= a.mesh().triangle_count() || tb >= b.mesh().triangle_count()) return false;
  if (a.mesh().is_degenerate(ta) || b.mesh().is_degenerate(tb)) return false;
  const bool oriented = a.mesh().is_closed_oriented() && b.mesh().is_closed_oriented();
  const auto hit = crossing_in_a(a, ta, b, tb, relative_transform(pose_a, pose_b), oriented);
  if (!hit) return false;
  if (point) *point = pose_a.apply(0.5 * (hit->segment_start + hit->segment_end));
  return true;
}

const char* to_string(InconclusiveReason r) {
  switch (r) {
    case InconclusiveReason::kNone: return "NONE";
    case InconclusiveReason::kDegenerateTriangles: return "DEGENERATE_TRIANGLES";
    case InconclusiveReason::kTessellationUnresolved: return "TESSELLATION_UNRESOLVED";
    case InconclusiveReason::kBrepUndecided: return "BREP_UNDECIDED";
    case InconclusiveReason::kPairFailed: return "PAIR_FAILED";
    case InconclusiveReason::kSweepBudgetExhausted: return "SWEEP_BUDGET_EXHAUSTED";
    case InconclusiveReason::kTooManyContacts: return "TOO_MANY_CONTACTS";
  }
  return "PAIR_FAILED";
}

int severity(Verdict v) {
  switch (v) {
    case Verdict::kClear: return 0;
    case Verdict::kTouching: return 1;
    case Verdict::kInconclusive: return 2;
    case Verdict::kCollision: return 3;
  }
  return 3;
}

double winding_number(const TriangleMesh& mesh, const Vec3& point) {
  // Van Oosterom-Strackee solid angle of each triangle, summed.
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle tri = mesh.triangle(t);
    const Vec3 a = tri[0] - point, b = tri[1] - point, c = tri[2] - point;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(numerator, denominator);
  }
  return total / (4.0 * kPi);
}

bool inside_closed_mesh(const MeshBvh& mesh, const Vec3& point) {
  if (!mesh.root_bounds().contains(Aabb{point, point})) return false;
  if (mesh.mesh().body_seeds().size() == 1)
    if (const auto parity = point_inside(mesh, point)) return *parity;
  return std::fabs(winding_number(mesh.mesh(), point)) > 0.5;
}

Result<VerdictResult> assess(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                             const RigidTransform& pose_b, const VerdictOptions& options) {
  if (!(options.contact_tolerance_mm >= 0.0) || !std::isfinite(options.contact_tolerance_mm))
    return invalid_argument("contact_tolerance_mm", "must be a finite, non-negative distance");
  VerdictResult out;
  const bool oriented = a.mesh().is_closed_oriented() && b.mesh().is_closed_oriented();

  // The distance query's bound: the caller's, but at least twice the contact tolerance (never
  // below kContactMm), so that a pair with nothing found within it is CLEAR, never TOUCHING.
  const double touch_margin = std::max(options.contact_tolerance_mm, tolerances::kContactMm);
  DistanceRequest dreq;
  dreq.stop = options.stop;
  dreq.spare = options.spare;
  if (std::isfinite(options.distance_upper_bound_mm)) dreq.upper_bound_mm = std::max(options.distance_upper_bound_mm, 2.0 * touch_margin);
  // With a bound, measured first: nothing within it, or nearest farther than the contact tolerance,
  // and no pair can cross or touch (the query's rounding, slivers included, is orders below
  // kContactMm at coordinates up to kMaxCoordinateMm), so the all-contacts search is skipped: near
  // long parallel surfaces it costs as much as the measure. Surfaces that meet end the measure at
  // once (distance 0).
  const RigidTransform b_in_a = relative_transform(pose_a, pose_b);
  std::optional<DistanceResult> measured_first;
  if (std::isfinite(dreq.upper_bound_mm)) {
    auto m = distance(a, pose_a, b, pose_b, dreq);
    if (!m.ok()) return m.error();
    measured_first = std::move(m).value();
    out.stats = measured_first->stats;
  }
  const bool surfaces_apart = measured_first && (!measured_first->found || measured_first->distance_mm > touch_margin);
  // A caller that wants one contact, where the measure ended on a pair that crosses: that pair is
  // the COLLISION (one crossing decides it), without the all-contacts search.
  if (!surfaces_apart && oriented && options.max_contacts == 1 && measured_first && measured_first->found &&
      measured_first->distance_mm == 0.0) {
    const std::uint32_t ta = measured_first->triangle_a, tb = measured_first->triangle_b;
    if (!a.mesh().is_degenerate(ta) && !b.mesh().is_degenerate(tb)) {
      if (const auto hit = crossing_in_a(a, ta, b, tb, b_in_a, true)) {
        Contact c;
        c.triangle_a = ta;
        c.triangle_b = tb;
        c.coplanar = hit->coplanar;
        c.segment_start = pose_a.apply(hit->segment_start);
        c.segment_end = pose_a.apply(hit->segment_end);
        c.point = 0.5 * (c.segment_start + c.segment_end);
        out.verdict = Verdict::kCollision;
        out.distance_mm = 0.0;
        out.point_a = out.point_b = c.point;
        out.contacts.push_back(c);
        out.contacts_truncated = true;
        out.crossing_pairs = 1;
        out.first_crossing = 0;
        out.reason = "at least 1 triangle pairs cross";
        return out;
      }
    }
  }
  if (!surfaces_apart) {
    CollisionRequest creq;
    creq.all_contacts = true;
    creq.max_contacts = options.max_contacts;
    creq.stop = options.stop;
    auto collided = collide(a, pose_a, b, pose_b, creq);
    if (!collided.ok()) return collided.error();

    // Which listed contacts cross (closed meshes: not a touch from outside), and how many were
    // decided on zero-area triangles.
    std::size_t decided_on_degenerate = 0;
    const auto classify = [&](const CollisionResult& col) {
      out.first_crossing = -1;
      out.crossing_pairs = 0;
      decided_on_degenerate = 0;
      for (const Contact& c : col.contacts) {
        if (c.involves_degenerate) {
          ++decided_on_degenerate;
          continue;
        }
        if (!oriented) {
          if (out.first_crossing < 0) out.first_crossing = static_cast<int>(&c - col.contacts.data());
          ++out.crossing_pairs;
          continue;
        }
        const Triangle ta = a.mesh().triangle(c.triangle_a);
        if (!is_outside_contact(ta, b_triangle_in_a(b, b_in_a, c.triangle_b))) {
          if (out.first_crossing < 0) out.first_crossing = static_cast<int>(&c - col.contacts.data());
          ++out.crossing_pairs;
        }
      }
    };
    classify(collided.value());
    // One crossing pair among those listed makes the pair a COLLISION whatever the rest are. When
    // none crosses but the list is cut short, the verdict is decided over every pair (thousands of
    // coplanar pairs where a finely meshed box rests on a plate; open meshes whose first pairs are
    // all on zero-area triangles): the cap applies only to what is reported.
    bool crossings_counted_in_full = !collided.value().truncated;
    if (collided.value().truncated && out.crossing_pairs == 0) {
      creq.max_contacts = std::numeric_limits<std::size_t>::max();
      collided = collide(a, pose_a, b, pose_b, creq);
      if (!collided.ok()) return collided.error();
      classify(collided.value());
      crossings_counted_in_full = true;
    }
    CollisionResult& col = collided.value();
    out.stats += col.stats;

    if (col.colliding) {
      out.distance_mm = 0.0;
      out.point_a = out.point_b = col.contacts.front().point;
      out.contacts = std::move(col.contacts);
      out.contacts_truncated = col.truncated;
      if (out.contacts.size() > options.max_contacts) {
        // Keep the first crossing pair among those reported.
        if (out.first_crossing >= static_cast<int>(options.max_contacts) && options.max_contacts > 0) {
          std::swap(out.contacts[options.max_contacts - 1], out.contacts[static_cast<std::size_t>(out.first_crossing)]);
          out.first_crossing = static_cast<int>(options.max_contacts) - 1;
        }
        out.contacts.resize(options.max_contacts);
        if (out.first_crossing >= static_cast<int>(out.contacts.size())) out.first_crossing = -1;
        out.contacts_truncated = true;
      }
      if (out.crossing_pairs > 0) {
        out.verdict = Verdict::kCollision;
        out.reason = oriented ? (crossings_counted_in_full ? "" : "at least ") + std::to_string(out.crossing_pairs) +
                                    " triangle pairs cross"
                              : "meshes intersect (open meshes: any contact counts as a collision)";
      } else if (decided_on_degenerate > 0) {
        out.verdict = Verdict::kInconclusive;
        out.inconclusive_reason = InconclusiveReason::kDegenerateTriangles;
        out.reason = "contact decided on zero-area triangles only";
      } else {
        out.verdict = Verdict::kTouching;
        out.reason = "surfaces touch from outside without crossing";
      }
      return out;
    }
  }

  // The nearest points: the first measure's, else measured now.
  if (!measured_first) {
    auto m = distance(a, pose_a, b, pose_b, dreq);
    if (!m.ok()) return m.error();
    out.stats += m.value().stats;
    measured_first = std::move(m).value();
  }
  DistanceResult& d = *measured_first;
  if (!d.found && std::isfinite(dreq.upper_bound_mm)) {
    d.distance_mm = dreq.upper_bound_mm;
    out.distance_is_lower_bound = true;
  }
  out.distance_mm = d.distance_mm;
  out.point_a = d.point_a;
  out.point_b = d.point_b;

  // Disjoint surfaces: a body may still lie wholly inside a closed mesh. One point of every
  // connected body of each mesh is tested against the other when that one is closed, whether or
  // not the body is closed itself (an open scan inside a crate interferes with it).
  {
    // Ray parity through the BVH decides it in O(log n); the winding number (O(n)) only when
    // every ray was degenerate.
    auto inside = [](const MeshBvh& m, const Vec3& p) { return inside_closed_mesh(m, p); };
    auto contained_body = [&](const MeshBvh& container, const MeshBvh& body, const RigidTransform& body_in_container,
                              Vec3& point) {
      if (!container.mesh().is_closed_oriented()) return false;
      for (std::uint32_t seed : body.mesh().body_seeds()) {
        point = body_in_container.apply(body.mesh().vertices()[seed]);
        if (inside(container, point)) return true;
      }
      return false;
    };
    Vec3 p = Vec3::Zero();
    const bool b_inside_a = contained_body(a, b, b_in_a, p);
    const bool a_inside_b = !b_inside_a && contained_body(b, a, b_in_a.inverse(), p);
    if (b_inside_a || a_inside_b) {
      // How deep the point lies: its distance to the container's surface.
      const MeshBvh& container = b_inside_a ? a : b;
      const RigidTransform& container_pose = b_inside_a ? pose_a : pose_b;
      auto probe_mesh = TriangleMesh::create({p, p, p}, {{0, 1, 2}});
      if (probe_mesh.ok()) {
        auto probe = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(probe_mesh).value()));
        if (probe.ok()) {
          auto depth = distance(container, RigidTransform{}, *probe.value(), RigidTransform{});
          if (depth.ok()) out.containment_depth_mm = depth.value().distance_mm;
        }
      }
      out.verdict = Verdict::kCollision;
      out.contained = true;
      out.containment_point = out.point_a = out.point_b = container_pose.apply(p);
      out.distance_mm = 0.0;
      out.reason = b_inside_a ? "a body of mesh B lies inside mesh A" : "a body of mesh A lies inside mesh B";
      return out;
    }
  }
  if (d.distance_mm <= options.contact_tolerance_mm) {
    out.verdict = Verdict::kTouching;
    out.reason = "apart by no more than the contact tolerance";
  } else {
    out.verdict = Verdict::kClear;
    out.reason = (out.distance_is_lower_bound ? "apart by at least " : "apart by ") + std::to_string(d.distance_mm) + " mm";
  }
  return out;
}

}  // namespace gk
