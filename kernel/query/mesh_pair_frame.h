// Two posed meshes seen from mesh A's frame: the relative transform of B, and the node tests every
// dual-tree traversal shares. B's vertices are transformed only where a leaf pair needs them.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/mesh/oriented_box.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/tolerances.h"
#include "kernel/query/triangle_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace gk {

// Work done by a query (seed 004 counts these as the measure of work).
struct QueryStats {
  long long node_pairs_tested = 0;
  long long triangle_pairs_tested = 0;
  // A triangle bounded against the other side's leaf (box and slab) before its pairs are measured:
  // bounding-volume tests too, one triangle's box at a time.
  long long triangle_node_tests = 0;
  QueryStats& operator+=(const QueryStats& o) {
    node_pairs_tested += o.node_pairs_tested;
    triangle_pairs_tested += o.triangle_pairs_tested;
    triangle_node_tests += o.triangle_node_tests;
    return *this;
  }
};

class MeshPairFrame {
 public:
  // Fails when a pose is not a finite rigid motion.
  static Result<MeshPairFrame> make(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                    const RigidTransform& pose_b) {
    // Each pose's distance from orthonormal is computed once: for the check and for the slack.
    const double off_a = pose_a.is_finite() ? pose_a.off_orthonormality() : 0.0;
    const double off_b = pose_b.is_finite() ? pose_b.off_orthonormality() : 0.0;
    if (!pose_a.is_finite() || !pose_a.is_rigid_given(off_a))
      return invalid_argument("pose_a", "not a finite rigid transform (orthonormal rotation, det +1)");
    if (!pose_b.is_finite() || !pose_b.is_rigid_given(off_b))
      return invalid_argument("pose_b", "not a finite rigid transform (orthonormal rotation, det +1)");
    return MeshPairFrame(a, pose_a, b, pose_b, off_a, off_b);
  }

  const MeshBvh& a() const { return *a_; }
  const MeshBvh& b() const { return *b_; }
  const RigidTransform& pose_a() const { return pose_a_; }
  const RigidTransform& b_in_a() const { return b_in_a_; }

  bool is_leaf_a(int n) const { return na_[n].is_leaf(); }
  bool is_leaf_b(int n) const { return nb_[n].is_leaf(); }
  int first_child_a(int n) const { return n + 1; }
  int second_child_a(int n) const { return na_[n].second_child(); }
  int first_child_b(int n) const { return n + 1; }
  int second_child_b(int n) const { return nb_[n].second_child(); }
  // Leaf triangle range [begin, end] inclusive, in tree order.
  int begin_a(int n) const { return na_[n].first_triangle(); }
  int end_a(int n) const { return na_[n].last_triangle(); }
  int begin_b(int n) const { return nb_[n].first_triangle(); }
  int end_b(int n) const { return nb_[n].last_triangle(); }

  // Size measure used to decide which node of a pair to split: the larger one.
  float size_a(int n) const { return na_[n].size(); }
  float size_b(int n) const { return nb_[n].size(); }

  // From now on nodes_lower_bound and slabs_separate measure the gap along each node's slab
  // normal, for the meshes large enough to have slabs (fits them on their first use).
  void use_slabs() {
    sa_ = a_->node_slabs();
    sb_ = b_->node_slabs();
  }

  // Separating-axis test of node boxes, conservative by the rounding slack.
  bool nodes_overlap(int node_a, int node_b, double margin = 0.0) const {
    const BvhNode& a = na_[node_a];
    const BvhNode& b = nb_[node_b];
    return boxes_overlap(a.center(), a.half_extent(), b_in_a_.apply(b.center()), b_in_a_.rotation, abs_r_, b.half_extent(),
                         slack_ + margin);
  }

  // True when no triangle of leaf_a can meet node_b's box: each triangle and the box projected on
  // the triangle's normal are apart. Any direction is a valid axis, so a rounded normal costs
  // tightness, never correctness; the slack (scaled by the axis' length) covers the dot products'
  // rounding, and a degenerate triangle (zero normal) never counts as missing. This keeps a large
  // flat triangle (a conveyor's top) from opening every node of a dense mesh driven into it.
  bool leaf_a_misses_node_b(int leaf_a, int node_b) const {
    return leaf_misses_box(*a_, na_[leaf_a], b_in_a_, nb_[node_b]);
  }
  bool leaf_b_misses_node_a(int leaf_b, int node_a) const {
    return leaf_misses_box(*b_, nb_[leaf_b], a_in_b_, na_[node_a]);
  }

