#include "engine/audits/audit_job.h"

#include "engine/scenes/placed_scene.h"
#include "engine/verdicts/exact_depth.h"
#include "engine/verdicts/pair_verdict.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <tuple>

namespace gk::engine {

void AuditJob::update(const std::function<void(AuditSnapshot&)>& change) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    change(state_);
    state_.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  }
  changed_.notify_all();
  std::lock_guard<std::mutex> lock(watchers_mutex_);
  for (auto& [token, on_change] : watchers_) on_change();
}

std::uint64_t AuditJob::subscribe(std::function<void()> on_change) {
  std::lock_guard<std::mutex> lock(watchers_mutex_);
  if (watchers_.size() >= kMaxWatchers) return 0;
  const std::uint64_t token = next_watcher_++;
  watchers_[token] = std::move(on_change);
  return token;
}

void AuditJob::unsubscribe(std::uint64_t token) {
  std::lock_guard<std::mutex> lock(watchers_mutex_);
  watchers_.erase(token);
}

void AuditJob::end(const std::function<void(AuditSnapshot&)>& change) {
  AuditSnapshot final_state = snapshot();
  change(final_state);
  final_state.eta_s = 0.0;
  final_state.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  // Kept (archived) before anybody can see that the job has ended.
  if (on_end_) on_end_(final_state);
  update([&](AuditSnapshot& s) { s = std::move(final_state); });
}

void AuditJob::fail(const Error& error) {
  end([&](AuditSnapshot& s) {
    s.status = AuditStatus::kFailed;
    s.message = error.to_string();
  });
}

void AuditJob::fail_unexpectedly(const std::string& message) {
  if (snapshot().status != AuditStatus::kRunning) return;
  fail(Error{ErrorCode::kInternal, "audit", message});
}

std::vector<AuditedObject> AuditJob::objects() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return objects_;
}

