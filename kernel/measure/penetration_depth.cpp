#include "kernel/measure/penetration_depth.h"

#include "kernel/mesh/convex_decomposition.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/mesh/convexity.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/core/units.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace gk {
namespace {

constexpr int kMaxPiecesPerMesh = 32;
constexpr int kMaxPieceDirections = 48;
// Larger meshes are decomposed only where the two boxes overlap (the rest cannot touch).
constexpr std::size_t kWholeMeshTriangles = 4096;
// Piece axes closer than this (cosine of 0.25 degrees) to one already taken add nothing.
constexpr double kSameDirectionCosine = 0.99999048;

// The separating axes of every overlapping pair of convex pieces, deepest first.
struct PieceAxes {
  std::vector<Vec3> directions;
  int pieces_a = 0, pieces_b = 0;
  double max_concavity_mm = 0.0;
  bool both_convex_whole = false;  // each mesh is one convex piece covering all of it
};

Result<PieceAxes> piece_axes(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b,
                             const StopToken& stop) {
  const Aabb box_a = transformed_box(a.root_bounds(), pose_a), box_b = transformed_box(b.root_bounds(), pose_b);
  Aabb overlap{box_a.min.cwiseMax(box_b.min), box_a.max.cwiseMin(box_b.max)};
  PieceAxes out;
  if (overlap.empty()) return out;
  overlap = overlap.expanded(tolerances::kContactMm);
  DecompositionOptions oa, ob;
  oa.max_pieces = ob.max_pieces = kMaxPiecesPerMesh;
  oa.stop = ob.stop = &stop;
  const bool whole_a = a.mesh().triangle_count() <= kWholeMeshTriangles;
  const bool whole_b = b.mesh().triangle_count() <= kWholeMeshTriangles;
  if (!whole_a) oa.region = transformed_box(overlap, pose_a.inverse());
  if (!whole_b) ob.region = transformed_box(overlap, pose_b.inverse());
  auto da = approximate_convex_decomposition(a.mesh(), oa);
  if (!da.ok()) return da.error();
  auto db = approximate_convex_decomposition(b.mesh(), ob);
  if (!db.ok()) return db.error();
  out.pieces_a = static_cast<int>(da.value().pieces.size());
  out.pieces_b = static_cast<int>(db.value().pieces.size());
  out.max_concavity_mm = std::max(da.value().max_concavity_mm, db.value().max_concavity_mm);
  std::vector<std::pair<double, Vec3>> found;
  bool all_edges = true;
  for (const ConvexPiece& pa : da.value().pieces) {
    const Aabb wa = transformed_box(pa.bounds, pose_a);
    for (const ConvexPiece& pb : db.value().pieces) {
      if (!wa.overlaps(transformed_box(pb.bounds, pose_b))) continue;
      const ConvexSeparation s = convex_penetration(pa, pose_a, pb, pose_b);
      all_edges = all_edges && s.edge_axes_tested;
      if (s.depth_mm > 0.0) found.emplace_back(s.depth_mm, s.direction);
    }
  }
  std::sort(found.begin(), found.end(), [](const auto& l, const auto& r) { return l.first > r.first; });
  for (const auto& [depth, dir] : found) {
    bool seen = false;
    for (const Vec3& d : out.directions) seen = seen || d.dot(dir) > kSameDirectionCosine;
    if (!seen) out.directions.push_back(dir);
    if (static_cast<int>(out.directions.size()) >= kMaxPieceDirections) break;
  }
  // Exact only for truly convex solids (every edge convex, volume equal to the hull's): a piece
  // with all its vertices on its hull can still be a V-groove or a U-channel.
  out.both_convex_whole = all_edges && out.pieces_a == 1 && out.pieces_b == 1 && out.max_concavity_mm == 0.0 &&
                          whole_a && whole_b && is_convex_solid(a.mesh()) && is_convex_solid(b.mesh());
  return out;
}

}  // namespace