  // A lower bound of the distance between anything in node_a and anything in node_b: the largest
  // of the box-to-box gaps measured along A's axes, along B's axes and along the line of centres,
  // and of the gaps along the nodes' slab normals. The cheapest come first: once one of them puts
  // the pair at least `cutoff` apart (a caller's best distance so far, beyond which it drops the
  // pair) that is returned without the rest - a bound still, and the pair is dropped all the same.
  double nodes_lower_bound(int node_a, int node_b, double cutoff = std::numeric_limits<double>::infinity()) const {
    const BvhNode& a = na_[node_a];
    const BvhNode& b = nb_[node_b];
    const Vec3 ea = a.half_extent();
    const Vec3 eb = b.half_extent();
    const Vec3 d = b_in_a_.apply(b.center()) - a.center();
    const double reach = cutoff + slack_;  // a component at least this far drops the pair
    const Vec3 gap_a = (d.cwiseAbs() - ea - abs_r_ * eb).cwiseMax(0.0);
    double squared = gap_a.squaredNorm();
    if (squared >= reach * reach) return std::sqrt(squared) - slack_;
    const Vec3 d_in_b = b_in_a_.rotation.transpose() * d;
    const Vec3 gap_b = (d_in_b.cwiseAbs() - abs_r_.transpose() * ea - eb).cwiseMax(0.0);
    squared = std::max(squared, gap_b.squaredNorm());
    double bound = std::sqrt(squared);
    if (bound >= reach) return bound - slack_;
    // Along the line of centres: |d| minus how far each node reaches towards the other, by box and
    // slab together (tightest at rotations where the boxes' own axes are oblique to each other).
    const double length = d.norm();
    if (length > 0.0) {
      const Vec3 towards_b = d / length;
      const Span reach_a = span_of(towards_b, sa_ ? &sa_[node_a] : nullptr, ea);
      const Span reach_b = span_of(d_in_b / length, sb_ ? &sb_[node_b] : nullptr, eb);
      bound = std::max(bound, length + reach_b.lo - reach_a.hi);
      if (bound >= reach) return bound - slack_;
    }
    bound = std::max(bound, slab_gap(node_a, node_b, d));
    return std::max(bound - slack_, 0.0);
  }

  // True when the nodes' slabs (in use and fitted) put them apart by more than the rounding slack:
  // no triangle of one can meet a triangle of the other. Asked after the boxes overlap.
  // Only a slab clearly thinner than its box along its normal is worth the test: near the roots of
  // closed meshes the slabs are as thick as the boxes and the test would cost without ever
  // separating (it made the quickest random-pose collisions 25 % slower).
  bool slabs_separate(int node_a, int node_b) const {
    const bool flat_a = sa_ != nullptr && is_flat(sa_[node_a], na_[node_a]);
    const bool flat_b = sb_ != nullptr && is_flat(sb_[node_b], nb_[node_b]);
    if (!flat_a && !flat_b) return false;
    const Vec3 d = b_in_a_.apply(nb_[node_b].center()) - na_[node_a].center();
    return slab_gap(node_a, node_b, d) > slack_;
  }

  // The box bound, tightened when exactly one side is a leaf: the leaf's triangles against the
  // other node's bounding sphere. This keeps a small, dense mesh from being opened in full under
  // every large triangle whose box comes near it. `cutoff` as for nodes_lower_bound.
  double pair_lower_bound(int node_a, int node_b, double cutoff = std::numeric_limits<double>::infinity()) const {
    const double box = nodes_lower_bound(node_a, node_b, cutoff);
    if (box >= cutoff) return box;
    const bool leaf_a = is_leaf_a(node_a), leaf_b = is_leaf_b(node_b);
    if (leaf_a == leaf_b) return box;
    double nearest = std::numeric_limits<double>::infinity();
    double radius, leaf_reach;
    if (leaf_a) {
      const Vec3 c = b_in_a_.apply(nb_[node_b].center());
      radius = nb_[node_b].half_extent().norm();
      leaf_reach = na_[node_a].half_extent().norm();
      for (int k = begin_a(node_a); k <= end_a(node_a); ++k)
        nearest = std::min(nearest, (closest_point_on_triangle(c, a_->ordered_triangle(k)) - c).norm());
    } else {
      const Vec3 c = a_in_b_.apply(na_[node_a].center());
      radius = na_[node_a].half_extent().norm();
      leaf_reach = nb_[node_b].half_extent().norm();
      for (int k = begin_b(node_b); k <= end_b(node_b); ++k)
        nearest = std::min(nearest, (closest_point_on_triangle(c, b_->ordered_triangle(k)) - c).norm());
    }
    // A NaN (never expected, but a bound must not prune on one) counts as no bound.
    if (!(nearest == nearest)) return box;
    // The closest point's own rounding is taken off (kClosestPointRoundingRelative).
    const double rounding = tolerances::kClosestPointRoundingRelative * (nearest + radius + leaf_reach);
    return std::max(box, nearest - radius - slack_ - rounding);
  }

