#include "kernel/bvh/binned_sah_builder.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace gk {
namespace {

// A triangle while the tree is built: its float box and mesh index, 32 bytes, moved as the
// triangles are partitioned (the array is streamed, never gathered through an index). Its
// "centroid" is lo + hi, the box centre doubled: binning only needs an order-preserving measure.
struct Prim {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::int32_t key;  // BuildKeys: triangles of different keys part below its node size
  float c(int a) const { return lo[a] + hi[a]; }
};

struct Box {
  float lo[3] = {INFINITY, INFINITY, INFINITY};
  float hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  void grow(const float l[3], const float h[3]) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], l[a]);
      hi[a] = std::max(hi[a], h[a]);
    }
  }
  void grow(const Box& b) { grow(b.lo, b.hi); }
  float half_area() const {
    if (!(hi[0] >= lo[0])) return 0.0f;
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x * y + y * z + z * x;
  }
};

// More bins find better splits in large nodes; small nodes are cheaper with fewer.
constexpr int kBins = 16;

struct Builder {
  std::vector<Prim>& prims;
  std::vector<BvhNode>& nodes;
  int leaf_size;
  std::size_t key_split_at;  // 0: no keys
  int depth = 0;

  // With keys, a node of at most key_split_at triangles of several keys: where its keys part,
  // half of them from the other half in the order of their triangles' mean centroid along the
  // axis where those means spread most (a node of many small groups stays shallow); else end.
  std::size_t key_split(std::size_t begin, std::size_t end) {
    if (end - begin > key_split_at) return end;
    const std::int32_t first = prims[begin].key;
    bool mixed = false;
    for (std::size_t i = begin + 1; i < end && !mixed; ++i) mixed = prims[i].key != first;
    if (!mixed) return end;
    struct KeyMean {
      std::int32_t key;
      double sum[3];
      std::size_t n;
    };
    std::vector<KeyMean> keys;
    for (std::size_t i = begin; i < end; ++i) {
      auto at = std::find_if(keys.begin(), keys.end(), [&](const KeyMean& k) { return k.key == prims[i].key; });
      if (at == keys.end()) at = keys.insert(keys.end(), KeyMean{prims[i].key, {0.0, 0.0, 0.0}, 0});
      for (int a = 0; a < 3; ++a) at->sum[a] += prims[i].c(a);
      ++at->n;
    }
    int axis = 0;
    double widest = -1.0;
    for (int a = 0; a < 3; ++a) {
      double lo = INFINITY, hi = -INFINITY;
      for (const KeyMean& k : keys) {
        lo = std::min(lo, k.sum[a] / static_cast<double>(k.n));
        hi = std::max(hi, k.sum[a] / static_cast<double>(k.n));
      }
      if (hi - lo > widest) {
        widest = hi - lo;
        axis = a;
      }
    }
    std::sort(keys.begin(), keys.end(), [&](const KeyMean& l, const KeyMean& r) {
      const double ml = l.sum[axis] / static_cast<double>(l.n), mr = r.sum[axis] / static_cast<double>(r.n);
      return ml != mr ? ml < mr : l.key < r.key;
    });
    keys.resize(keys.size() / 2);
    const auto split = std::stable_partition(prims.begin() + static_cast<std::ptrdiff_t>(begin), prims.begin() + static_cast<std::ptrdiff_t>(end),
                                             [&](const Prim& p) {
                                               return std::any_of(keys.begin(), keys.end(), [&](const KeyMean& k) { return k.key == p.key; });
                                             });
    return static_cast<std::size_t>(split - prims.begin());
  }

  void make_leaf(int node, std::size_t begin, std::size_t end) {
    nodes[static_cast<std::size_t>(node)].index = static_cast<std::int32_t>(begin);
    nodes[static_cast<std::size_t>(node)].count = static_cast<std::int32_t>(end - begin);
  }

  // bounds: the triangles' boxes; centres: their centroids' box. Both known from the parent's bins.
  int build(std::size_t begin, std::size_t end, const Box& bounds, const Box& centres, int level) {
    depth = std::max(depth, level);
    const int node = static_cast<int>(nodes.size());
    BvhNode n{};
    std::copy(bounds.lo, bounds.lo + 3, n.lo);
    std::copy(bounds.hi, bounds.hi + 3, n.hi);
    nodes.push_back(n);
    const std::size_t count = end - begin;
    const std::size_t by_key = level >= kMaxBvhDepth ? end : key_split(begin, end);
    if (by_key == end && (count <= static_cast<std::size_t>(leaf_size) || level >= kMaxBvhDepth)) {
      make_leaf(node, begin, end);
      return node;
    }
    std::size_t mid;
    Box left_bounds, left_centres, right_bounds, right_centres;
    if (by_key != end) {
      mid = by_key;
      measure_sides(begin, mid, end, left_bounds, left_centres, right_bounds, right_centres);
    } else {
      split_by_area(begin, end, centres, mid, left_bounds, left_centres, right_bounds, right_centres);
    }
    build(begin, mid, left_bounds, left_centres, level + 1);
    const int right = build(mid, end, right_bounds, right_centres, level + 1);
    nodes[static_cast<std::size_t>(node)].index = right;
    nodes[static_cast<std::size_t>(node)].count = 0;
    return node;
  }

  // The boxes of [begin, mid) and [mid, end), and of their centroids.
  void measure_sides(std::size_t begin, std::size_t mid, std::size_t end, Box& left_bounds, Box& left_centres, Box& right_bounds,
                     Box& right_centres) const {
    left_bounds = right_bounds = left_centres = right_centres = Box{};
    for (std::size_t i = begin; i < end; ++i) {
      (i < mid ? left_bounds : right_bounds).grow(prims[i].lo, prims[i].hi);
      const float pc[3] = {prims[i].c(0), prims[i].c(1), prims[i].c(2)};
      (i < mid ? left_centres : right_centres).grow(pc, pc);
    }
  }

