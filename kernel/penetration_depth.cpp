#include "kernel/penetration_depth.h"

#include "kernel/convex_decomposition.h"
#include "kernel/convexity.h"
#include "kernel/mesh_collision.h"
#include "kernel/mesh_distance.h"

#include <cmath>

namespace gk {
namespace {

constexpr double kPi = 3.14159265358979323846;
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

Result<PieceAxes> piece_axes(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b) {
  const Aabb box_a = transformed_box(a.root_bounds(), pose_a), box_b = transformed_box(b.root_bounds(), pose_b);
  Aabb overlap{box_a.min.cwiseMax(box_b.min), box_a.max.cwiseMin(box_b.max)};
  PieceAxes out;
  if (overlap.empty()) return out;
  overlap = overlap.expanded(tolerances::kContactMm);
  DecompositionOptions oa, ob;
  oa.max_pieces = ob.max_pieces = kMaxPiecesPerMesh;
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
                                const Vec3& u, double tolerance_mm) {
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

}  // namespace

Result<DepthAlong> penetration_along(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, const Vec3& direction, double tolerance_mm) {
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("direction", "must be a non-zero vector");
  if (!(tolerance_mm > 0.0)) return invalid_argument("tolerance_mm", "must be positive");
  auto free = already_free(a, pose_a, b, pose_b);
  if (!free.ok()) return free.error();
  if (free.value()) return DepthAlong{};
  return advance_back(a, pose_a, b, pose_b, direction.normalized(), tolerance_mm);
}

Result<DepthVector> penetration_vector(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                       const RigidTransform& pose_b, int samples, double tolerance_mm) {
  if (samples < 6 || samples > 100000) return invalid_argument("samples", "must be in [6, 100000]");
  DepthVector best;
  best.depth_mm = std::numeric_limits<double>::infinity();
  auto axes = piece_axes(a, pose_a, b, pose_b);
  if (!axes.ok()) return axes.error();
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
    auto d = advance_back(a, pose_a, b, pose_b, candidates[i].normalized(), tolerance_mm);
    if (!d.ok()) return d.error();
    ++best.directions_tried;
    if (d.value().depth_mm < best.depth_mm) {
      best.depth_mm = d.value().depth_mm;
      best.direction = candidates[i];
      best.from_piece_axis = static_cast<int>(i) < best.piece_directions;
    }
    if (best.depth_mm == 0.0) break;
  }
  best.exact = axes.value().both_convex_whole && best.depth_mm > 0.0;
  // A Fibonacci lattice of n points leaves every direction within about sqrt(4 pi / n) radians
  // (times a small constant) of a sample.
  best.max_angle_between_samples_deg = 180.0 / kPi * 2.0 * std::sqrt(4.0 * kPi / samples);
  return best;
}

}  // namespace gk