  // A lower bound of the distance between a triangle (given in the node's mesh frame) and anything
  // in that node: the gap between the triangle's box and the node's, and along the node's slab
  // normal when slabs are in use. Lets a leaf pair skip the triangles that cannot come closer
  // than the best distance found so far.
  // `cutoff` as for nodes_lower_bound.
  double triangle_to_node_a_bound(const Triangle& t_in_a, int node_a, double cutoff = std::numeric_limits<double>::infinity()) const {
    return triangle_to_node_bound(t_in_a, na_[node_a], sa_ ? &sa_[node_a] : nullptr, cutoff);
  }
  double triangle_to_node_b_bound(const Triangle& t_in_b, int node_b, double cutoff = std::numeric_limits<double>::infinity()) const {
    return triangle_to_node_bound(t_in_b, nb_[node_b], sb_ ? &sb_[node_b] : nullptr, cutoff);
  }
  Triangle a_triangle_in_b(int ordered_a) const {
    const Triangle t = a_->ordered_triangle(ordered_a);
    return {a_in_b_.apply(t[0]), a_in_b_.apply(t[1]), a_in_b_.apply(t[2])};
  }

  Triangle b_triangle_in_a(int ordered_b) const {
    const Triangle t = b_->ordered_triangle(ordered_b);
    return {b_in_a_.apply(t[0]), b_in_a_.apply(t[1]), b_in_a_.apply(t[2])};
  }

  Vec3 to_world(const Vec3& p_in_a) const { return pose_a_.apply(p_in_a); }

 private:
  MeshPairFrame(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b,
                double off_orthonormal_a, double off_orthonormal_b)
      : a_(&a), b_(&b), na_(a.nodes()), nb_(b.nodes()), pose_a_(pose_a),
        // A at the origin unrotated (the usual case): B's pose is the relative one, exactly.
        b_in_a_(pose_a.rotation == Mat3::Identity() && pose_a.translation == Vec3::Zero()
                    ? pose_b
                    : pose_a.inverse_given(off_orthonormal_a) * pose_b) {
    abs_r_ = abs_with_epsilon(b_in_a_.rotation);
    // With A unrotated (the usual case), the relative rotation is B's, exactly.
    const double off_orthonormal = pose_a.rotation == Mat3::Identity() ? off_orthonormal_b : b_in_a_.off_orthonormality();
    a_in_b_ = b_in_a_.inverse_given(off_orthonormal);
    // Rounding in a box test is relative to the magnitude of the coordinates involved.
    const Aabb ra = a.root_bounds(), rb = b.root_bounds();
    const double scale = std::max({ra.min.cwiseAbs().maxCoeff(), ra.max.cwiseAbs().maxCoeff(),
                                   b_in_a_.translation.cwiseAbs().maxCoeff() + rb.min.cwiseAbs().maxCoeff() +
                                       rb.max.cwiseAbs().maxCoeff(), 1.0});
    // A pose's rotation is accepted within kRotationOrthonormality of orthonormal (a rotation
    // written with 9 decimals), while the node tests assume an orthonormal R (a transpose for the
    // inverse, unit axes): their error is then about |R^T R - I| times the coordinates, which the
    // slack must cover as well, or a box lands beside where its triangles are.
    slack_ = (tolerances::kBoxSlackRelative + 16.0 * off_orthonormal) * scale;
  }

  // The gap along A's slab normal (in A's frame) and along B's (in B's frame), for the meshes that
  // have slabs: each side spans its own slab there, the other side what its box and (if it has
  // one) its slab together allow. d: B's centre minus A's, in A's frame. 0 without slabs.
  double slab_gap(int node_a, int node_b, const Vec3& d) const {
    const NodeSlab* slab_a = sa_ ? &sa_[node_a] : nullptr;
    const NodeSlab* slab_b = sb_ ? &sb_[node_b] : nullptr;
    double gap = 0.0;
    if (slab_a != nullptr) {
      // Positions relative to A's centre: A spans [lo, hi]; B's centre sits at na . d.
      const Vec3 na = slab_a->direction();
      gap = interval_gap(slab_a->lo, slab_a->hi, na.dot(d), span_of(b_in_a_.rotation.transpose() * na, slab_b, nb_[node_b].half_extent()));
    }
    if (slab_b != nullptr) {
      // Positions relative to B's centre: B spans [lo, hi]; A's centre sits at -nb_in_a . d.
      const Vec3 nb_in_a = b_in_a_.rotation * slab_b->direction();
      gap = std::max(gap, interval_gap(slab_b->lo, slab_b->hi, -nb_in_a.dot(d), span_of(nb_in_a, slab_a, na_[node_a].half_extent())));
    }
    // Gaps measured along normals of length up to kSlabNormalMaxLength.
    return gap / kSlabNormalMaxLength;
  }