namespace {

// Is B already free of A? (No surface contact, and for closed meshes neither inside the other:
// the distance query alone cannot tell containment, so the collide + box test decide it.)
Result<bool> already_free(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b) {
  auto touching = collide(a, pose_a, b, pose_b);
  if (!touching.ok()) return touching.error();
  return !touching.value().colliding &&
         !transformed_box(a.root_bounds(), pose_a).overlaps(transformed_box(b.root_bounds(), pose_b));
}

// B, known not to be free, moved along unit u: the largest translation at which it still touches A.
Result<DepthAlong> advance_back(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b,
                                const Vec3& u, double tolerance_mm, const StopToken& stop = {}) {
  DepthAlong out;
  const Aabb box_a = transformed_box(a.root_bounds(), pose_a), box_b = transformed_box(b.root_bounds(), pose_b);
  // A translation along u that surely separates the boxes.
  double hi_a = -std::numeric_limits<double>::infinity(), lo_b = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 8; ++k) {
    const Vec3 ca((k & 1) ? box_a.max.x() : box_a.min.x(), (k & 2) ? box_a.max.y() : box_a.min.y(), (k & 4) ? box_a.max.z() : box_a.min.z());
    const Vec3 cb((k & 1) ? box_b.max.x() : box_b.min.x(), (k & 2) ? box_b.max.y() : box_b.min.y(), (k & 4) ? box_b.max.z() : box_b.min.z());
    hi_a = std::max(hi_a, u.dot(ca));
    lo_b = std::min(lo_b, u.dot(cb));
  }
  double t = std::max(0.0, hi_a - lo_b) + 1.0;
  // Back along -u by conservative advancement until the surfaces meet.
  for (out.steps = 0; out.steps < 100000; ++out.steps) {
    if (out.steps % 16 == 15 && stop.stop_requested()) return stopped("advancing along one direction");
    RigidTransform moved = pose_b;
    moved.translation += t * u;
    auto d = distance(a, pose_a, b, moved);
    if (!d.ok()) return d.error();
    const double gap = d.value().distance_mm;
    if (gap <= tolerance_mm) {
      out.depth_mm = t;
      return out;
    }
    t -= gap;
    if (t <= 0.0) return out;  // back at the start without meeting a surface: B was free
  }
  return Error{ErrorCode::kInternal, "direction", "advancement did not converge"};
}

// The translations t in [0, t_max] at which triangle ta touches or crosses tb + t u (both in A's
// frame), by the separating-axis theorem: on each candidate axis the projections must overlap,
// a linear condition in t. False when no t qualifies. Rounding is covered by `slack` [mm].
bool meeting_interval(const Triangle& ta, const Triangle& tb, const Vec3& u, double t_max, double slack, double& lo, double& hi) {
  const Vec3 ea[3] = {ta[1] - ta[0], ta[2] - ta[1], ta[0] - ta[2]};
  const Vec3 eb[3] = {tb[1] - tb[0], tb[2] - tb[1], tb[0] - tb[2]};
  const Vec3 na = ea[0].cross(ea[1]), nb = eb[0].cross(eb[1]);
  Vec3 axes[17];
  int n = 0;
  axes[n++] = na;
  axes[n++] = nb;
  for (const Vec3& x : ea)
    for (const Vec3& y : eb) axes[n++] = x.cross(y);
  for (const Vec3& x : ea) axes[n++] = na.cross(x);  // in-plane normals: coplanar triangles
  for (const Vec3& y : eb) axes[n++] = nb.cross(y);
  lo = 0.0;
  hi = t_max;
  for (int i = 0; i < n; ++i) {
    const double len = axes[i].norm();
    if (!(len > 1e-300)) continue;
    const Vec3 axis = axes[i] / len;
    double a0 = axis.dot(ta[0]), a1 = a0, b0 = axis.dot(tb[0]), b1 = b0;
    for (int k = 1; k < 3; ++k) {
      a0 = std::min(a0, axis.dot(ta[k]));
      a1 = std::max(a1, axis.dot(ta[k]));
      b0 = std::min(b0, axis.dot(tb[k]));
      b1 = std::max(b1, axis.dot(tb[k]));
    }
    // Overlap of [a0, a1] and [b0 + t k, b1 + t k]: a0 - b1 - slack <= t k <= a1 - b0 + slack.
    const double k = axis.dot(u);
    const double from = a0 - b1 - slack, to = a1 - b0 + slack;
    if (std::fabs(k) < 1e-15) {
      if (from > 0.0 || to < 0.0) return false;
      continue;
    }
    double t0 = from / k, t1 = to / k;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
    if (lo > hi) return false;
  }
  return true;
}

