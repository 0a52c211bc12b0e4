#include "kernel/mesh/display_decimation.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

namespace gk {
namespace {

DisplayMesh as_is(const TriangleMesh& mesh) {
  DisplayMesh out;
  out.vertices = mesh.vertices();
  for (const TriangleMesh::Face& f : mesh.faces()) out.triangles.push_back({f[0], f[1], f[2]});
  return out;
}

// Clusters with `cells` cells along the box's longest side.
DisplayMesh clustered(const TriangleMesh& mesh, const Aabb& box, int cells) {
  const Vec3 size = box.max - box.min;
  const double cell = std::max(size.maxCoeff(), 1e-9) / cells;
  const auto key_of = [&](const Vec3& p) {
    const auto index = [&](int k) {
      return static_cast<std::uint64_t>(std::clamp(std::floor((p[k] - box.min[k]) / cell), 0.0, 2097151.0));
    };
    return (index(0) << 42) | (index(1) << 21) | index(2);
  };
  std::unordered_map<std::uint64_t, std::uint32_t> cluster_of_key;
  std::vector<Vec3> sums;
  std::vector<double> counts;
  std::vector<std::uint32_t> cluster(mesh.vertices().size());
  for (std::size_t v = 0; v < mesh.vertices().size(); ++v) {
    const Vec3& p = mesh.vertices()[v];
    const auto [it, added] = cluster_of_key.emplace(key_of(p), static_cast<std::uint32_t>(sums.size()));
    if (added) {
      sums.push_back(Vec3::Zero());
      counts.push_back(0.0);
    }
    cluster[v] = it->second;
    sums[it->second] += p;
    counts[it->second] += 1.0;
  }
  DisplayMesh out;
  out.vertices.resize(sums.size());
  for (std::size_t c = 0; c < sums.size(); ++c) out.vertices[c] = sums[c] / counts[c];
  std::set<std::array<std::uint32_t, 3>> kept;  // the same three clusters once, whatever the order
  for (const TriangleMesh::Face& f : mesh.faces()) {
    const std::array<std::uint32_t, 3> t{cluster[f[0]], cluster[f[1]], cluster[f[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    std::array<std::uint32_t, 3> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    if (kept.insert(sorted).second) out.triangles.push_back(t);
  }
  return out;
}

}  // namespace

DisplayMesh decimate_for_display(const TriangleMesh& mesh, std::size_t max_triangles) {
  max_triangles = std::max<std::size_t>(max_triangles, 1);
  if (mesh.triangle_count() <= max_triangles) return as_is(mesh);
  const Aabb box = mesh.bounds();
  // A closed surface on an n-cell grid keeps a few n^2 triangles: start finer than that, then
  // coarsen in small steps, so the result comes close to the budget.
  int cells = std::max(2, static_cast<int>(2.0 * std::sqrt(static_cast<double>(max_triangles))));
  for (;;) {
    DisplayMesh out = clustered(mesh, box, cells);
    if (out.triangles.size() <= max_triangles || cells <= 1) {
      if (out.triangles.size() > max_triangles) out.triangles.resize(max_triangles);
      return out;
    }
    cells = std::max(1, std::min(cells - 1, static_cast<int>(cells * 0.85)));
  }
}

}  // namespace gk