  // The slab is at most half as thick as the node's box along the slab's normal.
  static bool is_flat(const NodeSlab& slab, const BvhNode& node) {
    const float box_thickness = 2.0f * (std::fabs(slab.normal[0]) * (node.hi[0] - node.lo[0]) +
                                        std::fabs(slab.normal[1]) * (node.hi[1] - node.lo[1]) +
                                        std::fabs(slab.normal[2]) * (node.hi[2] - node.lo[2])) * 0.5f;
    return slab.hi - slab.lo < 0.5f * box_thickness;
  }

  // How far a node reaches along the unit axis u (in the node's own frame), either way from its
  // centre: by box and slab together (reach_along, kernel/bvh/node_slabs.h), or by the box alone.
  using Span = SlabReach;
  static Span span_of(const Vec3& u, const NodeSlab* slab, const Vec3& e) {
    if (slab != nullptr) return reach_along(u, *slab, e);
    const double box = u.cwiseAbs().dot(e);
    return {-box, box};
  }

  double triangle_to_node_bound(const Triangle& t, const BvhNode& node, const NodeSlab* slab, double cutoff) const {
    const Vec3 tmin = t[0].cwiseMin(t[1]).cwiseMin(t[2]), tmax = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
    double bound = (tmin - node.upper()).cwiseMax(node.lower() - tmax).cwiseMax(0.0).norm();
    if (slab != nullptr && bound - slack_ < cutoff) {
      const Vec3 n = slab->direction();
      const Vec3 c = node.center();
      const double s0 = n.dot(t[0] - c), s1 = n.dot(t[1] - c), s2 = n.dot(t[2] - c);
      const double gap = std::max({std::min({s0, s1, s2}) - static_cast<double>(slab->hi),
                                   static_cast<double>(slab->lo) - std::max({s0, s1, s2}), 0.0});
      bound = std::max(bound, gap / kSlabNormalMaxLength);
    }
    return std::max(bound - slack_, 0.0);
  }

  // The gap between [lo, hi] and the span placed at `offset` along the same axis (0 if they meet).
  static double interval_gap(float lo, float hi, double offset, const Span& other) {
    return std::max({offset + other.lo - static_cast<double>(hi), static_cast<double>(lo) - (offset + other.hi), 0.0});
  }

  // Every triangle of `leaf` (of `leaf_mesh`) is apart from `box`, a node of the other mesh whose
  // frame `box_in_leaf` maps into the leaf's.
  bool leaf_misses_box(const MeshBvh& leaf_mesh, const BvhNode& leaf, const RigidTransform& box_in_leaf, const BvhNode& box) const {
    const Vec3 c = box_in_leaf.apply(box.center());
    const Vec3 e = box.half_extent();
    for (int k = leaf.first_triangle(); k <= leaf.last_triangle(); ++k)
      if (!triangle_misses_box(leaf_mesh.ordered_triangle(k), c, box_in_leaf.rotation, e)) return false;
    return true;
  }

  // The triangle and the box (centre c, axes the columns of `axes`, half extents e, all in the
  // triangle's frame) are apart along the triangle's normal.
  bool triangle_misses_box(const Triangle& t, const Vec3& c, const Mat3& axes, const Vec3& e) const {
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    const double s0 = n.dot(t[0]), s1 = n.dot(t[1]), s2 = n.dot(t[2]);
    const double lo = std::min({s0, s1, s2}), hi = std::max({s0, s1, s2});
    const double centre = n.dot(c);
    const double radius = (axes.transpose() * n).cwiseAbs().dot(e);
    const double tol = slack_ * n.lpNorm<1>();
    return centre - radius > hi + tol || centre + radius < lo - tol;
  }

  const MeshBvh* a_;
  const MeshBvh* b_;
  const BvhNode* na_;
  const BvhNode* nb_;
  const NodeSlab* sa_ = nullptr;  // set by use_slabs()
  const NodeSlab* sb_ = nullptr;
  RigidTransform pose_a_;
  RigidTransform b_in_a_;
  RigidTransform a_in_b_;
  Mat3 abs_r_;
  double slack_ = 0.0;
};

}  // namespace gk
