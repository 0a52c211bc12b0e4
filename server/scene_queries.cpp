#include "server/scene_queries.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace gk::server {
namespace {

struct Placed {
  const SceneObjectRecord* object;
  std::shared_ptr<const LoadedPart> part;
  RigidTransform pose;
  Aabb box;
};


Result<Placed> place(const SceneObjectRecord& o, PartRegistry& parts) {
  auto part = parts.load(o.part_id, 0.05);
  if (!part.ok()) return Error{part.error().code, "objects[" + o.id + "].part_id", part.error().message};
  const RigidTransform pose = o.pose.transform();
  return Placed{&o, part.value(), pose, transformed_box(part.value()->mesh->bounds(), pose)};
}

int severity(Verdict v) {
  switch (v) {
    case Verdict::kClear: return 0;
    case Verdict::kTouching: return 1;
    case Verdict::kInconclusive: return 2;
    case Verdict::kCollision: return 3;
  }
  return 2;
}

}  // namespace

Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts) {
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be >= 0");
  auto self_it = scene.objects.find(object_id);
  if (self_it == scene.objects.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  auto self = place(self_it->second, parts);
  if (!self.ok()) return self.error();
  const Aabb reach = self.value().box.expanded(clearance_mm);
  MoveOutcome out;
  for (const auto& [id, other] : scene.objects) {
    if (id == object_id) continue;
    auto placed = place(other, parts);
    if (!placed.ok()) return placed.error();
    if (!placed.value().box.overlaps(reach)) continue;
    ++out.candidates;
    auto v = assess(*self.value().part->bvh, self.value().pose, *placed.value().part->bvh, placed.value().pose);
    if (!v.ok()) return v.error();
    const VerdictResult& r = v.value();
    if (r.verdict == Verdict::kClear && r.distance_mm >= clearance_mm) continue;
    out.contacts.push_back({id, r.verdict, r.distance_mm, r.point_a, r.point_b});
    if (severity(r.verdict) > severity(out.verdict)) out.verdict = r.verdict;
  }
  return out;
}

void AuditJob::update(const std::function<void(AuditSnapshot&)>& change) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    change(state_);
    state_.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    if (state_.pairs_done > 0 && state_.pairs_total > state_.pairs_done)
      state_.eta_s = state_.elapsed_s / static_cast<double>(state_.pairs_done) *
                     static_cast<double>(state_.pairs_total - state_.pairs_done);
    else
      state_.eta_s = 0.0;
  }
  changed_.notify_all();
}

void AuditJob::run(PartRegistry& parts) {
  // Broad phase: every pair whose boxes, grown by the clearance, overlap (the factory issue
  // brings sweep-and-prune, tiles and parallelism).
  std::vector<Placed> placed;
  for (const auto& [id, o] : scene_.objects) {
    auto p = place(o, parts);
    if (!p.ok()) {
      update([&](AuditSnapshot& s) {
        s.status = AuditStatus::kFailed;
        s.message = p.error().to_string();
      });
      return;
    }
    placed.push_back(p.value());
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < placed.size(); ++i)
    for (std::size_t j = i + 1; j < placed.size(); ++j)
      if (placed[i].box.expanded(clearance_mm_).overlaps(placed[j].box)) pairs.emplace_back(i, j);
  update([&](AuditSnapshot& s) { s.pairs_total = pairs.size(); });
  for (const auto& [i, j] : pairs) {
    if (cancelled_) {
      update([](AuditSnapshot& s) {
        s.status = AuditStatus::kCancelled;
        s.message = "cancelled; the clashes found so far are kept";
      });
      return;
    }
    auto v = assess(*placed[i].part->bvh, placed[i].pose, *placed[j].part->bvh, placed[j].pose);
    ClashRecord clash;
    bool is_clash = false;
    if (!v.ok()) {
      clash = {placed[i].object->id, placed[j].object->id, Verdict::kInconclusive, 0.0, Vec3::Zero(), 0};
      is_clash = true;
    } else if (v.value().verdict != Verdict::kClear || v.value().distance_mm < clearance_mm_) {
      clash = {placed[i].object->id, placed[j].object->id, v.value().verdict, v.value().distance_mm, v.value().point_a,
               static_cast<unsigned>(v.value().contacts.size())};
      is_clash = true;
    }
    update([&](AuditSnapshot& s) {
      ++s.pairs_done;
      if (is_clash) s.clashes.push_back(clash);
    });
  }
  update([](AuditSnapshot& s) { s.status = AuditStatus::kDone; });
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

std::string AuditJobs::add(std::shared_ptr<AuditJob> job) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string id = "audit-" + std::to_string(++counter_);
  jobs_[id] = std::move(job);
  return id;
}

Result<std::shared_ptr<AuditJob>> AuditJobs::get(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return Error{ErrorCode::kNotFound, "job_id", "no audit job '" + id + "'"};
  return it->second;
}

}  // namespace gk::server
