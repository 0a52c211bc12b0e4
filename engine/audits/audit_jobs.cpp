#include "engine/audits/audit_jobs.h"

#include "engine/audits/clash_id.h"

#include <spdlog/spdlog.h>

namespace gk::engine {

AuditJobs::AuditJobs(PartRegistry& parts, EndedAudits* archive, Options options, AuditCheckpoints* checkpoints,
                     ClashStatuses* statuses)
    : parts_(parts), archive_(archive), ended_in_memory_(std::max<std::size_t>(1, options.ended_in_memory)),
      large_audits_(std::move(options.large_audits)), large_audit_min_triangles_(options.large_audit_min_triangles),
      checkpoints_(archive ? checkpoints : nullptr), statuses_(statuses), pool_(options.concurrent, options.queued) {}

AuditJobs::~AuditJobs() {
  cancel_all();
  pool_.stop();
}

void AuditJobs::stop() {
  if (checkpoints_) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [id, job] : jobs_) job->interrupt();
  } else {
    cancel_all();
  }
  pool_.stop();
}

Result<std::string> AuditJobs::start(const SceneRecord& scene, const AuditOptions& options, const std::string& baseline_id) {
  std::shared_ptr<const AuditJob> baseline;
  if (!baseline_id.empty()) {
    auto base = get(baseline_id);
    if (!base.ok()) return Error{base.error().code, "baseline_job_id", base.error().message};
    if (base.value()->scene().id != scene.id) return invalid_argument("baseline_job_id", "audited another scene");
    if (base.value()->snapshot().status != AuditStatus::kDone)
      return Error{ErrorCode::kFailedPrecondition, "baseline_job_id", "has not finished"};
    // The baseline's answers carry over only when they were computed with the same options.
    const std::vector<std::string> then = base.value()->answer_options();
    const std::vector<std::string> now = AuditJob(scene, options).answer_options();
    for (std::size_t i = 0; i < now.size(); ++i)
      if (i >= then.size() || then[i] != now[i]) {
        const std::string name = now[i].substr(0, now[i].find('='));
        return Error{ErrorCode::kFailedPrecondition, name,
                     "the baseline was audited with " + (i < then.size() ? then[i] : std::string("unknown options")) +
                         ", this audit asks " + now[i] + "; re-audit against a baseline with the same options, or audit in full"};
      }
    baseline = base.value();
  }
  auto job = std::make_shared<AuditJob>(scene, options, baseline);
  const std::string id = add(job);
  if (checkpoints_) {
    auto begun = checkpoints_->begin(id, scene, options, baseline_id);
    if (!begun.ok()) spdlog::warn("audit {} has no checkpoint (it cannot resume after a stop): {}", id, begun.error().to_string());
  }
  if (!submit(id, job)) {
    remove(id);
    if (checkpoints_) (void)checkpoints_->forget(id);
    return Error{ErrorCode::kResourceExhausted, "audit", "audit queue full: retry later"};
  }
  return id;
}

bool AuditJobs::submit(const std::string& id, std::shared_ptr<AuditJob> job) {
  return pool_.try_submit([this, job, id] {
    try {
      job->run(
          parts_,
          [&](const AuditSnapshot& final_state) {
            // A finished audit found exactly these clashes: the review statuses follow (a cancelled,
            // failed or interrupted one found only some).
            if (statuses_ && final_state.status == AuditStatus::kDone) {
              std::vector<FoundClash> found;
              found.reserve(final_state.clashes.size());
              for (const ClashRecord& c : final_state.clashes) found.push_back({clash_id(job->scene().id, c.a, c.b), c.a, c.b});
              auto recorded = statuses_->record_audit(job->scene().id, id, found);
              if (!recorded.ok()) spdlog::warn("audit {}: clash statuses not updated: {}", id, recorded.error().to_string());
            }
            if (!archive_) return;
            // Interrupted by the daemon's stop: kept for resuming, not archived as ended.
            if (checkpoints_ && job->interrupted() && final_state.status == AuditStatus::kCancelled) return;
            auto saved = archive_->save(id, *job, final_state);
            if (!saved.ok()) {
              spdlog::warn("audit {} not archived (kept in memory): {}", id, saved.error().to_string());
              return;
            }
            archived(id);
            if (checkpoints_) {
              auto gone = checkpoints_->forget(id);
              if (!gone.ok()) spdlog::warn("audit {}: its checkpoint stays: {}", id, gone.error().to_string());
            }
          },
          [&](std::size_t tile, const std::vector<PairClash>& clashes) {
            if (!checkpoints_) return;
            auto kept = checkpoints_->tile_done(id, tile, clashes);
            if (!kept.ok()) spdlog::warn("audit {}: tile {} not checkpointed: {}", id, tile, kept.error().to_string());
          },
          [&](const std::vector<AuditObject>& objects, const AuditOptions& options) -> Result<AuditResult> {
            std::size_t triangles = 0;
            for (const AuditObject& o : objects) triangles += triangle_count(o);
            if (!large_audits_ || triangles < large_audit_min_triangles_) return audit_scene(objects, options);
            spdlog::info("audit {}: {} triangles, handed to the distributed driver", id, triangles);
            return large_audits_(id, job->scene(), objects, options);
          });
    } catch (const std::exception& e) {
      job->fail_unexpectedly(e.what());
    } catch (...) {
      job->fail_unexpectedly("unexpected error of unknown type");
    }
  });
}