void AuditJob::run(PartRegistry& parts, std::function<void(const AuditSnapshot&)> on_end,
                   std::function<void(std::size_t, const std::vector<PairClash>&)> on_tile,
                   const std::function<Result<AuditResult>(const std::vector<AuditObject>&, const AuditOptions&)>& runner) {
  on_end_ = std::move(on_end);
  // The scene's objects in id order; one mesh and BVH per part, shared by every copy.
  auto placed = place_scene(scene_, parts);
  if (!placed.ok()) return fail(placed.error());
  std::vector<AuditObject>& objects = placed.value().objects;
  const std::vector<const SceneObjectRecord*>& records = placed.value().records;
  const std::map<std::string, std::uint32_t>& index_of = placed.value().index_of;
  std::vector<AuditedObject> audited;
  for (std::size_t i = 0; i < records.size(); ++i)
    audited.push_back({records[i]->id, records[i]->name, records[i]->category, placed.value().boxes[i]});
  {
    std::lock_guard<std::mutex> lock(mutex_);
    objects_ = audited;
  }
  auto to_record = [&](const PairClash& c) {
    const SceneObjectRecord& a = *records[c.a];
    const SceneObjectRecord& b = *records[c.b];
    return ClashRecord{a.id, b.id, a.name, b.name, a.category, b.category, c, false, ""};
  };
  AuditOptions options = options_;
  options.cancel = &cancelled_;
  options.on_progress = [this](const AuditProgress& p) {
    update([&](AuditSnapshot& s) {
      s.tiles_total = p.tiles_total;
      s.tiles_done = p.tiles_done;
      s.pairs_total = p.pairs_total;
      s.pairs_done = p.pairs_done;
      s.eta_s = p.eta_s;
    });
  };
  // A clash with a CAD part within its deflection is decided again on the exact faces as it is
  // found (serialised with the other reports); the final list uses the same answers.
  const std::vector<std::shared_ptr<const LoadedPart>>& parts_of = placed.value().parts;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::optional<ClashRecord>> redecided;
  std::mutex redecided_mutex;
  auto final_record = [&](const PairClash& c) -> std::optional<ClashRecord> {
    ClashRecord r = to_record(c);
    if (parts_of[c.a]->deflection_mm + parts_of[c.b]->deflection_mm == 0.0) return r;
    {
      std::lock_guard<std::mutex> lock(redecided_mutex);
      auto it = redecided.find({c.a, c.b});
      if (it != redecided.end()) return it->second;
    }
    auto exact = decide_contact({parts_of[c.a].get(), objects[c.a].pose}, {parts_of[c.b].get(), objects[c.b].pose},
                          options_.clearance_mm);
    std::optional<ClashRecord> out;
    if (!exact.ok()) {
      r.clash.verdict = Verdict::kInconclusive;
      r.clash.inconclusive_reason = InconclusiveReason::kPairFailed;
      r.reason = exact.error().to_string();
      out = r;
    } else if (exact.value()) {
      const engine::PairVerdict& v = *exact.value();
      r.clash.verdict = v.result.verdict;
      r.clash.inconclusive_reason = v.result.inconclusive_reason;
      r.clash.distance_mm = v.result.distance_mm;
      r.clash.point_a = v.result.point_a;
      r.clash.point_b = v.result.point_b;
      r.clash.clearance_violation = v.result.verdict == Verdict::kClear;
      r.decided_on_brep = v.decided_on_brep;
      r.reason = v.result.reason;
      if (v.result.verdict != Verdict::kCollision) {
        r.clash.depth_mm = -1.0;
        r.clash.depth_direction.reset();
      } else if (options_.compute_depth && (parts_of[c.a]->is_cad() || parts_of[c.b]->is_cad())) {
        // The triangles' depth frees the tessellations, not the solids: checked (and extended) on
        // the exact faces as ClearanceQuery does; along the centres' line when the triangles are free.
        const engine::PosedPart pa{parts_of[c.a].get(), objects[c.a].pose}, pb_{parts_of[c.b].get(), objects[c.b].pose};
        Vec3 direction = r.clash.depth_direction ? r.clash.depth_direction->vector() : Vec3::Zero();
        double depth = std::max(r.clash.depth_mm, 0.0);
        if (!(depth > 0.0) || !(direction.norm() > 0.0)) {
          direction = transformed_box(pb_.part->mesh->bounds(), pb_.pose).center() - transformed_box(pa.part->mesh->bounds(), pa.pose).center();
          if (!(direction.norm() > 0.0)) direction = Vec3::UnitZ();
          depth = 0.0;
        }
        direction.normalize();
        const StopToken stop([this] { return cancelled_.load(); });
        auto checked = engine::check_depth_on_brep(pa, pb_, direction, depth, stop);
        r.clash.depth_mm = checked.ok() ? checked.value().depth_mm : -1.0;  // -1: not certified
        r.clash.depth_direction = checked.ok() ? Direction::of(direction) : std::nullopt;
      }
      out = r;
    }
    std::lock_guard<std::mutex> lock(redecided_mutex);
    redecided[{c.a, c.b}] = out;
    return out;
  };
  options.on_clash = [&](const PairClash& c) {
    std::optional<ClashRecord> r = final_record(c);
    if (r) update([&](AuditSnapshot& s) { s.clashes.push_back(std::move(*r)); });
  };
  // Resumed: the finished tiles are not computed again; their clashes are known from the start.
  std::vector<PairClash> resumed;
  for (const auto& [tile, clashes] : finished_tiles_) {
    options.skip_tiles.push_back(tile);
    for (const PairClash& c : clashes) {
      if (c.a >= objects.size() || c.b >= objects.size() || c.a >= c.b)
        return fail(Error{ErrorCode::kInternal, "checkpoint", "a resumed tile names objects this snapshot does not have"});
      resumed.push_back(c);
      options.on_clash(c);
    }
  }
  options.on_tile_done = on_tile;
  Result<AuditResult> result = Error{};
  if (baseline_) {
    // Re-audit: objects new or changed since the baseline's snapshot are recomputed; the
    // baseline's other clashes carry over (re-indexed to this snapshot).
    const AuditSnapshot base = baseline_->snapshot();
    const SceneRecord& before = baseline_->scene();
    std::vector<std::uint32_t> changed;
    for (const auto& [id, o] : scene_.objects) {
      auto it = before.objects.find(id);
      const bool same = it != before.objects.end() && it->second.part_id == o.part_id && it->second.category == o.category &&
                        it->second.group == o.group && it->second.pose.translation == o.pose.translation &&
                        it->second.pose.axis == o.pose.axis && it->second.pose.angle_deg == o.pose.angle_deg;
      if (!same) changed.push_back(index_of.at(id));
    }
    AuditResult previous;
    for (const ClashRecord& r : base.clashes) {
      auto ia = index_of.find(r.a), ib = index_of.find(r.b);
      if (ia == index_of.end() || ib == index_of.end()) continue;  // removed since
      PairClash c = r.clash;
      c.a = std::min(ia->second, ib->second);
      c.b = std::max(ia->second, ib->second);
      previous.clashes.push_back(c);
    }
    sort_in_pair_order(previous.clashes);
    update([](AuditSnapshot& s) { s.reaudit = true; });
    result = reaudit_scene(objects, previous, changed, options);
  } else {
    result = runner ? runner(objects, options) : audit_scene(objects, options);
  }
  if (!result.ok()) return fail(result.error());
  AuditResult& r = result.value();
  if (!resumed.empty()) {
    r.clashes.insert(r.clashes.end(), resumed.begin(), resumed.end());
    sort_in_pair_order(r.clashes);
  }
  std::vector<ClashRecord> ordered;
  for (const PairClash& c : r.clashes)
    if (std::optional<ClashRecord> record = final_record(c)) ordered.push_back(std::move(*record));
  end([&](AuditSnapshot& s) {
    s.clashes = std::move(ordered);
    s.pairs_done = r.pairs_done;
    s.candidate_pairs = r.candidate_pairs;
    s.excluded_by_rules = r.excluded_by_rules;
    s.objects = r.objects;
    s.triangles = r.triangles;
    s.broad_s = r.times.broad_s;
    s.narrow_s = r.times.narrow_s;
    s.status = r.cancelled ? AuditStatus::kCancelled : AuditStatus::kDone;
    s.message = !r.cancelled      ? ""
                : interrupted_ ? "interrupted by the daemon's stop; it resumes from its finished tiles when the daemon starts again"
                               : "cancelled; the clashes of the pairs finished are kept";
  });
}