  // The binned surface-area split of [begin, end) (partitioned in place at mid).
  void split_by_area(std::size_t begin, std::size_t end, const Box& centres, std::size_t& mid, Box& left_bounds, Box& left_centres,
                     Box& right_bounds, Box& right_centres) {
    const std::size_t count = end - begin;
    int axis = 0;
    float extent = centres.hi[0] - centres.lo[0];
    for (int a = 1; a < 3; ++a)
      if (centres.hi[a] - centres.lo[a] > extent) {
        extent = centres.hi[a] - centres.lo[a];
        axis = a;
      }
    if (!(extent > 0.0f)) {
      // Every centroid in one place: any halving is as good as another.
      mid = begin + count / 2;
      measure_sides(begin, mid, end, left_bounds, left_centres, right_bounds, right_centres);
    } else {
      const float origin = centres.lo[axis];
      // Slightly under kBins / extent, so the largest centroid still falls in the last bin.
      const float scale = static_cast<float>(kBins) * (1.0f - 1e-5f) / extent;
      auto bin_of = [&](const Prim& p) { return std::min(kBins - 1, static_cast<int>((p.c(axis) - origin) * scale)); };
      std::array<Box, kBins> bin_bounds, bin_centres;
      std::array<std::size_t, kBins> bin_count{};
      for (std::size_t i = begin; i < end; ++i) {
        const int b = std::max(0, bin_of(prims[i]));
        bin_bounds[b].grow(prims[i].lo, prims[i].hi);
        const float pc[3] = {prims[i].c(0), prims[i].c(1), prims[i].c(2)};
        bin_centres[b].grow(pc, pc);
        ++bin_count[b];
      }
      // Areas and counts right of each split, then the sweep from the left.
      std::array<float, kBins> right_area{};
      std::array<std::size_t, kBins> right_count{};
      Box acc;
      std::size_t acc_n = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.grow(bin_bounds[b]);
        acc_n += bin_count[b];
        right_area[b] = acc.half_area();
        right_count[b] = acc_n;
      }
      Box left;
      std::size_t left_n = 0;
      int best_split = -1;
      float best_cost = INFINITY;
      for (int b = 0; b < kBins - 1; ++b) {
        left.grow(bin_bounds[b]);
        left_n += bin_count[b];
        if (left_n == 0 || right_count[b + 1] == 0) continue;
        const float cost = left.half_area() * static_cast<float>(left_n) + right_area[b + 1] * static_cast<float>(right_count[b + 1]);
        if (cost < best_cost) {
          best_cost = cost;
          best_split = b;
        }
      }
      if (best_split < 0) best_split = 0;  // unreachable: the first and the last bins are both filled
      for (int b = 0; b < kBins; ++b) {
        (b <= best_split ? left_bounds : right_bounds).grow(bin_bounds[b]);
        (b <= best_split ? left_centres : right_centres).grow(bin_centres[b]);
      }
      const auto split = std::partition(prims.begin() + static_cast<std::ptrdiff_t>(begin), prims.begin() + static_cast<std::ptrdiff_t>(end),
                                        [&](const Prim& p) { return std::max(0, bin_of(p)) <= best_split; });
      mid = static_cast<std::size_t>(split - prims.begin());
      if (mid == begin || mid == end) {  // guards against a float surprise: halve instead
        mid = begin + count / 2;
        measure_sides(begin, mid, end, left_bounds, left_centres, right_bounds, right_centres);
      }
    }
  }
};

}  // namespace

void triangle_float_box(const Triangle& t, float lo[3], float hi[3]) {
  for (int a = 0; a < 3; ++a) {
    lo[a] = float_at_or_below(std::min({t[0][a], t[1][a], t[2][a]}));
    hi[a] = float_at_or_above(std::max({t[0][a], t[1][a], t[2][a]}));
  }
}

BuiltTree build_binned_sah(const TriangleMesh& mesh, int leaf_size, const BuildKeys& keys) {
  const std::size_t n = mesh.triangle_count();
  std::vector<Prim> prims(n);
  Box bounds, centres;
  for (std::size_t i = 0; i < n; ++i) {
    Prim& p = prims[i];
    triangle_float_box(mesh.triangle(i), p.lo, p.hi);
    p.id = static_cast<std::uint32_t>(i);
    p.key = keys.of_triangle ? (*keys.of_triangle)[i] : 0;
    bounds.grow(p.lo, p.hi);
    const float pc[3] = {p.c(0), p.c(1), p.c(2)};
    centres.grow(pc, pc);
  }
  BuiltTree tree;
  // A binary tree of leaves holding at least one triangle has fewer than 2n nodes; with bigger
  // leaves it has far fewer, so reserve for leaves about half full and let the vector grow.
  tree.nodes.reserve(std::max<std::size_t>(1, 2 * n / static_cast<std::size_t>(std::max(1, leaf_size / 2)) + 1));
  Builder builder{prims, tree.nodes, leaf_size, keys.of_triangle ? keys.split_at : 0};
  if (n > 0) builder.build(0, n, bounds, centres, 0);
  tree.nodes.shrink_to_fit();
  tree.depth = builder.depth + 1;
  tree.order.resize(n);
  for (std::size_t i = 0; i < n; ++i) tree.order[i] = prims[i].id;
  return tree;
}

}  // namespace gk
