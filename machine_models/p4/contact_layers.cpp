#include "machine_models/p4/contact_layers.h"

namespace gk::p4 {

Result<std::optional<TriangleMesh>> clip_mesh_at_z(const TriangleMesh& mesh, double z, bool keep_below) {
  auto side = [&](const Vec3& p) { return keep_below ? z - p.z() : p.z() - z; };  // > 0: kept
  std::vector<Vec3> vertices;
  std::vector<TriangleMesh::Face> faces;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle tri = mesh.triangle(t);
    if (side(tri[0]) <= 0.0 && side(tri[1]) <= 0.0 && side(tri[2]) <= 0.0) continue;
    // Sutherland-Hodgman against the plane, then a fan.
    std::vector<Vec3> poly;
    for (int i = 0; i < 3; ++i) {
      const Vec3& a = tri[i];
      const Vec3& b = tri[(i + 1) % 3];
      const double sa = side(a), sb = side(b);
      if (sa > 0.0) poly.push_back(a);
      if ((sa > 0.0) != (sb > 0.0)) {
        Vec3 cut = a + (sa / (sa - sb)) * (b - a);
        cut.z() = z;  // on the plane exactly
        poly.push_back(cut);
      }
    }
    if (poly.size() < 3) continue;
    const auto base = static_cast<std::uint32_t>(vertices.size());
    for (const Vec3& p : poly) vertices.push_back(p);
    for (std::uint32_t i = 1; i + 1 < poly.size(); ++i) faces.push_back({base, base + i, base + i + 1});
  }
  if (faces.empty()) return std::optional<TriangleMesh>();
  auto clipped = TriangleMesh::create(std::move(vertices), std::move(faces));
  if (!clipped.ok()) return clipped.error();
  return std::optional<TriangleMesh>(std::move(clipped).value());
}

}  // namespace gk::p4
