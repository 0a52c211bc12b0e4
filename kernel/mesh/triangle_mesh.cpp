#include "kernel/mesh/triangle_mesh.h"

#include "kernel/predicates/exact_predicates.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace gk {
namespace {

const char* kAxisName[3] = {"x", "y", "z"};

}  // namespace

Result<TriangleMesh> TriangleMesh::create(std::vector<Vec3> vertices, std::vector<Face> faces,
                                          const MeshBuildOptions& options) {
  if (vertices.empty()) return invalid_argument("vertices", "mesh has no vertices");
  if (faces.empty()) return invalid_argument("triangles", "mesh has no triangles");
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      const double c = vertices[i][axis];
      if (std::isfinite(c) && std::fabs(c) <= tolerances::kMaxCoordinateMm) continue;
      const std::string field = "vertices[" + std::to_string(i) + "]." + kAxisName[axis];
      if (!std::isfinite(c)) return invalid_argument(field, "coordinate is not finite");
      return invalid_argument(field, "coordinate " + std::to_string(c) + " mm is beyond the "
                                     "accepted range of " + std::to_string(tolerances::kMaxCoordinateMm) + " mm");
    }
  }
  for (std::size_t t = 0; t < faces.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (faces[t][k] >= vertices.size())
        return invalid_argument("triangles[" + std::to_string(t) + "][" + std::to_string(k) + "]",
                                "vertex index " + std::to_string(faces[t][k]) + " is out of range (" +
                                    std::to_string(vertices.size()) + " vertices)");
    }
  }

  TriangleMesh mesh;
  mesh.vertices_ = std::move(vertices);
  // Zero area: repeated corner index, or exactly collinear corners.
  // The kept triangles' degeneracy is known from this test (the same one
  // compute_bounds_and_degeneracy makes): no second pass of exact predicates.
  std::vector<std::uint8_t> zero_area(faces.size(), 0);
  for (std::size_t t = 0; t < faces.size(); ++t) {
    const Face& f = faces[t];
    zero_area[t] = f[0] == f[1] || f[1] == f[2] || f[0] == f[2] ||
                   exact::collinear(mesh.vertices_[f[0]], mesh.vertices_[f[1]], mesh.vertices_[f[2]]);
  }
  // Only a zero-area triangle whose edges are all edges of triangles with area is dropped (a
  // sliver along a seam: its points lie on those edges already). One with an edge of its own (a
  // needle, a wire) is geometry: kept, and a contact on it is reported as on zero-area triangles.
  // (The edges are listed only when there is something to drop: most meshes have no such triangle.)
  std::vector<std::pair<std::uint32_t, std::uint32_t>> area_edges;
  std::vector<std::uint8_t> area_vertex;
  if (options.drop_zero_area_triangles && std::find(zero_area.begin(), zero_area.end(), 1) != zero_area.end()) {
    area_vertex.assign(mesh.vertices_.size(), 0);
    area_edges.reserve(3 * faces.size());
    for (std::size_t t = 0; t < faces.size(); ++t) {
      if (zero_area[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t u = faces[t][k], v = faces[t][(k + 1) % 3];
        area_edges.push_back({std::min(u, v), std::max(u, v)});
        area_vertex[u] = 1;
      }
    }
    std::sort(area_edges.begin(), area_edges.end());
  }
  const auto covered = [&](const Face& f) {
    bool any_edge = false;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = f[k], v = f[(k + 1) % 3];
      if (u == v) continue;
      any_edge = true;
      if (!std::binary_search(area_edges.begin(), area_edges.end(), std::make_pair(std::min(u, v), std::max(u, v)))) return false;
    }
    return any_edge || area_vertex[f[0]] != 0;  // a point: covered if a triangle with area has it
  };
  std::vector<Face> kept;
  kept.reserve(faces.size());
  mesh.degenerate_.reserve(faces.size());
  for (std::size_t t = 0; t < faces.size(); ++t) {
    const Face& f = faces[t];
    if (zero_area[t]) {
      mesh.report_.zero_area_triangles.push_back(static_cast<std::uint32_t>(t));
      if (options.drop_zero_area_triangles && covered(f)) {
        ++mesh.report_.dropped_triangles;
        continue;
      }
      ++mesh.degenerate_count_;
    }
    kept.push_back(f);
    mesh.degenerate_.push_back(zero_area[t]);
  }
  if (kept.empty()) return invalid_argument("triangles", "every triangle has zero area");
  mesh.faces_ = std::move(kept);
  for (const Face& f : mesh.faces_)
    for (std::uint32_t v : f) mesh.bounds_.extend(mesh.vertices_[v]);
  mesh.analyse_topology();
  return mesh;
}