bool AuditJob::running() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_.status == AuditStatus::kRunning;
}

AuditSnapshot AuditJob::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

AuditSnapshot AuditJob::wait_for_change(unsigned long long seen_done, AuditStatus seen_status,
                                        std::chrono::milliseconds timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return state_.pairs_done != seen_done || state_.status != seen_status; });
  return state_;
}

std::shared_ptr<AuditJob> AuditJob::restored(SceneRecord scene, AuditSnapshot snapshot, std::vector<AuditedObject> objects,
                                            std::vector<std::string> answer_options) {
  auto job = std::make_shared<AuditJob>(std::move(scene), AuditOptions{});
  job->state_ = std::move(snapshot);
  job->objects_ = std::move(objects);
  job->restored_answer_options_ = std::move(answer_options);
  // Archived before the options were kept: never equal to any audit's, so never reused.
  if (job->restored_answer_options_.empty()) job->restored_answer_options_ = {"unrecorded"};
  return job;
}

std::vector<std::string> AuditJob::answer_options() const {
  if (!restored_answer_options_.empty()) return restored_answer_options_;
  auto number = [](double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  };
  std::vector<std::string> out = {"clearance_mm=" + number(options_.clearance_mm),
                                  "compute_depth=" + std::string(options_.compute_depth ? "true" : "false"),
                                  "compute_volume=" + std::string(options_.compute_volume ? "true" : "false"),
                                  "region_merge_mm=" + number(options_.region_merge_mm),
                                  "max_contacts_per_pair=" + std::to_string(options_.max_contacts_per_pair)};
  std::string rules;
  for (const ContactRule& r : options_.rules)
    rules += r.name + ":" + r.category_a + "/" + r.category_b + (r.same_group_only ? "/same_group" : "") + ";";
  out.push_back("rules=" + rules);
  return out;
}

}  // namespace gk::engine
