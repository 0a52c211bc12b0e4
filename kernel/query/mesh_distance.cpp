#include "kernel/query/mesh_distance.h"

#include "kernel/query/triangle_distance.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

namespace gk {
namespace {

// Leaves up to this size get their triangles bounded one by one before their pairs (the default
// leaf holds 4; a larger leaf is measured pair by pair).
constexpr int kMaxLeafTriangles = 8;

struct BoundedPair {
  int a, b;
  double lower_bound;
};

// The bound of a node pair left out of a distance query (DistanceRequest::excluded).
constexpr double kOutOfReach = std::numeric_limits<double>::infinity();

// A search with this many node pairs queued is dealt out to a spare thread, when there is one.
constexpr std::size_t kSplitFrontier = 64;

const auto farther = [](const BoundedPair& x, const BoundedPair& y) { return x.lower_bound > y.lower_bound; };

// Each triangle of leaf_a bounded against leaf_b (box and slab) before its pairs, when the leaf
// holds at most kMaxLeafTriangles; of() is 0 (no bound) for a larger leaf's.
struct LeafABounds {
  LeafABounds(const MeshPairFrame& frame, int leaf_a, int leaf_b, double cutoff, QueryStats& stats)
      : first(frame.begin_a(leaf_a)), count(frame.end_a(leaf_a) - first + 1), bounded(count <= kMaxLeafTriangles) {
    if (!bounded) return;
    for (int i = 0; i < count; ++i)
      bound[static_cast<std::size_t>(i)] = frame.triangle_to_node_b_bound(frame.a_triangle_in_b(first + i), leaf_b, cutoff);
    stats.triangle_node_tests += count;
  }
  double of(int ordered_a) const { return bounded ? bound[static_cast<std::size_t>(ordered_a - first)] : 0.0; }

  std::array<double, kMaxLeafTriangles> bound{};
  int first, count;
  bool bounded;
};

// The best distance of two searches sharing one: lowered by either, read by both to prune.
void lower_shared(std::atomic<double>* shared, double value) {
  if (shared == nullptr) return;
  double now = shared->load(std::memory_order_relaxed);
  while (value < now && !shared->compare_exchange_weak(now, value, std::memory_order_relaxed)) {
  }
}

// One thread's best-first search: always expand the pair with the smallest lower bound, so the
// first leaves reached are the likely nearest and the bound tightens before the rest is looked at.
struct Search {
  Search(const MeshPairFrame& frame_, const MeshBvh& a_, const DistanceRequest& request_, std::vector<BoundedPair>& queue_,
         std::atomic<double>* shared_, double best_)
      : frame(frame_), a(a_), request(request_), queue(queue_), shared(shared_), best(best_) {}

  const MeshPairFrame& frame;
  const MeshBvh& a;
  const DistanceRequest& request;
  std::vector<BoundedPair>& queue;
  std::atomic<double>* shared;  // with a second search
  double best;          // the bound pairs are pruned at: this search's own best, or the other's
  double own_best = std::numeric_limits<double>::infinity();  // the distance of this search's own witnesses
  int best_ka = -1, best_kb = -1;
  Vec3 best_pa = Vec3::Zero(), best_pb = Vec3::Zero();
  QueryStats stats;
  bool stopped_early = false;
  bool stop_asked = false;  // the caller gave up

  void measure(int ka, int kb, const Triangle& tb) {
    if (request.excluded && request.excluded->triangles_settled(ka, kb)) return;
    ++stats.triangle_pairs_tested;
    const TriangleDistance d = triangle_distance(a.ordered_triangle(ka), tb, best);
    if (!d.bounded_only && d.distance < best) {
      if (request.excluded_pair &&
          request.excluded_pair(a.mesh_triangle_index(ka), frame.b().mesh_triangle_index(kb), frame.to_world(d.on_p), frame.to_world(d.on_q), d.distance))
        return;
      best = own_best = d.distance;
      best_ka = ka;
      best_kb = kb;
      best_pa = d.on_p;
      best_pb = d.on_q;
      lower_shared(shared, best);
    }
  }