std::size_t AuditJobs::resume_unfinished() {
  if (!checkpoints_) return 0;
  auto unfinished = checkpoints_->unfinished();
  if (!unfinished.ok()) {
    spdlog::warn("unfinished audits cannot be read: {}", unfinished.error().to_string());
    return 0;
  }
  std::size_t queued = 0;
  for (UnfinishedAudit& u : unfinished.value()) {
    if (!u.unreadable.empty()) {
      // Nothing to run: it ends FAILED, archived, and its checkpoint goes.
      AuditSnapshot failed;
      failed.status = AuditStatus::kFailed;
      failed.message = "the audit could not be resumed after a restart: " + u.unreadable;
      auto job = AuditJob::restored(u.scene, failed, {}, {});
      {
        std::lock_guard<std::mutex> lock(mutex_);
        jobs_[u.job_id] = job;
      }
      if (archive_ && archive_->save(u.job_id, *job, failed).ok()) {
        archived(u.job_id);
        (void)checkpoints_->forget(u.job_id);
      }
      spdlog::warn("audit {} not resumed: {}", u.job_id, u.unreadable);
      continue;
    }
    // The baseline must have ended DONE; one that is itself being resumed (its archive write had
    // failed) is not a baseline yet.
    std::shared_ptr<const AuditJob> baseline;
    if (!u.baseline_job_id.empty()) {
      auto base = get(u.baseline_job_id);
      if (base.ok() && base.value()->snapshot().status == AuditStatus::kDone) baseline = base.value();
    }
    auto job = std::make_shared<AuditJob>(u.scene, u.options, baseline);
    const std::size_t finished = u.tiles.size();
    // A re-audit whose baseline cannot be used is done as a full audit (whose answer a re-audit
    // equals), from scratch: its tiles were the re-audit's.
    if (u.baseline_job_id.empty() || baseline) job->resume_from(std::move(u.tiles));
    if (u.cancelled) job->cancel();  // ends CANCELLED at once, with the finished tiles' clashes
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jobs_[u.job_id] = job;
    }
    if (submit(u.job_id, job)) {
      ++queued;
      spdlog::info("audit {} resumed from {} finished tiles{}", u.job_id, finished, u.cancelled ? " (cancelled: it ends so)" : "");
    } else {
      remove(u.job_id);
      spdlog::warn("audit {} not resumed: the audit queue is full; its checkpoint stays for the next start", u.job_id);
    }
  }
  return queued;
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

std::size_t AuditJobs::running() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t n = 0;
  for (const auto& [id, job] : jobs_) n += job->running() ? 1 : 0;
  return n;
}

Result<std::shared_ptr<AuditJob>> AuditJobs::cancel(const std::string& id) {
  auto job = get(id);
  if (!job.ok()) return job;
  if (checkpoints_ && job.value()->running()) {
    auto kept = checkpoints_->cancelled(id);
    if (!kept.ok()) spdlog::warn("audit {}: the cancel is not kept for a restart: {}", id, kept.error().to_string());
  }
  job.value()->cancel();
  return job;
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

}  // namespace gk::engine
