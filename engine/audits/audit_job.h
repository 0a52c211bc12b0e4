// The interference audit of a scene (engine/audits/scene_audit on a snapshot of it) as a cancellable
// job with progress; a CAD pair within its deflection is decided again on the exact faces.
#pragma once

#include "engine/parts/part_registry.h"
#include "engine/scenes/scene_store.h"
#include "kernel/query/contact_verdict.h"
#include "engine/audits/scene_audit.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace gk::engine {

// A clash between two scene objects: the kernel's answer and who they are.
struct ClashRecord {
  std::string a, b;  // object ids, a < b
  std::string name_a, name_b, category_a, category_b;
  PairClash clash;   // a/b there are indices into the audited object list
  bool decided_on_brep = false;  // a CAD part within its deflection: decided on the exact faces
  std::string reason;            // what decided it (exact faces), or why it is INCONCLUSIVE
};

// An audited object as the report shows it.
struct AuditedObject {
  std::string id, name, category;
  Aabb box;
};

enum class AuditStatus { kRunning, kDone, kCancelled, kFailed };

// Runs a job's audit elsewhere (server/audit_handoff: a distributed driver): given the job's id,
// its scene snapshot, the placed objects and the options (with the job's cancel flag, progress,
// clash and tile callbacks and the tiles to skip), returns what audit_scene would.
using AuditRunner = std::function<Result<AuditResult>(const std::string& job_id, const SceneRecord& snapshot,
                                                      const std::vector<AuditObject>& objects, const AuditOptions& options)>;

struct AuditSnapshot {
  AuditStatus status = AuditStatus::kRunning;
  unsigned long long tiles_total = 0, tiles_done = 0;
  unsigned long long pairs_total = 0, pairs_done = 0;
  std::vector<ClashRecord> clashes;  // as found while running; in (a, b) order once ended
  double elapsed_s = 0.0, eta_s = 0.0;
  std::string message;
  unsigned long long candidate_pairs = 0, excluded_by_rules = 0, objects = 0, triangles = 0;
  double broad_s = 0.0, narrow_s = 0.0;
  bool reaudit = false;
};

// One audit job (engine/audits/scene_audit on the scene's snapshot): runs on a worker, can be cancelled,
// keeps its results (partial if cancelled). With a finished baseline job it is a re-audit.
class AuditJob {
 public:
  // options: what to compute (clearance, rules, tiles, threads, depth, volume); the job adds its
  // cancellation flag and progress reporting.
  AuditJob(SceneRecord scene, AuditOptions options, std::shared_ptr<const AuditJob> baseline = nullptr)
      : scene_(std::move(scene)), options_(std::move(options)), baseline_(std::move(baseline)) {}
  // A job that ended before the daemon restarted, as the archive kept it.
  static std::shared_ptr<AuditJob> restored(SceneRecord scene, AuditSnapshot snapshot, std::vector<AuditedObject> objects,
                                            std::vector<std::string> answer_options);
  // The options the answers depend on, each "name=value" (clearance, rules, depth, volume, region
  // merge, contacts kept): a re-audit may reuse a baseline's answers only when they are equal.
  // (Tiles and threads change how the work is split, never the answers.)
  std::vector<std::string> answer_options() const;
  // on_end sees the final state before it is published (the daemon archives it there); on_tile
  // each finished tile (for checkpoints: scene_audit's on_tile_done).
  // `runner` (when given) audits in its place; a re-audit always runs here.
  void run(PartRegistry& parts, std::function<void(const AuditSnapshot&)> on_end = {},
           std::function<void(std::size_t, const std::vector<PairClash>&)> on_tile = {},
           const std::function<Result<AuditResult>(const std::vector<AuditObject>&, const AuditOptions&)>& runner = {});
  // Before run: tiles an earlier run of this job finished (from its checkpoint), not computed again.
  void resume_from(std::map<std::size_t, std::vector<PairClash>> finished_tiles) { finished_tiles_ = std::move(finished_tiles); }
  void cancel() { cancelled_ = true; }
  // The daemon is stopping: the job ends like a cancelled one, but is marked interrupted, so that
  // its checkpoint is kept and it resumes when the daemon starts again.
  void interrupt() {
    if (cancelled_.exchange(true)) return;  // cancelled by a client before: it stays cancelled
    interrupted_ = true;
  }
  bool interrupted() const { return interrupted_; }
  const AuditOptions& options() const { return options_; }
  // The job's run threw: it ends FAILED with this message (unless it had ended already).
  void fail_unexpectedly(const std::string& message);
  AuditSnapshot snapshot() const;
  bool running() const;  // cheap (snapshot() copies the clashes)
  // Waits until the progress changes (or timeout); returns the snapshot.
  AuditSnapshot wait_for_change(unsigned long long seen_done, AuditStatus seen_status, std::chrono::milliseconds timeout) const;
  // Watchers are told of every change (called on the thread that made it, never under the job's
  // state lock). At most kMaxWatchers at once: subscribe returns 0 beyond. Unsubscribe returns
  // only once no call to that watcher is running, so the watcher may be destroyed then.
  static constexpr std::size_t kMaxWatchers = 64;
  std::uint64_t subscribe(std::function<void()> on_change);
  void unsubscribe(std::uint64_t token);
  const SceneRecord& scene() const { return scene_; }
  std::vector<AuditedObject> objects() const;

 private:
  void update(const std::function<void(AuditSnapshot&)>& change);
  void fail(const Error& error);
  void end(const std::function<void(AuditSnapshot&)>& change);
  std::function<void(const AuditSnapshot&)> on_end_;
  SceneRecord scene_;
  AuditOptions options_;
  std::vector<std::string> restored_answer_options_;  // for a restored job (its options are not kept)
  std::shared_ptr<const AuditJob> baseline_;
  std::atomic<bool> cancelled_{false};
  std::atomic<bool> interrupted_{false};
  std::map<std::size_t, std::vector<PairClash>> finished_tiles_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::mutex watchers_mutex_;
  std::map<std::uint64_t, std::function<void()>> watchers_;
  std::uint64_t next_watcher_ = 1;
  AuditSnapshot state_;
  std::vector<AuditedObject> objects_;
};

}  // namespace gk::engine
