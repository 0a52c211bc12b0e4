// What the kernel says about a scene: the contacts of one object against its neighbours (each
// move of a drag), and the interference audit of every pair, as a cancellable job with progress.
#pragma once

#include "kernel/stop_token.h"
#include "engine/pair_verdict.h"
#include "kernel/contact_verdict.h"
#include "kernel/layout_session.h"
#include "kernel/scene_audit.h"
#include "server/part_registry.h"
#include "server/scene_store.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace gk::server {

struct ObjectContactResult {
  std::string other;
  Verdict verdict = Verdict::kClear;
  double distance_mm = 0.0;
  Vec3 point = Vec3::Zero(), other_point = Vec3::Zero();
  InconclusiveReason inconclusive_reason = InconclusiveReason::kNone;
  bool decided_on_brep = false;
};

struct MoveOutcome {
  Verdict verdict = Verdict::kClear;  // the worst over the neighbours
  std::vector<ObjectContactResult> contacts;
  unsigned candidates = 0;
};

// A scene's objects ready for the kernel, in id order: one mesh and BVH per part, shared by every
// copy (instancing), each at its pose.
struct PlacedScene {
  std::vector<AuditObject> objects;
  std::vector<std::shared_ptr<const LoadedPart>> parts;  // each object's part (its exact B-Rep for CAD)
  std::vector<const SceneObjectRecord*> records;  // into the SceneRecord it was placed from
  std::vector<Aabb> boxes;
  std::map<std::string, std::uint32_t> index_of;
};
Result<PlacedScene> place_scene(const SceneRecord& scene, PartRegistry& parts);

// A drag stream's layout session (kernel/layout_session): built on the first move of an object,
// kept while the stream drags the same object with the same clearance and nobody else edits the
// scene, rebuilt otherwise.
class DragSession {
 public:
  // After the move is stored: the scene's version then, and how to read the whole scene (only
  // called when the session must be rebuilt: a copy of 10,000 objects costs milliseconds).
  Result<MoveOutcome> move(const std::string& scene_id, std::uint64_t scene_version,
                           const std::function<Result<SceneRecord>()>& read_scene, const std::string& object_id,
                           double clearance_mm, const RigidTransform& pose, PartRegistry& parts);

 private:
  std::unique_ptr<LayoutSession> session_;
  std::vector<std::shared_ptr<const LoadedPart>> parts_;  // object index -> part
  std::vector<std::string> ids_;  // object index -> id
  std::string scene_id_, object_id_;
  double clearance_mm_ = -1.0;
  std::uint64_t version_ = 0;     // the scene version the session reflects
};

// The object against every other object of the scene: those whose boxes (grown by clearance_mm)
// meet get an exact verdict; colliding, touching or closer-than-clearance ones are reported.
// `stop`: a caller that gave up (deadline, cancel) ends the work (kStopped).
Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts, const StopToken& stop = {});

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

// One audit job (kernel/scene_audit on the scene's snapshot): runs on a worker, can be cancelled,
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
  // on_end sees the final state before it is published (the daemon archives it there).
  void run(PartRegistry& parts, std::function<void(const AuditSnapshot&)> on_end = {});
  void cancel() { cancelled_ = true; }
  // The job's run threw: it ends FAILED with this message (unless it had ended already).
  void fail_unexpectedly(const std::string& message);
  AuditSnapshot snapshot() const;
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
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::mutex watchers_mutex_;
  std::map<std::uint64_t, std::function<void()>> watchers_;
  std::uint64_t next_watcher_ = 1;
  AuditSnapshot state_;
  std::vector<AuditedObject> objects_;
};

// The audit jobs: running ones in memory, ended ones archived (AuditArchive) and kept in memory only
// up to a count, the least recently read dropped first and read again from the archive on demand
// (a watcher or a report being written holds its job alive meanwhile). New ids never repeat an old
// one: they carry this daemon's start time.
class AuditArchive;

class AuditJobs {
 public:
  // archive may be null (nothing is then dropped: an ended job lives only in memory).
  explicit AuditJobs(const AuditArchive* archive = nullptr, std::size_t ended_in_memory = 16)
      : archive_(archive), ended_in_memory_(std::max<std::size_t>(1, ended_in_memory)) {}
  std::string add(std::shared_ptr<AuditJob> job);
  // The job ended and is safely archived: from now on it may be dropped from memory.
  void archived(const std::string& id);
  void remove(const std::string& id);
  // Every job still running stops (the daemon is stopping): each ends CANCELLED with the pairs it
  // finished, archived like any ended job.
  void cancel_all();
  Result<std::shared_ptr<AuditJob>> get(const std::string& id);
  std::size_t in_memory() const;

 private:
  void drop_beyond_limit();  // mutex_ held
  const AuditArchive* archive_;
  const std::size_t ended_in_memory_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<AuditJob>> jobs_;
  std::list<std::string> ended_;  // archived jobs in memory, least recently read first
  unsigned long long counter_ = 0;
  long long epoch_ms_ = std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::system_clock::now().time_since_epoch()).count();
};

}  // namespace gk::server
