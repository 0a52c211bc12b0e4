#include "kernel/mesh/convex_decomposition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>

namespace gk {
namespace {

// Concavity is measured on at most this many of a patch's vertices (evenly spaced): it steers the
// splitting and is reported, it decides nothing.
constexpr std::size_t kConcavitySamples = 512;

std::vector<std::array<std::uint32_t, 2>> unique_edges(const std::vector<std::array<std::uint32_t, 3>>& faces) {
  std::set<std::array<std::uint32_t, 2>> edges;
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = f[k], v = f[(k + 1) % 3];
      if (u != v) edges.insert({std::min(u, v), std::max(u, v)});
    }
  return {edges.begin(), edges.end()};
}

Aabb bounds_of(const std::vector<Vec3>& points) {
  Aabb box;
  for (const Vec3& p : points) box.extend(p);
  return box;
}

// The patch's convex piece: its hull, or for a flat patch the patch itself (its corners, its
// plane's normal and its edges, whose in-plane hull the separating-axis test sees).
ConvexPiece piece_of_patch(const TriangleMesh& mesh, const std::vector<std::uint32_t>& triangles) {
  std::map<std::uint32_t, std::uint32_t> local;
  std::vector<Vec3> points;
  std::vector<std::array<std::uint32_t, 3>> faces;
  for (std::uint32_t t : triangles) {
    std::array<std::uint32_t, 3> f{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.faces()[t][k];
      auto [it, fresh] = local.emplace(v, static_cast<std::uint32_t>(points.size()));
      if (fresh) points.push_back(mesh.vertices()[v]);
      f[k] = it->second;
    }
    faces.push_back(f);
  }
  auto hull = convex_hull_polytope(points);
  if (hull.ok()) {
    ConvexPiece piece = convex_piece_of(hull.value());
    const std::size_t stride = std::max<std::size_t>(1, points.size() / kConcavitySamples);
    for (std::size_t i = 0; i < points.size(); i += stride) {
      double inside = std::numeric_limits<double>::infinity();
      for (std::size_t f = 0; f < hull.value().faces.size(); ++f)
        inside = std::min(inside, piece.face_normals[f].dot(hull.value().corners[hull.value().faces[f][0]] - points[i]));
      piece.concavity_mm = std::max(piece.concavity_mm, inside);
    }
    return piece;
  }
  ConvexPiece flat;
  flat.corners = points;
  flat.edges = unique_edges(faces);
  Vec3 normal = Vec3::Zero();
  for (const auto& f : faces) {
    const Vec3 n = (points[f[1]] - points[f[0]]).cross(points[f[2]] - points[f[0]]);
    if (n.squaredNorm() > normal.squaredNorm()) normal = n;
  }
  if (normal.squaredNorm() > 0.0) flat.face_normals.push_back(normal.normalized());
  flat.bounds = bounds_of(points);
  return flat;
}

}  // namespace

ConvexPiece convex_piece_of(const HullPolytope& hull) {
  ConvexPiece piece;
  piece.corners = hull.corners;
  for (const auto& f : hull.faces) {
    const Vec3 n = (hull.corners[f[1]] - hull.corners[f[0]]).cross(hull.corners[f[2]] - hull.corners[f[0]]);
    piece.face_normals.push_back(n.squaredNorm() > 0.0 ? Vec3(n.normalized()) : Vec3::Zero());
  }
  piece.edges = unique_edges(hull.faces);
  piece.bounds = bounds_of(hull.corners);
  return piece;
}

