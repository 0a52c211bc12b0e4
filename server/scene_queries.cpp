#include "server/scene_queries.h"

#include "engine/exact_depth.h"
#include "server/audit_archive.h"

#include <algorithm>
#include <sstream>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <tuple>

namespace gk::server {
namespace {

struct Placed {
  const SceneObjectRecord* object;
  std::shared_ptr<const LoadedPart> part;
  RigidTransform pose;
  Aabb box;
};


Result<Placed> place(const SceneObjectRecord& o, PartRegistry& parts) {
  auto part = parts.load(o.part_id, kPartDeflectionMm);
  if (!part.ok()) return Error{part.error().code, "objects[" + o.id + "].part_id", part.error().message};
  const RigidTransform pose = o.pose.transform();
  return Placed{&o, part.value(), pose, transformed_box(part.value()->mesh->bounds(), pose)};
}


// A pair the kernel reported from the triangles alone, decided again where a CAD part's
// tessellation cannot tell (engine/pair_verdict); nullopt when it is no contact after all.
Result<std::optional<engine::PairVerdict>> redecide(const engine::PosedPart& a, const engine::PosedPart& b,
                                                    double clearance_mm, const StopToken& stop = {}) {
  engine::PairVerdictOptions options;
  options.clearance_mm = clearance_mm;
  options.mesh.stop = &stop;
  options.mesh.distance_upper_bound_mm = clearance_mm;
  auto v = engine::decide_pair(a, b, options);
  if (!v.ok()) return v.error();
  const VerdictResult& r = v.value().result;
  if (r.verdict == Verdict::kClear && r.distance_mm >= clearance_mm) return std::optional<engine::PairVerdict>{};
  return std::optional<engine::PairVerdict>{std::move(v).value()};
}

}  // namespace

Result<PlacedScene> place_scene(const SceneRecord& scene, PartRegistry& parts) {
  PlacedScene out;
  for (const auto& [id, o] : scene.objects) {
    auto p = place(o, parts);
    if (!p.ok()) return p.error();
    out.index_of[id] = static_cast<std::uint32_t>(out.objects.size());
    out.objects.push_back({o.name, o.category, o.group, p.value().part->bvh, p.value().pose, p.value().part->deflection_mm});
    out.parts.push_back(p.value().part);
    out.records.push_back(&o);
    out.boxes.push_back(p.value().box);
  }
  return out;
}

Result<MoveOutcome> DragSession::move(const std::string& scene_id, std::uint64_t scene_version,
                                      const std::function<Result<SceneRecord>()>& read_scene, const std::string& object_id,
                                      double clearance_mm, const RigidTransform& pose, PartRegistry& parts) {
  // Still valid when only this stream's own moves happened since (one version each).
  const bool same = session_ && scene_id == scene_id_ && object_id == object_id_ && clearance_mm == clearance_mm_ &&
                    scene_version == version_ + 1;
  if (!same) {
    auto read = read_scene();
    if (!read.ok()) return read.error();
    const SceneRecord& scene = read.value();
    scene_version = scene.version;
    auto placed = place_scene(scene, parts);
    if (!placed.ok()) return placed.error();
    auto it = placed.value().index_of.find(object_id);
    if (it == placed.value().index_of.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
    auto session = LayoutSession::create(std::move(placed.value().objects), it->second, clearance_mm);
    if (!session.ok()) return session.error();
    session_ = std::move(session).value();
    ids_.clear();
    for (const SceneObjectRecord* r : placed.value().records) ids_.push_back(r->id);
    parts_ = placed.value().parts;
    scene_id_ = scene.id;
    object_id_ = object_id;
    clearance_mm_ = clearance_mm;
  }
  version_ = scene_version;
  auto frame = session_->move_to(pose);
  if (!frame.ok()) return frame.error();
  MoveOutcome out;
  out.candidates = frame.value().candidates;
  const std::shared_ptr<const LoadedPart>& self = parts_[session_->moving_index()];
  for (const FrameContact& c : frame.value().contacts) {
    const std::shared_ptr<const LoadedPart>& other = parts_[c.other];
    ObjectContactResult contact{ids_[c.other], c.verdict, c.distance_mm, c.point, c.other_point};
    if (self->deflection_mm + other->deflection_mm > 0.0) {
      // The triangles of a CAD part cannot tell within its deflection: the exact faces decide.
      auto exact = redecide({self.get(), pose}, {other.get(), session_->pose_of(c.other)}, clearance_mm);
      if (!exact.ok()) return exact.error();
      if (!exact.value()) continue;
      const engine::PairVerdict& v = *exact.value();
      contact = {ids_[c.other], v.result.verdict, v.result.distance_mm, v.result.point_a, v.result.point_b,
                 v.result.inconclusive_reason, v.decided_on_brep};
    }
    if (severity(contact.verdict) > severity(out.verdict)) out.verdict = contact.verdict;
    out.contacts.push_back(std::move(contact));
  }
  return out;
}

Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts, const StopToken& stop) {
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be >= 0");
  auto self_it = scene.objects.find(object_id);
  if (self_it == scene.objects.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  auto self = place(self_it->second, parts);
  if (!self.ok()) return self.error();
  MoveOutcome out;
  for (const auto& [id, other] : scene.objects) {
    if (id == object_id) continue;
    if (stop.stop_requested()) return stopped("the moved object's contacts");
    auto placed = place(other, parts);
    if (!placed.ok()) return placed.error();
    // Boxes of triangles: a CAD part's true surface may stand out of its tessellation's box.
    const double deviation = self.value().part->deflection_mm + placed.value().part->deflection_mm;
    if (!placed.value().box.overlaps(self.value().box.expanded(clearance_mm + deviation))) continue;
    ++out.candidates;
    auto v = redecide({self.value().part.get(), self.value().pose}, {placed.value().part.get(), placed.value().pose},
                      clearance_mm, stop);
    if (!v.ok()) return v.error();
    if (!v.value()) continue;
    const engine::PairVerdict& pv = *v.value();
    const VerdictResult& r = pv.result;
    out.contacts.push_back({id, r.verdict, r.distance_mm, r.point_a, r.point_b, r.inconclusive_reason, pv.decided_on_brep});
    if (severity(r.verdict) > severity(out.verdict)) out.verdict = r.verdict;
  }
  return out;
}

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

void AuditJob::run(PartRegistry& parts, std::function<void(const AuditSnapshot&)> on_end) {
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
    auto exact = redecide({parts_of[c.a].get(), objects[c.a].pose}, {parts_of[c.b].get(), objects[c.b].pose},
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
        r.clash.depth_direction = Vec3::Zero();
      } else if (options_.compute_depth && (parts_of[c.a]->is_cad() || parts_of[c.b]->is_cad())) {
        // The triangles' depth frees the tessellations, not the solids: checked (and extended) on
        // the exact faces as ClearanceQuery does; along the centres' line when the triangles are free.
        const engine::PosedPart pa{parts_of[c.a].get(), objects[c.a].pose}, pb_{parts_of[c.b].get(), objects[c.b].pose};
        Vec3 direction = r.clash.depth_direction;
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
        r.clash.depth_direction = checked.ok() ? direction : Vec3::Zero();
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
    std::sort(previous.clashes.begin(), previous.clashes.end(),
              [](const PairClash& l, const PairClash& r) { return std::tie(l.a, l.b) < std::tie(r.a, r.b); });
    update([](AuditSnapshot& s) { s.reaudit = true; });
    result = reaudit_scene(objects, previous, changed, options);
  } else {
    result = audit_scene(objects, options);
  }
  if (!result.ok()) return fail(result.error());
  const AuditResult& r = result.value();
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
    s.message = r.cancelled ? "cancelled; the clashes of the pairs finished are kept" : "";
  });
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

void AuditJobs::archived(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!archive_ || jobs_.count(id) == 0) return;
  ended_.remove(id);
  ended_.push_back(id);
  drop_beyond_limit();
}

