#include "kernel/mesh/convex_hull.h"

#include "kernel/predicates/exact_predicates.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace gk {
namespace {

struct HullFace {
  std::array<int, 3> v;      // counter-clockwise seen from outside
  std::vector<int> outside;  // points strictly outside this face (exact), not yet on the hull
  bool alive = true;
};

std::uint64_t edge_key(int from, int to) { return (std::uint64_t(std::uint32_t(from)) << 32) | std::uint32_t(to); }

class Quickhull {
 public:
  explicit Quickhull(const std::vector<Vec3>& p) : p_(p) {}

  Result<HullPolytope> run() {
    if (p_.size() < 4) return invalid_argument("points", "a hull needs at least four points");
    for (std::size_t i = 0; i < p_.size(); ++i)
      if (!p_[i].allFinite()) return invalid_argument("points[" + std::to_string(i) + "]", "not finite");
    std::array<int, 4> tet;
    if (!initial_tetrahedron(tet)) return invalid_argument("points", "all points are coplanar: the hull has no volume");
    // Orient the tetrahedron so that every face looks away from the fourth corner.
    if (exact::orient3d(p_[tet[0]], p_[tet[1]], p_[tet[2]], p_[tet[3]]) > 0) std::swap(tet[1], tet[2]);
    add_face(tet[0], tet[1], tet[2]);
    add_face(tet[0], tet[3], tet[1]);
    add_face(tet[1], tet[3], tet[2]);
    add_face(tet[2], tet[3], tet[0]);
    std::vector<int> all;
    for (int i = 0; i < static_cast<int>(p_.size()); ++i)
      if (i != tet[0] && i != tet[1] && i != tet[2] && i != tet[3]) all.push_back(i);
    assign(all, 0, static_cast<int>(faces_.size()));

    // Faces are appended as the hull grows, so one pass over the growing list visits every face
    // that ever has outside points; a face that dies is skipped.
    for (std::size_t f = 0; f < faces_.size(); ++f) {
      if (!faces_[f].alive || faces_[f].outside.empty()) continue;
      add_point(static_cast<int>(f), farthest(static_cast<int>(f)));
    }
    return to_polytope();
  }

 private:
  bool initial_tetrahedron(std::array<int, 4>& tet) const {
    // Extreme points along x, then the farthest from them, then a non-coplanar fourth.
    int lo = 0, hi = 0;
    for (int i = 1; i < static_cast<int>(p_.size()); ++i) {
      if (p_[i].x() < p_[lo].x()) lo = i;
      if (p_[i].x() > p_[hi].x()) hi = i;
    }
    if (lo == hi) {
      for (int i = 0; i < static_cast<int>(p_.size()); ++i)
        if (p_[i] != p_[lo]) hi = i;
      if (lo == hi) return false;
    }
    int third = -1;
    double best = -1.0;
    const Vec3 axis = p_[hi] - p_[lo];
    for (int i = 0; i < static_cast<int>(p_.size()); ++i) {
      const double d = axis.cross(p_[i] - p_[lo]).squaredNorm();
      if (d > best && !exact::collinear(p_[lo], p_[hi], p_[i])) {
        best = d;
        third = i;
      }
    }
    if (third < 0) return false;
    int fourth = -1;
    best = -1.0;
    const Vec3 n = axis.cross(p_[third] - p_[lo]);
    for (int i = 0; i < static_cast<int>(p_.size()); ++i) {
      const double d = std::fabs(n.dot(p_[i] - p_[lo]));
      if (d > best && exact::orient3d(p_[lo], p_[hi], p_[third], p_[i]) != 0) {
        best = d;
        fourth = i;
      }
    }
    if (fourth < 0) return false;
    tet = {lo, hi, third, fourth};
    return true;
  }

  int add_face(int a, int b, int c) {
    HullFace f;
    f.v = {a, b, c};
    faces_.push_back(std::move(f));
    const int id = static_cast<int>(faces_.size()) - 1;
    edge_to_face_[edge_key(a, b)] = id;
    edge_to_face_[edge_key(b, c)] = id;
    edge_to_face_[edge_key(c, a)] = id;
    return id;
  }