// Every translation in [0, t_max] at which B's surface meets A's, as intervals (unsorted), by a
// dual traversal with B's node boxes swept along u. False when more than max_pairs pairs qualify.
bool meeting_intervals(const MeshBvh& a, const MeshBvh& b, const RigidTransform& b_in_a, const Vec3& u, double t_max,
                       std::size_t max_pairs, std::vector<std::pair<double, double>>& out) {
  const BvhNode* na = a.nodes();
  const BvhNode* nb = b.nodes();
  const Mat3 abs_r = b_in_a.rotation.cwiseAbs();
  const double slack = tolerances::kComparisonSlackRelative * std::max({a.root_bounds().max.cwiseAbs().maxCoeff(), a.root_bounds().min.cwiseAbs().maxCoeff(),
                                        b_in_a.translation.norm() + b.root_bounds().max.cwiseAbs().maxCoeff() +
                                            b.root_bounds().min.cwiseAbs().maxCoeff() + t_max, 1.0});
  const Vec3 sweep = t_max * u;
  std::vector<std::pair<int, int>> stack = {{0, 0}};
  std::size_t pairs = 0;
  while (!stack.empty()) {
    const auto [ia, ib] = stack.back();
    stack.pop_back();
    // B's node box in A's frame, swept from t = 0 to t_max.
    const Vec3 cb = b_in_a.apply(nb[ib].center());
    const Vec3 hb = abs_r * nb[ib].half_extent();
    const Vec3 lo_b = cb - hb + sweep.cwiseMin(Vec3::Zero()) - Vec3::Constant(slack);
    const Vec3 hi_b = cb + hb + sweep.cwiseMax(Vec3::Zero()) + Vec3::Constant(slack);
    const Vec3 lo_a = na[ia].lower(), hi_a = na[ia].upper();
    if ((lo_a.array() > hi_b.array()).any() || (lo_b.array() > hi_a.array()).any()) continue;
    const bool leaf_a = na[ia].is_leaf(), leaf_b = nb[ib].is_leaf();
    if (leaf_a && leaf_b) {
      for (int ka = na[ia].first_triangle(); ka <= na[ia].last_triangle(); ++ka)
        for (int kb = nb[ib].first_triangle(); kb <= nb[ib].last_triangle(); ++kb) {
          if (++pairs > max_pairs) return false;
          const Triangle ta = a.ordered_triangle(ka);
          const Triangle tl = b.ordered_triangle(kb);
          const Triangle tb = {b_in_a.apply(tl[0]), b_in_a.apply(tl[1]), b_in_a.apply(tl[2])};
          double lo = 0.0, hi = 0.0;
          if (meeting_interval(ta, tb, u, t_max, slack, lo, hi)) out.emplace_back(lo, hi);
        }
      continue;
    }
    const bool split_a = !leaf_a && (leaf_b || na[ia].size() >= nb[ib].size());
    if (split_a) {
      stack.push_back({ia + 1, ib});
      stack.push_back({na[ia].second_child(), ib});
    } else {
      stack.push_back({ia, ib + 1});
      stack.push_back({ia, nb[ib].second_child()});
    }
  }
  return true;
}

// The first translation along u at which B is free of A (its surface apart from or touching A's,
// and not inside it): the end of the first stretch of meeting translations after which B is not
// contained. Each candidate is confirmed by the exact verdict; nullopt when none is confirmed
// below `last` (the last exit, free by construction) or there are too many pairs to list.
std::optional<double> first_free_translation(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                             const RigidTransform& pose_b, const Vec3& u, double last, double tolerance_mm) {
  const RigidTransform b_in_a = relative_transform(pose_a, pose_b);
  const Vec3 u_in_a = pose_a.rotation.transpose() * u;
  std::vector<std::pair<double, double>> intervals;
  if (!meeting_intervals(a, b, b_in_a, u_in_a, last, 4000000, intervals)) return std::nullopt;
  std::sort(intervals.begin(), intervals.end());
  auto free_at = [&](double t) {
    RigidTransform moved = pose_b;
    moved.translation += t * u;
    auto v = assess(a, pose_a, b, moved);
    return v.ok() && (v.value().verdict == Verdict::kClear || v.value().verdict == Verdict::kTouching);
  };
  // Walk the union of the intervals from t = 0; each gap's start is a candidate.
  double reach = 0.0;  // the union covers [.., reach]
  std::size_t i = 0;
  while (i < intervals.size() && intervals[i].first <= reach) reach = std::max(reach, intervals[i++].second);
  while (reach < last) {
    const double gap_end = i < intervals.size() ? intervals[i].first : last;
    const double candidate = std::min(reach + tolerance_mm, last);
    if (candidate < gap_end && free_at(0.5 * (reach + gap_end)) && free_at(candidate)) return candidate;
    if (i >= intervals.size()) break;
    reach = std::max(reach, intervals[i].second);
    while (i < intervals.size() && intervals[i].first <= reach) reach = std::max(reach, intervals[i++].second);
  }
  return std::nullopt;
}

}  // namespace