void AuditJobs::drop_beyond_limit() {
  while (ended_.size() > ended_in_memory_) {
    jobs_.erase(ended_.front());
    ended_.pop_front();
  }
}

std::size_t AuditJobs::in_memory() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jobs_.size();
}

void AuditJobs::cancel_all() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [id, job] : jobs_) job->cancel();
}

void AuditJobs::remove(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  jobs_.erase(id);
  ended_.remove(id);
}

std::string AuditJobs::add(std::shared_ptr<AuditJob> job) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Unique across restarts too (a job that was running when the daemon stopped is not archived,
  // so a counter alone would hand its id to the next job): the daemon's start time, then a count.
  const std::string id = "audit-" + std::to_string(epoch_ms_) + "-" + std::to_string(++counter_);
  jobs_[id] = std::move(job);
  return id;
}

Result<std::shared_ptr<AuditJob>> AuditJobs::get(const std::string& id) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = jobs_.find(id);
    if (it != jobs_.end()) {
      if (std::find(ended_.begin(), ended_.end(), id) != ended_.end()) {
        ended_.remove(id);  // read again: the most recently read now
        ended_.push_back(id);
      }
      return it->second;
    }
  }
  if (!archive_) return Error{ErrorCode::kNotFound, "job_id", "no audit job '" + id + "'"};
  auto loaded = archive_->load(id);  // outside the lock: a database read
  if (!loaded.ok()) return loaded.error();
  std::lock_guard<std::mutex> lock(mutex_);
  auto [it, fresh] = jobs_.insert({id, loaded.value()});
  std::shared_ptr<AuditJob> job = it->second;
  if (fresh) {
    ended_.push_back(id);
    drop_beyond_limit();
  }
  return job;
}

}  // namespace gk::server