Result<ConvexDecomposition> approximate_convex_decomposition(const TriangleMesh& mesh, const DecompositionOptions& options) {
  if (!(options.max_concavity_mm >= 0.0) || !std::isfinite(options.max_concavity_mm))
    return invalid_argument("max_concavity_mm", "must be a finite, non-negative distance");
  if (options.max_pieces < 1 || options.max_pieces > 4096) return invalid_argument("max_pieces", "must be in [1, 4096]");
  std::vector<std::uint32_t> all;
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (!options.region.empty()) {
      Aabb box;
      for (const Vec3& p : mesh.triangle(t)) box.extend(p);
      if (!box.overlaps(options.region)) continue;
    }
    all.push_back(t);
  }
  struct Patch {
    std::vector<std::uint32_t> triangles;
    ConvexPiece piece;
  };
  std::vector<Patch> patches;
  if (!all.empty()) patches.push_back({all, piece_of_patch(mesh, all)});
  while (static_cast<int>(patches.size()) < options.max_pieces && !(options.stop && options.stop->stop_requested())) {
    // Split the deepest patch that can be split.
    std::size_t worst = patches.size();
    for (std::size_t i = 0; i < patches.size(); ++i)
      if (patches[i].triangles.size() >= 2 && patches[i].piece.concavity_mm > options.max_concavity_mm &&
          (worst == patches.size() || patches[i].piece.concavity_mm > patches[worst].piece.concavity_mm))
        worst = i;
    if (worst == patches.size()) break;
    std::vector<std::uint32_t> tris = std::move(patches[worst].triangles);
    auto centroid = [&mesh](std::uint32_t t) {
      const Triangle tri = mesh.triangle(t);
      return Vec3((tri[0] + tri[1] + tri[2]) / 3.0);
    };
    Aabb spread;
    for (std::uint32_t t : tris) spread.extend(centroid(t));
    int axis = 0;
    spread.diagonal().maxCoeff(&axis);
    const auto mid = tris.begin() + static_cast<std::ptrdiff_t>(tris.size() / 2);
    std::nth_element(tris.begin(), mid, tris.end(),
                     [&](std::uint32_t l, std::uint32_t r) { return centroid(l)[axis] < centroid(r)[axis]; });
    std::vector<std::uint32_t> left(tris.begin(), mid), right(mid, tris.end());
    patches[worst] = {left, piece_of_patch(mesh, left)};
    patches.push_back({right, piece_of_patch(mesh, right)});
  }
  ConvexDecomposition out;
  for (Patch& p : patches) {
    out.max_concavity_mm = std::max(out.max_concavity_mm, p.piece.concavity_mm);
    out.pieces.push_back(std::move(p.piece));
  }
  return out;
}

ConvexSeparation convex_penetration(const ConvexPiece& a, const RigidTransform& pose_a, const ConvexPiece& b,
                                    const RigidTransform& pose_b, std::size_t max_edge_pairs) {
  std::vector<Vec3> ca, cb;
  for (const Vec3& p : a.corners) ca.push_back(pose_a.apply(p));
  for (const Vec3& p : b.corners) cb.push_back(pose_b.apply(p));
  ConvexSeparation best;
  best.depth_mm = std::numeric_limits<double>::infinity();
  auto try_axis = [&](const Vec3& axis) {
    const double len = axis.norm();
    if (!(len > 1e-12)) return;
    const Vec3 n = axis / len;
    double min_a = std::numeric_limits<double>::infinity(), max_a = -min_a, min_b = min_a, max_b = -min_a;
    for (const Vec3& p : ca) {
      const double s = n.dot(p);
      min_a = std::min(min_a, s);
      max_a = std::max(max_a, s);
    }
    for (const Vec3& p : cb) {
      const double s = n.dot(p);
      min_b = std::min(min_b, s);
      max_b = std::max(max_b, s);
    }
    // B moves along +n until its lowest point passes A's highest, or along -n the other way.
    if (max_a - min_b < best.depth_mm) best = {n, max_a - min_b, false};
    if (max_b - min_a < best.depth_mm) best = {-n, max_b - min_a, false};
  };
  for (const Vec3& n : a.face_normals) try_axis(pose_a.apply_direction(n));
  for (const Vec3& n : b.face_normals) try_axis(pose_b.apply_direction(n));
  const bool edges = a.edges.size() * b.edges.size() <= max_edge_pairs;
  if (edges)
    for (const auto& ea : a.edges) {
      const Vec3 da = ca[ea[1]] - ca[ea[0]];
      for (const auto& eb : b.edges) try_axis(da.cross(cb[eb[1]] - cb[eb[0]]));
    }
  best.edge_axes_tested = edges;
  if (!std::isfinite(best.depth_mm)) best.depth_mm = 0.0;  // no usable axis (points only)
  return best;
}

}  // namespace gk