  // Runs from `p` (have_next) and the queue until done, or until the queue holds `split_at` pairs
  // (returns false then, with p pushed back on the queue).
  bool run(BoundedPair p, bool have_next, std::size_t split_at) {
    std::uint64_t looked_at = 0;
    while (true) {
      if (!have_next) {
        if (queue.empty()) return true;
        std::pop_heap(queue.begin(), queue.end(), farther);
        p = queue.back();
        queue.pop_back();
      }
      have_next = false;
      if ((looked_at++ & kStopCheckMask) == 0 && request.stop && request.stop->stop_requested()) {
        stop_asked = true;
        return true;
      }
      if (shared) best = std::min(best, shared->load(std::memory_order_relaxed));
      if (p.lower_bound >= best) return true;  // every pair left is at least this far: done
      if (queue.size() >= split_at) {
        queue.push_back(p);
        std::push_heap(queue.begin(), queue.end(), farther);
        return false;
      }
      const bool leaf_a = frame.is_leaf_a(p.a), leaf_b = frame.is_leaf_b(p.b);
      if (leaf_a && leaf_b) {
        // Each triangle's bound against the other leaf first: a triangle that cannot come closer
        // than the best so far is skipped with all its pairs. (Queueing the pairs that remain by
        // their bounds measured fewer of them but cost more in the queue: 10-30 % slower.)
        const LeafABounds a_bounds(frame, p.a, p.b, best, stats);
        for (int kb = frame.begin_b(p.b); kb <= frame.end_b(p.b); ++kb) {
          const Triangle tb = frame.b_triangle_in_a(kb);
          ++stats.triangle_node_tests;
          if (frame.triangle_to_node_a_bound(tb, p.a, best) >= best) continue;
          for (int ka = a_bounds.first; ka <= frame.end_a(p.a); ++ka)
            if (a_bounds.of(ka) < best) measure(ka, kb, tb);
        }
        if (best_ka >= 0 && best < request.stop_below_mm) {
          stopped_early = true;
          return true;
        }
        continue;
      }
      // Split the larger node.
      BoundedPair near, far;
      const bool split_a = !leaf_a && (leaf_b || frame.size_a(p.a) >= frame.size_b(p.b));
      if (split_a) {
        near = {frame.first_child_a(p.a), p.b, 0.0};
        far = {frame.second_child_a(p.a), p.b, 0.0};
      } else {
        near = {p.a, frame.first_child_b(p.b), 0.0};
        far = {p.a, frame.second_child_b(p.b), 0.0};
      }
      // A pair wholly of excluded groups is left out as if out of reach.
      const auto excluded = [&](const BoundedPair& x) { return request.excluded && request.excluded->nodes_settled(x.a, x.b); };
      near.lower_bound = excluded(near) ? kOutOfReach : frame.pair_lower_bound(near.a, near.b, best);
      far.lower_bound = excluded(far) ? kOutOfReach : frame.pair_lower_bound(far.a, far.b, best);
      stats.node_pairs_tested += 2;
      if (far.lower_bound < near.lower_bound) std::swap(near, far);
      if (far.lower_bound < best) {
        queue.push_back(far);
        std::push_heap(queue.begin(), queue.end(), farther);
      }
      // The nearer child is taken straight on when no queued pair is nearer (the order is still
      // best-first, without a push and a pop for it).
      if (near.lower_bound < best) {
        if (queue.empty() || near.lower_bound <= queue.front().lower_bound) {
          p = near;
          have_next = true;
        } else {
          queue.push_back(near);
          std::push_heap(queue.begin(), queue.end(), farther);
        }
      }
    }
  }
};

// How far p lies from a node's box (0 inside it).
double distance_to_box(const Vec3& p, const BvhNode& node) {
  return (p - p.cwiseMax(node.lower()).cwiseMin(node.upper())).norm();
}

// The first settled pair within delta_mm, looked for nearest first: by the node pairs' lower
// bound, then by how far their boxes lie from the caller's hint (two curved surfaces in line
// contact, a pin pressed to one side of its hole, have every overlapping box pair at bound 0, and
// the pairs within reach along one line), else from each other's centres. None when no settled
// pair is within delta_mm.
std::optional<ProximityPair> settled_within(const MeshPairFrame& frame, const SettledPairs& settled, const std::optional<Vec3>& hint_in_a,
                                            double delta_mm, QueryStats& stats, const StopToken& stop, bool& stopped_early) {
  struct Queued {
    double bound, away;
    int a, b;
  };
  const auto later = [](const Queued& x, const Queued& y) { return std::tie(x.bound, x.away) > std::tie(y.bound, y.away); };
  const std::optional<Vec3> hint_in_b =
      hint_in_a ? std::optional<Vec3>(frame.b_in_a().inverse().apply(*hint_in_a)) : std::nullopt;
  std::vector<Queued> heap;
  const double cutoff = std::nextafter(delta_mm, 1e300);
  const auto push = [&](int na, int nb) {
    if (!settled.may_hold_settled(na, nb)) return;
    const double bound = frame.pair_lower_bound(na, nb, cutoff);
    if (bound > delta_mm) return;
    const double away = hint_in_a ? distance_to_box(*hint_in_a, frame.a().node(na)) + distance_to_box(*hint_in_b, frame.b().node(nb))
                                  : (frame.b_in_a().apply(frame.b().node(nb).center()) - frame.a().node(na).center()).norm();
    heap.push_back({bound, away, na, nb});
    std::push_heap(heap.begin(), heap.end(), later);
  };
  push(0, 0);
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const Queued q = heap.back();
    heap.pop_back();
    if ((stats.node_pairs_tested++ & kStopCheckMask) == 0 && stop.stop_requested()) {
      stopped_early = true;
      return std::nullopt;
    }
    const bool leaf_a = frame.is_leaf_a(q.a), leaf_b = frame.is_leaf_b(q.b);
    if (leaf_a && leaf_b) {
      // Each triangle's bound against the other leaf first, as in pairs_within below (two curved
      // surfaces a fraction of a millimetre apart, a pin in its hole, have their leaf boxes
      // overlapping all round).
      const LeafABounds a_bounds(frame, q.a, q.b, cutoff, stats);
      for (int kb = frame.begin_b(q.b); kb <= frame.end_b(q.b); ++kb) {
        const Triangle tb = frame.b_triangle_in_a(kb);
        ++stats.triangle_node_tests;
        if (frame.triangle_to_node_a_bound(tb, q.a, cutoff) > delta_mm) continue;
        for (int ka = a_bounds.first; ka <= frame.end_a(q.a); ++ka) {
          if (a_bounds.of(ka) > delta_mm) continue;
          if (!settled.triangles_settled(ka, kb) || settled.skip_triangles(ka, kb, false)) continue;
          ++stats.triangle_pairs_tested;
          const TriangleDistance d = triangle_distance(frame.a().ordered_triangle(ka), tb, cutoff);
          if (!d.bounded_only && d.distance <= delta_mm)
            return ProximityPair{frame.a().mesh_triangle_index(ka), frame.b().mesh_triangle_index(kb), d.distance, frame.to_world(d.on_p),
                                 frame.to_world(d.on_q)};
        }
      }
      continue;
    }
    if (!leaf_a && (leaf_b || frame.size_a(q.a) >= frame.size_b(q.b))) {
      push(frame.first_child_a(q.a), q.b);
      push(frame.second_child_a(q.a), q.b);
    } else {
      push(q.a, frame.first_child_b(q.b));
      push(q.a, frame.second_child_b(q.b));
    }
  }
  return std::nullopt;
}

}  // namespace