void TriangleMesh::compute_bounds_and_degeneracy() {
  bounds_ = Aabb{};
  for (const Face& f : faces_)
    for (std::uint32_t v : f) bounds_.extend(vertices_[v]);
  degenerate_.assign(faces_.size(), 0);
  degenerate_count_ = 0;
  for (std::size_t t = 0; t < faces_.size(); ++t) {
    const Face& f = faces_[t];
    if (exact::collinear(vertices_[f[0]], vertices_[f[1]], vertices_[f[2]])) {
      degenerate_[t] = 1;
      ++degenerate_count_;
    }
  }
}

void TriangleMesh::analyse_topology() {
  // Count directed uses of each undirected edge: closed and oriented means every edge is used
  // exactly twice, once in each direction.
  // Sorted edge keys rather than a hash map: several times faster on the small meshes built per
  // request (machine bodies) and no slower on large ones. Each use: the edge, and whether it runs
  // from the lower index to the higher.
  std::vector<std::pair<std::uint64_t, bool>> uses;
  uses.reserve(faces_.size() * 3);
  for (const Face& f : faces_) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = f[k], b = f[(k + 1) % 3];
      const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      uses.emplace_back(key, a < b);
    }
  }
  std::sort(uses.begin(), uses.end());
  report_.boundary_edges = report_.non_manifold_edges = 0;
  bool oriented = true;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    int forward = 0;
    while (j < uses.size() && uses[j].first == uses[i].first) forward += uses[j++].second ? 1 : 0;
    const int total = static_cast<int>(j - i);
    if (total == 1) ++report_.boundary_edges;
    if (total > 2) ++report_.non_manifold_edges;
    if (total == 2 && forward != 1) oriented = false;
    i = j;
  }
  report_.closed = report_.boundary_edges == 0 && report_.non_manifold_edges == 0;
  report_.consistently_oriented = oriented && report_.non_manifold_edges == 0;

  // Connected bodies by union-find over the vertices the triangles use.
  std::vector<std::uint32_t> parent(vertices_.size());
  for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto root = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Face& f : faces_)
    for (int k = 1; k < 3; ++k) parent[root(f[k])] = root(f[0]);
  std::vector<char> seen(vertices_.size(), 0);
  body_seeds_.clear();
  for (const Face& f : faces_) {
    const std::uint32_t r = root(f[0]);
    if (seen[r]) continue;
    seen[r] = 1;
    body_seeds_.push_back(f[0]);
  }
}

double TriangleMesh::area() const {
  double total = 0.0;
  for (std::size_t t = 0; t < faces_.size(); ++t) {
    const Triangle tri = triangle(t);
    total += 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).norm();
  }
  return total;
}

double TriangleMesh::signed_volume() const {
  // Relative to the box centre, so that far-from-origin meshes lose no digits.
  const Vec3 origin = bounds_.center();
  double six_volume = 0.0;
  for (std::size_t t = 0; t < faces_.size(); ++t) {
    const Triangle tri = triangle(t);
    six_volume += (tri[0] - origin).dot((tri[1] - origin).cross(tri[2] - origin));
  }
  return six_volume / 6.0;
}

Result<bool> TriangleMesh::set_vertices(std::vector<Vec3> vertices) {
  if (vertices.size() != vertices_.size())
    return invalid_argument("vertices", "expected " + std::to_string(vertices_.size()) + " vertices, got " +
                                            std::to_string(vertices.size()));
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (!vertices[i].allFinite()) return invalid_argument("vertices[" + std::to_string(i) + "]", "not finite");
  vertices_ = std::move(vertices);
  compute_bounds_and_degeneracy();
  return true;
}

}  // namespace gk
