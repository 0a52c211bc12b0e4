// What the kernel says about a scene: the contacts of one object against its neighbours (each
// move of a drag), and the interference audit of every pair, as a cancellable job with progress.
#pragma once

#include "kernel/contact_verdict.h"
#include "server/part_registry.h"
#include "server/scene_store.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
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
};

struct MoveOutcome {
  Verdict verdict = Verdict::kClear;  // the worst over the neighbours
  std::vector<ObjectContactResult> contacts;
  unsigned candidates = 0;
};

// The object against every other object of the scene: those whose boxes (grown by clearance_mm)
// meet get an exact verdict; colliding, touching or closer-than-clearance ones are reported.
Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts);

struct ClashRecord {
  std::string a, b;
  Verdict verdict = Verdict::kClear;
  double distance_mm = 0.0;
  Vec3 point = Vec3::Zero();
  unsigned contact_pairs = 0;
};

enum class AuditStatus { kRunning, kDone, kCancelled, kFailed };

struct AuditSnapshot {
  AuditStatus status = AuditStatus::kRunning;
  unsigned long long pairs_total = 0, pairs_done = 0;
  std::vector<ClashRecord> clashes;
  double elapsed_s = 0.0, eta_s = 0.0;
  std::string message;
};

// One audit job: runs on a worker, can be cancelled, keeps its results (partial if cancelled).
class AuditJob {
 public:
  AuditJob(SceneRecord scene, double clearance_mm) : scene_(std::move(scene)), clearance_mm_(clearance_mm) {}
  void run(PartRegistry& parts);
  void cancel() { cancelled_ = true; }
  AuditSnapshot snapshot() const;
  // Waits until the progress changes (or timeout); returns the snapshot.
  AuditSnapshot wait_for_change(unsigned long long seen_done, AuditStatus seen_status, std::chrono::milliseconds timeout) const;

 private:
  void update(const std::function<void(AuditSnapshot&)>& change);
  SceneRecord scene_;
  double clearance_mm_;
  std::atomic<bool> cancelled_{false};
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  AuditSnapshot state_;
};

class AuditJobs {
 public:
  std::string add(std::shared_ptr<AuditJob> job);
  Result<std::shared_ptr<AuditJob>> get(const std::string& id) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<AuditJob>> jobs_;
  unsigned long long counter_ = 0;
};

}  // namespace gk::server
