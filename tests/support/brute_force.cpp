#include "tests/support/brute_force.h"

#include "kernel/query/triangle_distance.h"
#include "kernel/query/triangle_intersection.h"
#include "kernel/core/aabb.h"

#include <limits>
#include <vector>

namespace gk::testing {
namespace {

std::vector<Triangle> b_in_a_frame(const TriangleMesh& b, const RigidTransform& b_in_a) {
  std::vector<Triangle> out;
  out.reserve(b.triangle_count());
  for (std::size_t j = 0; j < b.triangle_count(); ++j) {
    const Triangle t = b.triangle(j);
    out.push_back({b_in_a.apply(t[0]), b_in_a.apply(t[1]), b_in_a.apply(t[2])});
  }
  return out;
}

Aabb box_of(const Triangle& t) {
  Aabb box;
  for (const Vec3& p : t) box.extend(p);
  return box;
}

// Apart along some axis by more than `gap` (with the margin for rounding).
bool boxes_apart_by_more_than(const Aabb& x, const Aabb& y, double gap) {
  const double limit = gap * (1.0 + 1e-12);
  return ((x.min - y.max).array() > limit).any() || ((y.min - x.max).array() > limit).any();
}

}  // namespace

namespace {

// Calls visit(i, ta, j, tb) for every pair whose triangles' boxes are not apart by more than
// gap() (asked per pair: a running minimum may shrink it); B's triangles in A's frame.
template <typename Gap, typename Visit>
void for_each_pair_not_apart(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                             const RigidTransform& pose_b, Gap gap, Visit visit) {
  const auto tb = b_in_a_frame(b, relative_transform(pose_a, pose_b));
  std::vector<Aabb> boxes_b;
  for (const Triangle& t : tb) boxes_b.push_back(box_of(t));
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const Triangle ta = a.triangle(i);
    const Aabb box_a = box_of(ta);
    for (std::size_t j = 0; j < tb.size(); ++j)
      if (!boxes_apart_by_more_than(box_a, boxes_b[j], gap())) visit(i, ta, j, tb[j]);
  }
}

std::pair<std::uint32_t, std::uint32_t> pair_of(std::size_t i, std::size_t j) {
  return {static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)};
}

}  // namespace

double brute_force_distance_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                   const RigidTransform& pose_b) {
  double best = std::numeric_limits<double>::infinity();
  for_each_pair_not_apart(a, pose_a, b, pose_b, [&] { return best; },
                          [&](std::size_t, const Triangle& ta, std::size_t, const Triangle& tb) {
                            best = std::min(best, triangle_distance(ta, tb).distance);
                          });
  return best;
}

PairSet brute_force_contacts_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                    const RigidTransform& pose_b) {
  // Boxes apart by anything (gap 0) hold triangles that cannot meet.
  PairSet out;
  for_each_pair_not_apart(a, pose_a, b, pose_b, [] { return 0.0; },
                          [&](std::size_t i, const Triangle& ta, std::size_t j, const Triangle& tb) {
                            if (triangles_intersect(ta, tb)) out.insert(pair_of(i, j));
                          });
  return out;
}

PairSet brute_force_pairs_within_pruned(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                        const RigidTransform& pose_b, double delta_mm) {
  PairSet out;
  for_each_pair_not_apart(a, pose_a, b, pose_b, [delta_mm] { return delta_mm; },
                          [&](std::size_t i, const Triangle& ta, std::size_t j, const Triangle& tb) {
                            if (triangle_distance(ta, tb).distance <= delta_mm) out.insert(pair_of(i, j));
                          });
  return out;
}

PairSet brute_force_contacts(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                             const RigidTransform& pose_b) {
  const auto tb = b_in_a_frame(b, relative_transform(pose_a, pose_b));
  PairSet out;
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const Triangle ta = a.triangle(i);
    for (std::size_t j = 0; j < tb.size(); ++j)
      if (triangles_intersect(ta, tb[j])) out.insert({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
  }
  return out;
}

double brute_force_distance(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                            const RigidTransform& pose_b) {
  const auto tb = b_in_a_frame(b, relative_transform(pose_a, pose_b));
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const Triangle ta = a.triangle(i);
    for (const Triangle& t : tb) best = std::min(best, triangle_distance(ta, t).distance);
  }
  return best;
}

PairSet brute_force_pairs_within(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                 const RigidTransform& pose_b, double delta_mm) {
  const auto tb = b_in_a_frame(b, relative_transform(pose_a, pose_b));
  PairSet out;
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const Triangle ta = a.triangle(i);
    for (std::size_t j = 0; j < tb.size(); ++j)
      if (triangle_distance(ta, tb[j]).distance <= delta_mm)
        out.insert({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
  }
  return out;
}

bool brute_force_any_within(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                            const RigidTransform& pose_b, double delta_mm) {
  const auto tb = b_in_a_frame(b, relative_transform(pose_a, pose_b));
  Aabb all_b;
  std::vector<Aabb> boxes_b;
  for (const Triangle& t : tb) {
    boxes_b.push_back(box_of(t));
    all_b.extend(boxes_b.back());
  }
  auto apart = [delta_mm](const Aabb& x, const Aabb& y) {
    return ((x.min - y.max).array() > delta_mm).any() || ((y.min - x.max).array() > delta_mm).any();
  };
  for (std::size_t i = 0; i < a.triangle_count(); ++i) {
    const Triangle ta = a.triangle(i);
    const Aabb box_a = box_of(ta);
    if (apart(box_a, all_b)) continue;
    for (std::size_t j = 0; j < tb.size(); ++j) {
      if (apart(box_a, boxes_b[j])) continue;
      if (triangles_intersect(ta, tb[j]) || triangle_distance(ta, tb[j]).distance <= delta_mm) return true;
    }
  }
  return false;
}

}  // namespace gk::testing
