// The audit jobs of a daemon: running ones in memory, ended ones kept by an EndedAudits store.
#pragma once

#include "engine/audits/audit_checkpoints.h"
#include "engine/audits/clash_statuses.h"
#include "engine/audits/audit_job.h"
#include "engine/audits/ended_audits.h"
#include "engine/parts/part_registry.h"
#include "engine/work_pool.h"

#include <algorithm>
#include <chrono>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace gk::engine {

// The audit jobs: running ones in memory, ended ones archived (AuditArchive) and kept in memory only
// up to a count, the least recently read dropped first and read again from the archive on demand
// (a watcher or a report being written holds its job alive meanwhile). New ids never repeat an old
// one: they carry this daemon's start time.
class AuditJobs {
 public:
  struct Options {
    std::size_t ended_in_memory = 16;  // ended jobs kept in memory (the rest are read back when asked for)
    int concurrent = 1;                // audits run at once, on their own threads
    std::size_t queued = 16;           // audits waiting; beyond, start() is refused (kResourceExhausted)
    // Audits of scenes with at least this many triangles (counted per object) are run by
    // large_audits (a distributed driver), when one is given; re-audits always run here.
    AuditRunner large_audits;
    std::size_t large_audit_min_triangles = 0;
  };
  // archive may be null (nothing is then dropped: an ended job lives only in memory); checkpoints
  // may be null (a running job is then lost when the daemon stops).
  // statuses may be null: clashes then have no review status kept across audits.
  AuditJobs(PartRegistry& parts, EndedAudits* archive, Options options, AuditCheckpoints* checkpoints = nullptr,
            ClashStatuses* statuses = nullptr);
  ~AuditJobs();

  // A new audit of `scene` with `options`, or a re-audit against the finished job baseline_id
  // (same scene, same answer options: else FAILED_PRECONDITION naming the option). Runs on the
  // audit threads; returns its id at once.
  Result<std::string> start(const SceneRecord& scene, const AuditOptions& options, const std::string& baseline_id = "");
  std::string add(std::shared_ptr<AuditJob> job);
  // The job ended and is safely archived: from now on it may be dropped from memory.
  void archived(const std::string& id);
  void remove(const std::string& id);
  // A client cancels a job: it ends CANCELLED with the pairs it finished, also if the daemon stops
  // before it has ended (the checkpoint remembers the cancel).
  Result<std::shared_ptr<AuditJob>> cancel(const std::string& id);
  // Every job still running stops: each ends CANCELLED with the pairs it finished, archived like
  // any ended job.
  void cancel_all();
  // Stops the audit threads (the daemon is stopping). With checkpoints, what runs is interrupted:
  // not archived, its checkpoint kept, resumed by resume_unfinished() at the next start; without,
  // it ends CANCELLED and is archived.
  void stop();
  // Queues again every audit the checkpoints hold (a daemon stopped or killed while they ran),
  // under their old ids, skipping their finished tiles. Returns how many were queued.
  std::size_t resume_unfinished();
  Result<std::shared_ptr<AuditJob>> get(const std::string& id);
  std::size_t in_memory() const;
  std::size_t running() const;  // started and not ended (those waiting for an audit thread too)

 private:
  void drop_beyond_limit();  // mutex_ held
  // Queues a job under id: runs it, checkpoints its tiles, archives it when it ends.
  bool submit(const std::string& id, std::shared_ptr<AuditJob> job);
  PartRegistry& parts_;
  EndedAudits* archive_;
  const std::size_t ended_in_memory_;
  AuditRunner large_audits_;
  std::size_t large_audit_min_triangles_ = 0;
  AuditCheckpoints* checkpoints_;
  ClashStatuses* statuses_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<AuditJob>> jobs_;
  std::list<std::string> ended_;  // archived jobs in memory, least recently read first
  unsigned long long counter_ = 0;
  long long epoch_ms_ = std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::system_clock::now().time_since_epoch()).count();
  WorkPool pool_;  // declared last: its threads are joined before the members they use go
};

}  // namespace gk::engine
