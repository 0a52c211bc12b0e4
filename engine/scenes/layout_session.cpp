#include "engine/scenes/layout_session.h"

#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>

namespace gk::engine {
namespace {

// A frame reports where two objects touch, not every crossing triangle pair: the first few
// contacts locate it (collecting thousands would cost a deep overlap milliseconds). The verdict
// itself is decided over every pair whatever the cap (assess's contract).
constexpr std::size_t kFirstContacts = 32;

OrientedBox placed(const OrientedBox& local, const RigidTransform& pose) {
  return {pose.apply(local.center), pose.rotation * local.axes, local.half_extent};
}

// The gap between the two boxes' projections on the unit axis (negative when they overlap on it):
// a lower bound of their distance.
double gap_along(const OrientedBox& a, const OrientedBox& b, const Vec3& axis) {
  const double ra = a.half_extent.dot((a.axes.transpose() * axis).cwiseAbs());
  const double rb = b.half_extent.dot((b.axes.transpose() * axis).cwiseAbs());
  return std::abs(axis.dot(b.center - a.center)) - ra - rb;
}

// The best of the 15 box axes: the largest gap, and the axis.
std::pair<double, Vec3> best_box_axis(const OrientedBox& a, const OrientedBox& b) {
  std::pair<double, Vec3> best{-std::numeric_limits<double>::infinity(), Vec3::UnitX()};
  auto consider = [&](const Vec3& axis) {
    const double n = axis.norm();
    if (!(n > 1e-9)) return;
    const Vec3 u = axis / n;
    const double g = gap_along(a, b, u);
    if (g > best.first) best = {g, u};
  };
  for (int i = 0; i < 3; ++i) consider(a.axes.col(i));
  for (int i = 0; i < 3; ++i) consider(b.axes.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) consider(a.axes.col(i).cross(b.axes.col(j)));
  return best;
}


}  // namespace

Result<std::unique_ptr<LayoutSession>> LayoutSession::create(std::vector<AuditObject> objects, std::uint32_t moving,
                                                             double clearance_mm) {
  if (moving >= objects.size()) return invalid_argument("moving", "no object " + std::to_string(moving));
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be a finite, non-negative distance");
  if (auto bad = check_objects(objects, false); !bad.ok()) return bad.error();
  std::unique_ptr<LayoutSession> s(new LayoutSession());
  s->objects_ = std::move(objects);
  s->moving_ = moving;
  s->clearance_mm_ = clearance_mm;
  const std::size_t n = s->objects_.size();
  // A pair is cleared by boxes only when they are farther apart than the clearance and the contact
  // tolerance (assess calls closer pairs TOUCHING), with a slack for rounding in the box fits.
  double magnitude = 1.0;
  for (const AuditObject& o : s->objects_) {
    const Aabb b = transformed_box(o.mesh->root_bounds(), o.pose);
    magnitude = std::max({magnitude, b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()});
  }
  // CAD parts: pairs within their tessellations' deviations of the clearance are reported too.
  double deviation = 0.0;
  for (const AuditObject& o : s->objects_) deviation = std::max(deviation, o.surface_deviation_mm);
  s->needed_gap_mm_ = std::max(clearance_mm + 2.0 * deviation, tolerances::kContactMm) + tolerances::kComparisonSlackRelative * magnitude;
  s->boxes_.resize(n);
  s->obbs_.resize(n);
  s->stamp_.assign(n, 0);
  // One oriented box per distinct mesh (fitted once per mesh, kept with it), placed per object.
  // The meshes' node slabs are fitted here too, not by the first frame that queries them (a frame
  // that fitted a 70,000-triangle mesh's took 4 ms more).
  for (std::size_t i = 0; i < n; ++i) {
    const AuditObject& o = s->objects_[i];
    (void)o.mesh->node_slabs();
    s->obbs_[i] = placed(o.mesh->oriented_box(), o.pose);
    s->boxes_[i] = transformed_box(o.mesh->root_bounds(), o.pose).expanded(0.5 * s->needed_gap_mm_);
  }
  s->moving_local_obb_ = s->objects_[moving].mesh->oriented_box();
  s->grid_ = std::make_unique<UniformGrid>(s->boxes_, tolerances::kLayoutGridMinCellMm, moving);
  return s;
}

void LayoutSession::gather(const GridCellRange& range) {
  gathered_ = grid_->oversized();
  if (++stamp_now_ == 0) {  // wrapped: clear the stamps
    std::fill(stamp_.begin(), stamp_.end(), 0);
    stamp_now_ = 1;
  }
  grid_->for_each_member(range, [&](std::uint32_t id) {
    if (stamp_[id] == stamp_now_) return;
    stamp_[id] = stamp_now_;
    gathered_.push_back(id);
  });
  last_range_ = range;
}

Result<FrameAnswer> LayoutSession::move_to(const RigidTransform& pose, const StopToken& stop) {
  if (!pose.is_finite() || !pose.is_rigid()) return invalid_argument("pose", "must be a finite rigid transform");
  AuditObject& self = objects_[moving_];
  self.pose = pose;
  const Aabb box = transformed_box(self.mesh->root_bounds(), pose).expanded(0.5 * needed_gap_mm_);
  // A huge moving box would sweep millions of cells: then every static object is a candidate.
  const GridCellRange range = grid_cell_range(box, grid_->cell_mm());
  if (range.cells() > 4096.0) {
    gathered_.clear();
    for (std::uint32_t i = 0; i < objects_.size(); ++i)
      if (i != moving_) gathered_.push_back(i);
    last_range_ = GridCellRange{{1, 1, 1}, {0, 0, 0}};  // matches no real range
  } else if (!(range == last_range_)) {
    gather(range);
  }
  const OrientedBox obb = placed(moving_local_obb_, pose);
  FrameAnswer out;
  exact_.clear();
  for (std::uint32_t id : gathered_) {
    if (!boxes_[id].overlaps(box)) continue;
    ++out.candidates;
    auto cached = separating_axis_.find(id);
    if (cached != separating_axis_.end() && gap_along(obb, obbs_[id], cached->second) > needed_gap_mm_) {
      ++out.axis_cache_hits;
      continue;
    }
    const auto [gap, axis] = best_box_axis(obb, obbs_[id]);
    if (gap > needed_gap_mm_) {
      separating_axis_[id] = axis;
      ++out.box_axis_clears;
      continue;
    }
    const AuditObject& other = objects_[id];
    auto crossed = crossing_.find(id);
    Vec3 where;
    if (crossed != crossing_.end() &&
        triangle_pair_crosses(*self.mesh, pose, crossed->second.first, *other.mesh, other.pose, crossed->second.second, &where)) {
      ++out.crossing_cache_hits;
      out.contacts.push_back({id, Verdict::kCollision, 0.0, where, where});
      out.worst = Verdict::kCollision;
      continue;
    }
    exact_.push_back(id);
  }

  // The pairs left are decided on their meshes: with several, half of them (by triangles) on the
  // session's second thread.
  results_.assign(exact_.size(), std::nullopt);
  const auto reach_of = [&](std::uint32_t id) { return clearance_mm_ + self.surface_deviation_mm + objects_[id].surface_deviation_mm; };
  const auto second_hand = [&] {
    if (!second_hand_) second_hand_ = std::make_unique<SecondHand>();
    return second_hand_.get();
  };
  const auto check = [&](std::size_t k) {
    if (stop.stop_requested()) {
      results_[k] = stopped("the moved object's contacts");
      return;
    }
    const AuditObject& other = objects_[exact_[k]];
    VerdictOptions options;
    options.max_contacts = kFirstContacts;
    options.distance_upper_bound_mm = reach_of(exact_[k]);
    options.stop = &stop;  // one pair of large meshes can take seconds: the deadline reaches into it
    if (exact_.size() == 1) options.spare = second_hand();  // the second thread is free: the pair's distance query may use it
    results_[k] = assess(*self.mesh, pose, *other.mesh, other.pose, options);
  };
  if (exact_.size() >= 2) {
    // Greedy by triangle count, the larger first: each pair to the lighter side.
    std::vector<std::size_t> order(exact_.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    const auto weight = [&](std::size_t k) { return objects_[exact_[k]].mesh->mesh().triangle_count(); };
    std::sort(order.begin(), order.end(), [&](std::size_t l, std::size_t r) { return weight(l) > weight(r); });
    std::vector<std::size_t> mine, theirs;
    std::size_t my_load = 0, their_load = 0;
    for (std::size_t k : order) {
      if (my_load <= their_load) {
        mine.push_back(k);
        my_load += weight(k);
      } else {
        theirs.push_back(k);
        their_load += weight(k);
      }
    }
    SecondHand* other_thread = second_hand();
    other_thread->start([&] {
      for (std::size_t k : theirs) check(k);
    });
    for (std::size_t k : mine) check(k);
    other_thread->wait();
  } else {
    for (std::size_t k = 0; k < exact_.size(); ++k) check(k);
  }
  for (std::size_t k = 0; k < exact_.size(); ++k) {
    const std::uint32_t id = exact_[k];
    Result<VerdictResult>& v = *results_[k];
    if (!v.ok()) return v.error();  // assess decides over every pair; the cap is on the contacts listed
    ++out.exact_checks;
    const VerdictResult& r = v.value();
    if (r.first_crossing >= 0)
      crossing_[id] = {r.contacts[r.first_crossing].triangle_a, r.contacts[r.first_crossing].triangle_b};
    else
      crossing_.erase(id);
    if (r.verdict == Verdict::kClear && r.distance_mm >= reach_of(id)) continue;
    out.contacts.push_back({id, r.verdict, r.distance_mm, r.point_a, r.point_b});
    if (severity(r.verdict) > severity(out.worst)) out.worst = r.verdict;
  }
  std::sort(out.contacts.begin(), out.contacts.end(), [](const FrameContact& l, const FrameContact& r) { return l.other < r.other; });
  return out;
}

}  // namespace gk::engine