  bool sees(int face, int point) const {
    const auto& v = faces_[face].v;
    return exact::orient3d(p_[v[0]], p_[v[1]], p_[v[2]], p_[point]) > 0;
  }

  void assign(const std::vector<int>& points, int first_face, int end_face) {
    for (int q : points) {
      for (int f = first_face; f < end_face; ++f) {
        if (faces_[f].alive && sees(f, q)) {
          faces_[f].outside.push_back(q);
          break;
        }
      }
    }
  }

  int farthest(int face) const {
    const auto& v = faces_[face].v;
    const Vec3 n = (p_[v[1]] - p_[v[0]]).cross(p_[v[2]] - p_[v[0]]);
    int best = faces_[face].outside.front();
    double best_d = -1.0;
    for (int q : faces_[face].outside) {
      const double d = n.dot(p_[q] - p_[v[0]]);
      if (d > best_d) {
        best_d = d;
        best = q;
      }
    }
    return best;
  }

  void add_point(int start, int eye) {
    // Every face the eye sees, found by flood fill from the start face.
    std::vector<int> visible = {start};
    std::vector<char> is_visible(faces_.size(), 0);
    is_visible[start] = 1;
    for (std::size_t i = 0; i < visible.size(); ++i) {
      const auto& v = faces_[visible[i]].v;
      for (int e = 0; e < 3; ++e) {
        const int twin = edge_to_face_.at(edge_key(v[(e + 1) % 3], v[e]));
        if (!is_visible[twin] && faces_[twin].alive && sees(twin, eye)) {
          is_visible[twin] = 1;
          visible.push_back(twin);
        }
      }
    }
    // Horizon: edges of visible faces whose twin is not visible; each gets a new face to the eye.
    std::vector<int> orphans;
    std::vector<std::array<int, 2>> horizon;
    for (int f : visible) {
      const auto& v = faces_[f].v;
      for (int e = 0; e < 3; ++e) {
        const int a = v[e], b = v[(e + 1) % 3];
        const int twin = edge_to_face_.at(edge_key(b, a));
        if (!is_visible[twin]) horizon.push_back({a, b});
      }
      faces_[f].alive = false;
      for (int q : faces_[f].outside)
        if (q != eye) orphans.push_back(q);
      faces_[f].outside.clear();
    }
    const int first_new = static_cast<int>(faces_.size());
    for (const auto& edge : horizon) add_face(edge[0], edge[1], eye);
    assign(orphans, first_new, static_cast<int>(faces_.size()));
  }

  HullPolytope to_polytope() const {
    std::vector<int> remap(p_.size(), -1);
    HullPolytope out;
    std::vector<Vec3>& vertices = out.corners;
    std::vector<std::array<std::uint32_t, 3>>& faces = out.faces;
    for (const HullFace& f : faces_) {
      if (!f.alive) continue;
      std::array<std::uint32_t, 3> face;
      for (int k = 0; k < 3; ++k) {
        if (remap[f.v[k]] < 0) {
          remap[f.v[k]] = static_cast<int>(vertices.size());
          vertices.push_back(p_[f.v[k]]);
        }
        face[k] = static_cast<std::uint32_t>(remap[f.v[k]]);
      }
      faces.push_back(face);
    }
    return out;
  }

  const std::vector<Vec3>& p_;
  std::vector<HullFace> faces_;
  std::unordered_map<std::uint64_t, int> edge_to_face_;
};

}  // namespace

Result<HullPolytope> convex_hull_polytope(const std::vector<Vec3>& points) { return Quickhull(points).run(); }

Result<TriangleMesh> convex_hull(const std::vector<Vec3>& points) {
  auto hull = convex_hull_polytope(points);
  if (!hull.ok()) return hull.error();
  return TriangleMesh::create(std::move(hull.value().corners), std::move(hull.value().faces));
}

}  // namespace gk
