#include "tests/support/random_meshes.h"

#include <Eigen/Geometry>

#include <map>
#include <utility>

namespace gk::testing {

TriangleMesh random_closed_blob(Rng& rng, int subdivisions, double radius, double roughness, const Vec3& center) {
  std::vector<Vec3> v = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<TriangleMesh::Face> f = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      const auto id = static_cast<std::uint32_t>(v.size() - 1);
      midpoint[key] = id;
      return id;
    };
    std::vector<TriangleMesh::Face> next;
    for (const auto& t : f) {
      const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({ab, t[1], bc});
      next.push_back({ca, bc, t[2]});
      next.push_back({ab, bc, ca});
    }
    f.swap(next);
  }
  std::uniform_real_distribution<double> r(radius * (1.0 - roughness), radius);
  for (Vec3& p : v) p = center + p.normalized() * r(rng);
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

TriangleMesh box_mesh(const Vec3& lo, const Vec3& hi) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k)
    v.emplace_back((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
  // Outward, counter-clockwise seen from outside.
  std::vector<TriangleMesh::Face> f = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                       {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

TriangleMesh prism_mesh(const std::vector<Vec2>& profile, const std::vector<std::array<std::uint32_t, 3>>& cap, double length) {
  const auto n = static_cast<std::uint32_t>(profile.size());
  std::vector<Vec3> v;
  for (const Vec2& p : profile) v.emplace_back(p.x(), p.y(), 0.0);
  for (const Vec2& p : profile) v.emplace_back(p.x(), p.y(), length);
  std::vector<TriangleMesh::Face> f;
  for (const auto& t : cap) {
    f.push_back({t[0] + n, t[1] + n, t[2] + n});  // top, seen from +z
    f.push_back({t[0], t[2], t[1]});              // bottom, reversed
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    f.push_back({i, j, j + n});
    f.push_back({i, j + n, i + n});
  }
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

TriangleMesh u_channel_mesh() {
  const std::vector<Vec2> p = {{0, 0}, {10, 0}, {10, 10}, {8, 10}, {8, 2}, {2, 2}, {2, 10}, {0, 10}};
  return prism_mesh(p, {{0, 1, 4}, {0, 4, 5}, {1, 2, 3}, {1, 3, 4}, {0, 5, 6}, {0, 6, 7}}, 20.0);
}

TriangleMesh random_soup(Rng& rng, int n, double extent, double size) {
  std::uniform_real_distribution<double> pos(-extent, extent), off(-size, size);
  std::vector<Vec3> v;
  std::vector<TriangleMesh::Face> f;
  for (int i = 0; i < n; ++i) {
    const Vec3 c(pos(rng), pos(rng), pos(rng));
    const auto base = static_cast<std::uint32_t>(v.size());
    for (int k = 0; k < 3; ++k) v.push_back(c + Vec3(off(rng), off(rng), off(rng)));
    f.push_back({base, base + 1, base + 2});
  }
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

RigidTransform random_pose(Rng& rng, double range) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> t(-range, range);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return {q.toRotationMatrix(), Vec3(t(rng), t(rng), t(rng))};
}

std::shared_ptr<const TriangleMesh> share(TriangleMesh mesh) {
  return std::make_shared<const TriangleMesh>(std::move(mesh));
}

std::string shared_data(const std::string& relative) { return std::string(GATEKEEPER_SHARED_DATA) + "/" + relative; }

TriangleMesh cylinder_mesh(double radius, double length, int sides) {
  std::vector<Vec3> v;
  std::vector<TriangleMesh::Face> f;
  for (int i = 0; i < sides; ++i) {
    const double t = 2.0 * 3.14159265358979323846 * i / sides;
    v.emplace_back(radius * std::cos(t), radius * std::sin(t), 0.0);
    v.emplace_back(radius * std::cos(t), radius * std::sin(t), length);
  }
  const auto c = static_cast<std::uint32_t>(v.size());
  v.emplace_back(0, 0, 0);
  v.emplace_back(0, 0, length);
  for (int i = 0; i < sides; ++i) {
    const auto a0 = static_cast<std::uint32_t>(2 * i), a1 = a0 + 1;
    const auto b0 = static_cast<std::uint32_t>(2 * ((i + 1) % sides)), b1 = b0 + 1;
    f.push_back({a0, b0, b1});
    f.push_back({a0, b1, a1});
    f.push_back({c, b0, a0});
    f.push_back({c + 1, a1, b1});
  }
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}


}  // namespace gk::testing