Result<DistanceResult> distance(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                const RigidTransform& pose_b, const DistanceRequest& request) {
  if (std::isnan(request.upper_bound_mm) || request.upper_bound_mm < 0.0)
    return invalid_argument("upper_bound_mm", "must be a non-negative number or infinity");
  if (std::isnan(request.stop_below_mm)) return invalid_argument("stop_below_mm", "is NaN");
  if (request.excluded && !request.excluded->labels(a, b)) return invalid_argument("excluded", "labels made for other trees");
  auto made = MeshPairFrame::make(a, pose_a, b, pose_b);
  if (!made.ok()) return made.error();
  MeshPairFrame& frame = made.value();
  frame.use_slabs();

  // The queue is a per-thread buffer reused across queries.
  thread_local std::vector<BoundedPair> queue;
  queue.clear();
  Search first(frame, a, request, queue, nullptr, request.upper_bound_mm);
  first.stats.node_pairs_tested = 1;
  const bool may_split = request.spare != nullptr && request.stop_below_mm < 0.0;
  const double root_bound = request.excluded && request.excluded->nodes_settled(0, 0) ? kOutOfReach : frame.nodes_lower_bound(0, 0);
  bool done = first.run({0, 0, root_bound}, true, may_split ? kSplitFrontier : SIZE_MAX);
  DistanceResult result;
  if (!done) {
    // Deal the queued pairs out by their bounds, alternately, so that each search has its share
    // of the nearest; both prune with the best either has found.
    std::sort(queue.begin(), queue.end(), [](const BoundedPair& x, const BoundedPair& y) { return x.lower_bound < y.lower_bound; });
    std::vector<BoundedPair> mine, theirs;
    for (std::size_t k = 0; k < queue.size(); ++k) (k % 2 == 0 ? mine : theirs).push_back(queue[k]);
    std::make_heap(mine.begin(), mine.end(), farther);
    std::make_heap(theirs.begin(), theirs.end(), farther);
    queue = std::move(mine);
    std::atomic<double> shared{first.best};
    first.shared = &shared;
    Search second(frame, a, request, theirs, &shared, first.best);
    request.spare->start([&second] { second.run({0, 0, 0.0}, false, SIZE_MAX); });
    first.run({0, 0, 0.0}, false, SIZE_MAX);
    request.spare->wait();
    if (second.stop_asked) first.stop_asked = true;
    first.stats += second.stats;
    // Each search's witnesses are at its own best; the nearer (the lower ids on a tie) is the answer.
    const bool second_better = second.best_ka >= 0 &&
                               (first.best_ka < 0 || second.own_best < first.own_best ||
                                (second.own_best == first.own_best &&
                                 std::make_pair(a.mesh_triangle_index(second.best_ka), b.mesh_triangle_index(second.best_kb)) <
                                     std::make_pair(a.mesh_triangle_index(first.best_ka), b.mesh_triangle_index(first.best_kb))));
    first.best = first.own_best;
    if (second_better) {
      first.best = second.own_best;
      first.best_ka = second.best_ka;
      first.best_kb = second.best_kb;
      first.best_pa = second.best_pa;
      first.best_pb = second.best_pb;
    }
  }
  if (first.stop_asked) return stopped("the distance query");
  result.stats = first.stats;
  result.stopped_early = first.stopped_early;
  if (first.best_ka >= 0) {
    result.found = true;
    result.distance_mm = first.best;
    result.triangle_a = a.mesh_triangle_index(first.best_ka);
    result.triangle_b = b.mesh_triangle_index(first.best_kb);
    result.point_a = frame.to_world(first.best_pa);
    result.point_b = frame.to_world(first.best_pb);
  }
  return result;
}