Result<DepthAlong> penetration_along(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, const Vec3& direction, double tolerance_mm,
                                     const StopToken& stop) {
  if (stop.stop_requested()) return stopped("the depth along a direction");
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("direction", "must be a non-zero vector");
  if (!(tolerance_mm > 0.0)) return invalid_argument("tolerance_mm", "must be positive");
  auto free = already_free(a, pose_a, b, pose_b);
  if (!free.ok()) return free.error();
  if (free.value()) return DepthAlong{};
  // The last exit is free (everything beyond it is); a free stretch may come earlier (B leaving
  // through a cavity of A): the first free position is what "how far B must move" means.
  const Vec3 u = direction.normalized();
  auto last = advance_back(a, pose_a, b, pose_b, u, tolerance_mm, stop);
  if (!last.ok()) return last;
  DepthAlong out = last.value();
  out.last_exit_mm = out.depth_mm;
  if (const std::optional<double> first = first_free_translation(a, pose_a, b, pose_b, u, out.depth_mm, tolerance_mm)) {
    out.depth_mm = std::min(out.depth_mm, *first);
  }
  return out;
}

Result<DepthVector> penetration_vector(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                       const RigidTransform& pose_b, int samples, double tolerance_mm,
                                       const StopToken& stop, const StopToken& enough) {
  if (samples < 6 || samples > 100000) return invalid_argument("samples", "must be in [6, 100000]");
  DepthVector best;
  best.depth_mm = std::numeric_limits<double>::infinity();
  auto axes = piece_axes(a, pose_a, b, pose_b, stop);
  if (!axes.ok()) return axes.error();
  if (stop.stop_requested()) return stopped("the convex pieces for the penetration depth");
  best.pieces_a = axes.value().pieces_a;
  best.pieces_b = axes.value().pieces_b;
  best.max_concavity_mm = axes.value().max_concavity_mm;
  std::vector<Vec3> candidates = axes.value().directions;
  // Sliding B off along one of the two parts' own axes is a common way out (flat parts, prisms).
  for (const Mat3* r : {&pose_a.rotation, &pose_b.rotation})
    for (int k = 0; k < 3; ++k) {
      candidates.push_back(r->col(k));
      candidates.push_back(-r->col(k));
    }
  best.piece_directions = static_cast<int>(candidates.size());
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < samples; ++i) {
    const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / samples;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    candidates.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  if (!(tolerance_mm > 0.0)) return invalid_argument("tolerance_mm", "must be positive");
  // Whether B is free does not depend on the direction: decided once.
  auto free = already_free(a, pose_a, b, pose_b);
  if (!free.ok()) return free.error();
  if (free.value()) {
    best.depth_mm = 0.0;
    return best;
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (stop.stop_requested() || (best.directions_tried > 0 && enough.stop_requested())) {
      // The best so far is still a certified upper bound (B moved by it is free), only less tight.
      if (best.directions_tried > 0 && std::isfinite(best.depth_mm)) {
        best.stopped_early = true;
        break;
      }
      return stopped("the penetration depth (no direction tried)");
    }
    auto d = advance_back(a, pose_a, b, pose_b, candidates[i].normalized(), tolerance_mm, stop);
    if (!d.ok() && d.error().code == ErrorCode::kStopped && best.directions_tried > 0 && std::isfinite(best.depth_mm)) {
      best.stopped_early = true;  // this direction unfinished; the ones before it stand
      break;
    }
    if (!d.ok()) return d.error();
    ++best.directions_tried;
    if (d.value().depth_mm < best.depth_mm) {
      best.depth_mm = d.value().depth_mm;
      best.direction = candidates[i];
      best.from_piece_axis = static_cast<int>(i) < best.piece_directions;
    }
    if (best.depth_mm == 0.0) break;
  }
  best.exact = axes.value().both_convex_whole && best.depth_mm > 0.0 && !best.stopped_early;
  // A Fibonacci lattice of n points leaves every direction within about sqrt(4 pi / n) radians
  // (times a small constant) of a sample.
  best.max_angle_between_samples_deg = 180.0 / kPi * 2.0 * std::sqrt(4.0 * kPi / samples);
  return best;
}

}  // namespace gk
