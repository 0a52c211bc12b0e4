#include "kernel/mesh/convexity.h"

#include "kernel/mesh/convex_hull.h"
#include "kernel/predicates/exact_predicates.h"

#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace gk {

bool is_convex_solid(const TriangleMesh& mesh) {
  if (!mesh.is_closed_oriented() || mesh.body_seeds().size() != 1 || mesh.has_degenerate_triangles()) return false;
  const double volume = mesh.signed_volume();
  if (!(volume > 0.0)) return false;  // inward-wound: its "inside" is the outside
  // Every directed edge (u, v) of a triangle meets the reverse edge (v, u) of its neighbour.
  const auto& faces = mesh.faces();
  const auto& v = mesh.vertices();
  auto key = [](std::uint32_t a, std::uint32_t b) { return (static_cast<std::uint64_t>(a) << 32) | b; };
  std::unordered_map<std::uint64_t, std::uint32_t> owner;  // directed edge -> triangle
  owner.reserve(faces.size() * 3);
  for (std::uint32_t t = 0; t < faces.size(); ++t)
    for (int k = 0; k < 3; ++k) owner[key(faces[t][k], faces[t][(k + 1) % 3])] = t;
  for (std::uint32_t t = 0; t < faces.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = faces[t][k], b = faces[t][(k + 1) % 3];
      auto it = owner.find(key(b, a));
      if (it == owner.end()) return false;
      const auto& n = faces[it->second];
      std::uint32_t far = n[0];
      for (int j = 0; j < 3; ++j)
        if (n[j] != a && n[j] != b) far = n[j];
      // The neighbour's far corner above this triangle's plane: the edge is a valley.
      if (exact::orient3d(v[faces[t][0]], v[faces[t][1]], v[faces[t][2]], v[far]) > 0) return false;
    }
  auto hull = convex_hull(v);
  if (!hull.ok()) return false;
  return std::fabs(hull.value().signed_volume() - volume) <= 1e-9 * volume;
}

}  // namespace gk