Result<ProximityResult> pairs_within(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, double delta_mm, std::size_t max_pairs,
                                     const StopToken& stop, const SettledPairs* settled,
                                     const std::function<bool(const ProximityPair&)>& enough) {
  if (!(delta_mm >= 0.0) || !std::isfinite(delta_mm))
    return invalid_argument("delta_mm", "must be a finite, non-negative distance");
  if (settled && !settled->labels(a, b)) return invalid_argument("settled", "labels made for other trees");
  auto made = MeshPairFrame::make(a, pose_a, b, pose_b);
  if (!made.ok()) return made.error();
  MeshPairFrame& frame = made.value();
  frame.use_slabs();
  ProximityResult result;
  // A settled pair within reach first: found (or none there), every settled pair may be skipped.
  if (settled && !settled->groups.empty()) {
    bool stopped_early = false;
    const std::optional<Vec3> hint = settled->hint ? std::optional<Vec3>(pose_a.inverse().apply(*settled->hint)) : std::nullopt;
    result.settled_witness = settled_within(frame, *settled, hint, delta_mm, result.stats, stop, stopped_early);
    if (stopped_early) return stopped("the pairs within the gap");
  }

  std::array<std::pair<int, int>, 2 * kMaxBvhDepth + 4> stack;
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0 && !result.truncated) {
    const auto [na, nb] = stack[--top];
    if ((result.stats.node_pairs_tested++ & kStopCheckMask) == 0 && stop.stop_requested()) return stopped("the pairs within the gap");
    // Settled pairs (their witness looked for above) and pairs proven apart are skipped.
    if (settled && settled->skip_nodes(na, nb, true)) continue;
    if (frame.pair_lower_bound(na, nb, std::nextafter(delta_mm, 1e300)) > delta_mm) continue;
    const bool leaf_a = frame.is_leaf_a(na), leaf_b = frame.is_leaf_b(nb);
    if (leaf_a && leaf_b) {
      // Each triangle's bound against the other leaf first, as in the distance search: two curved
      // surfaces in line contact (a pin in its hole) have most leaf pairs' boxes overlapping and
      // few of their triangles near.
      const double cutoff = std::nextafter(delta_mm, 1e300);
      const LeafABounds a_bounds(frame, na, nb, cutoff, result.stats);
      for (int kb = frame.begin_b(nb); kb <= frame.end_b(nb) && !result.truncated; ++kb) {
        const Triangle tb = frame.b_triangle_in_a(kb);
        ++result.stats.triangle_node_tests;
        if (frame.triangle_to_node_a_bound(tb, na, cutoff) > delta_mm) continue;
        for (int ka = a_bounds.first; ka <= frame.end_a(na); ++ka) {
          if (a_bounds.of(ka) > delta_mm) continue;
          if (settled && settled->skip_triangles(ka, kb, true)) continue;
          ++result.stats.triangle_pairs_tested;
          const TriangleDistance d = triangle_distance(a.ordered_triangle(ka), tb, std::nextafter(delta_mm, 1e300));
          if (!d.bounded_only && d.distance <= delta_mm) {
            if (result.pairs.size() >= max_pairs) {
              result.truncated = true;
              break;
            }
            result.pairs.push_back({a.mesh_triangle_index(ka), b.mesh_triangle_index(kb), d.distance,
                                    frame.to_world(d.on_p), frame.to_world(d.on_q)});
            if (enough && enough(result.pairs.back())) {
              result.truncated = true;
              break;
            }
          }
        }
      }
      continue;
    }
    const bool split_a = !leaf_a && (leaf_b || frame.size_a(na) >= frame.size_b(nb));
    if (split_a) {
      stack[top++] = {frame.second_child_a(na), nb};
      stack[top++] = {frame.first_child_a(na), nb};
    } else {
      stack[top++] = {na, frame.second_child_b(nb)};
      stack[top++] = {na, frame.first_child_b(nb)};
    }
  }
  std::sort(result.pairs.begin(), result.pairs.end(), [](const ProximityPair& x, const ProximityPair& y) {
    return std::tie(x.triangle_a, x.triangle_b) < std::tie(y.triangle_a, y.triangle_b);
  });
  return result;
}

}  // namespace gk
