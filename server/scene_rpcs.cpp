// The scene and audit RPCs of GatekeeperService: scenes a layout tool edits and drags objects
// through, and interference audits of a scene run as jobs.
#include "server/gatekeeper_service.h"

#include "server/access_control.h"
#include "server/audit_report.h"
#include "server/audit_report_page.h"
#include "server/proto_convert.h"
#include "server/rpc_helpers.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <set>
#include <thread>

namespace gk::server {
namespace {

// The drag stream: each move is stored and answered with its contacts before the next is read.
// A frame's work runs on the scene pool like a unary move (gRPC's callback thread only hands it
// over); a full pool ends the stream with RESOURCE_EXHAUSTED, a cancelled client skips the work.
class DragReactor final : public grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult> {
 public:
  DragReactor(GatekeeperService& service, grpc::CallbackServerContext* ctx) : service_(service), ctx_(ctx) {
    StartRead(&request_);
  }
  void OnReadDone(bool ok) override {
    if (!ok) return Finish(grpc::Status::OK);  // the client is done dragging
    const auto t0 = Clock::now();
    const bool queued = service_.scene_pool().try_submit([this, t0] { answer_frame(t0); });
    if (!queued) {
      service_.stats().record("DragObject.move", us_since(t0), true);
      Finish({grpc::StatusCode::RESOURCE_EXHAUSTED, "DragObject: too much scene work queued, retry later"});
    }
  }
  void OnWriteDone(bool ok) override {
    if (!ok) return Finish({grpc::StatusCode::CANCELLED, "the client went away"});
    StartRead(&request_);
  }
  void OnDone() override { delete this; }

 private:
  // On a scene worker: the frame's move and contacts, then its reply (or the stream's end).
  void answer_frame(Clock::time_point t0) {
    if (ctx_->IsCancelled()) return Finish({grpc::StatusCode::CANCELLED, "cancelled by the client"});
    reply_.Clear();
    const grpc::Status s = guarded_status("DragObject", [&] { return service_.move(request_, &reply_, &session_); });
    service_.stats().record("DragObject.move", us_since(t0), !s.ok());
    if (!s.ok()) return Finish(s);
    StartWrite(&reply_);
  }

  GatekeeperService& service_;
  grpc::CallbackServerContext* ctx_;
  pb::MoveObjectRequest request_;
  pb::MoveResult reply_;
  DragSession session_;
};

// A client-named object id (empty: assigned), and its labels.
Result<bool> check_object(const pb::SceneObject& in, const std::string& field) {
  if (!in.object_id().empty())
    if (auto bad = check_id(in.object_id(), field + ".object_id"); !bad.ok()) return bad;
  for (const auto& [text, name] : {std::pair<const std::string*, const char*>{&in.name(), ".name"}, {&in.category(), ".category"},
                                   {&in.group(), ".group"}})
    if (auto bad = check_label(*text, field + name); !bad.ok()) return bad;
  return true;
}

// Streams an audit's progress until it ends; the job itself runs whether or not anyone watches.
// Driven by the job's change notifications: no thread of its own. A change that arrives while a
// write is in flight is coalesced into one write of the latest state when that write completes.
class WatchReactor final : public grpc::ServerWriteReactor<pb::AuditProgress> {
 public:
  WatchReactor(std::shared_ptr<AuditJob> job, std::string job_id) : job_(std::move(job)), id_(std::move(job_id)) {
    std::lock_guard<std::recursive_mutex> lock(mutex_);
    token_ = job_->subscribe([this] { on_change(); });
    if (token_ == 0) {
      finished_ = true;
      Finish({grpc::StatusCode::RESOURCE_EXHAUSTED, "too many watchers of this audit: retry later"});
      return;
    }
    write_latest();
  }
  void OnWriteDone(bool ok) override {
    std::lock_guard<std::recursive_mutex> lock(mutex_);
    writing_ = false;
    if (finished_) return;
    if (!ok) return finish({grpc::StatusCode::CANCELLED, "the client went away"});
    if (last_status_ != AuditStatus::kRunning) return finish(grpc::Status::OK);
    if (pending_) write_latest();
  }
  void OnCancel() override {
    std::lock_guard<std::recursive_mutex> lock(mutex_);
    if (!finished_ && !writing_) finish({grpc::StatusCode::CANCELLED, "cancelled"});
    cancelled_ = true;
  }
  void OnDone() override {
    if (token_ != 0) job_->unsubscribe(token_);  // no call to on_change runs after this
    delete this;
  }

 private:
  void on_change() {
    std::lock_guard<std::recursive_mutex> lock(mutex_);
    if (finished_) return;
    if (writing_) {
      pending_ = true;
      return;
    }
    write_latest();
  }
  // Under mutex_: writes the job's current state unless nothing changed since the last write.
  void write_latest() {
    pending_ = false;
    if (cancelled_) return finish({grpc::StatusCode::CANCELLED, "cancelled"});
    const AuditSnapshot s = job_->snapshot();
    if (written_ && s.pairs_done == last_done_ && s.status == last_status_ && s.tiles_done == last_tiles_) return;
    written_ = true;
    last_done_ = s.pairs_done;
    last_tiles_ = s.tiles_done;
    last_status_ = s.status;
    progress_.Clear();
    progress_to_proto(id_, s, &progress_);
    writing_ = true;
    StartWrite(&progress_);
  }
  void finish(const grpc::Status& status) {
    finished_ = true;
    Finish(status);
  }

  std::shared_ptr<AuditJob> job_;
  std::string id_;
  std::uint64_t token_ = 0;
  std::recursive_mutex mutex_;  // a reaction may run inline from StartWrite
  bool writing_ = false, pending_ = false, finished_ = false, cancelled_ = false, written_ = false;
  unsigned long long last_done_ = 0, last_tiles_ = 0;
  AuditStatus last_status_ = AuditStatus::kRunning;
  pb::AuditProgress progress_;
};

}  // namespace

grpc::ServerUnaryReactor* GatekeeperService::CreateScene(grpc::CallbackServerContext* ctx, const pb::CreateSceneRequest* request,
                                                         pb::SceneInfo* response) {
  return unary(ctx, stats_, "CreateScene", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    if (auto bad = check_label(request->name(), "name"); !bad.ok()) return to_status(bad.error());
    auto scene = scenes_.create(request->name());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::Status GatekeeperService::move(const pb::MoveObjectRequest& request, pb::MoveResult* response, DragSession* drag,
                                     const StopToken& stop) {
  const auto t0 = Clock::now();
  auto pose = to_stored_pose(request.pose(), "pose");
  if (!pose.ok()) return to_status(pose.error());
  if (!std::isfinite(request.clearance_mm()) || request.clearance_mm() < 0.0)
    return {grpc::StatusCode::INVALID_ARGUMENT, "clearance_mm: must be a finite distance >= 0"};
  auto moved = scenes_.move(request.scene_id(), request.object_id(), pose.value());
  if (!moved.ok()) return to_status(moved.error());
  return contacts(request.scene_id(), request.object_id(), request.clearance_mm(), pose.value().transform(), drag, t0, response,
                  stop);
}

grpc::Status GatekeeperService::contacts(const std::string& scene_id, const std::string& object_id, double clearance_mm,
                                         const RigidTransform& pose, DragSession* drag, Clock::time_point t0,
                                         pb::MoveResult* response, const StopToken& stop) {
  Result<MoveOutcome> outcome = Error{};
  if (drag) {
    auto version = scenes_.version(scene_id);
    if (!version.ok()) return to_status(version.error());
    outcome = drag->move(scene_id, version.value(), [&] { return scenes_.get(scene_id); }, object_id, clearance_mm, pose, parts_);
  } else {
    auto scene = scenes_.get(scene_id);
    if (!scene.ok()) return to_status(scene.error());
    outcome = object_contacts(scene.value(), object_id, clearance_mm, parts_, stop);
  }
  if (!outcome.ok()) return to_status(outcome.error());
  response->set_object_id(object_id);
  response->set_verdict(to_proto(outcome.value().verdict));
  response->set_candidates(outcome.value().candidates);
  for (const ObjectContactResult& c : outcome.value().contacts) {
    pb::ObjectContact* o = response->add_contacts();
    o->set_other_object_id(c.other);
    o->set_verdict(to_proto(c.verdict));
    o->set_distance_mm(c.distance_mm);
    to_proto(c.point, o->mutable_point());
    to_proto(c.other_point, o->mutable_other_point());
    o->set_inconclusive_reason(to_proto(c.inconclusive_reason));
    o->set_decided_on_brep(c.decided_on_brep);
  }
  response->set_elapsed_us(us_since(t0));
  return grpc::Status::OK;
}

grpc::ServerUnaryReactor* GatekeeperService::PutObject(grpc::CallbackServerContext* ctx, const pb::PutObjectRequest* request,
                                                       pb::MoveResult* response) {
  return run_queued(scene_pool_, stats_, ctx, "PutObject", request, response,
                    [this, ctx](const pb::PutObjectRequest& put, pb::MoveResult* out) -> grpc::Status {
    const auto t0 = Clock::now();
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    const pb::SceneObject& in = put.object();
    if (auto bad = check_object(in, "object"); !bad.ok()) return to_status(bad.error());
    auto part = parts_.store().get(in.part_id());
    if (!part.ok()) return to_status(Error{part.error().code, "object.part_id", part.error().message});
    auto pose = to_stored_pose(in.pose(), "object.pose");
    if (!pose.ok()) return to_status(pose.error());
    if (!std::isfinite(put.clearance_mm()) || put.clearance_mm() < 0.0)
      return {grpc::StatusCode::INVALID_ARGUMENT, "clearance_mm: must be a finite distance >= 0"};
    auto stored = scenes_.put(put.scene_id(), {in.object_id(), in.name(), in.category(), in.part_id(), pose.value(), in.group()});
    if (!stored.ok()) return to_status(stored.error());
    // Stored once; then the new object's contacts, as a move would answer them.
    const StopToken stop([ctx] { return ctx->IsCancelled() || past_deadline(ctx); });
    return contacts(put.scene_id(), stored.value().id, put.clearance_mm(), pose.value().transform(), nullptr, t0, out, stop);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::PutObjects(grpc::CallbackServerContext* ctx, const pb::PutObjectsRequest* request,
                                                        pb::PutObjectsResponse* response) {
  return run_queued(record_pool_, stats_, ctx, "PutObjects", request, response,
                    [this, ctx](const pb::PutObjectsRequest& put, pb::PutObjectsResponse* out) -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    // Every object is checked before anything is stored, so a bad one leaves the scene as it was.
    std::vector<SceneObjectRecord> objects;
    std::set<std::string> known_parts;
    for (int i = 0; i < put.objects_size(); ++i) {
      const pb::SceneObject& in = put.objects(i);
      const std::string field = "objects[" + std::to_string(i) + "]";
      if (auto bad = check_object(in, field); !bad.ok()) return to_status(bad.error());
      if (!known_parts.count(in.part_id())) {
        auto part = parts_.store().get(in.part_id());
        if (!part.ok()) return grpc::Status(to_status(Error{part.error().code, field + ".part_id", part.error().message}));
        known_parts.insert(in.part_id());
      }
      auto pose = to_stored_pose(in.pose(), field + ".pose");
      if (!pose.ok()) return grpc::Status(to_status(pose.error()));
      objects.push_back({in.object_id(), in.name(), in.category(), in.part_id(), pose.value(), in.group()});
    }
    auto stored = scenes_.put_many(put.scene_id(), std::move(objects));
    if (!stored.ok()) return grpc::Status(to_status(stored.error()));
    for (const SceneObjectRecord& o : stored.value()) out->add_object_ids(o.id);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::MoveObject(grpc::CallbackServerContext* ctx, const pb::MoveObjectRequest* request,
                                                        pb::MoveResult* response) {
  return run_queued(scene_pool_, stats_, ctx, "MoveObject", request, response,
                    [this, ctx](const pb::MoveObjectRequest& r, pb::MoveResult* out) -> grpc::Status {
                      if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
                      const StopToken stop([ctx] { return ctx->IsCancelled() || past_deadline(ctx); });
                      return grpc::Status(move(r, out, nullptr, stop));
                    });
}

grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult>* GatekeeperService::DragObject(grpc::CallbackServerContext* ctx) {
  if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) {
    stats_.record("DragObject", 0.0, true);
    return new RefusedStream<grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult>>(allowed);
  }
  return new DragReactor(*this, ctx);
}

grpc::ServerUnaryReactor* GatekeeperService::DeleteObject(grpc::CallbackServerContext* ctx, const pb::DeleteObjectRequest* request,
                                                          pb::SceneInfo* response) {
  return unary(ctx, stats_, "DeleteObject", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto scene = scenes_.remove(request->scene_id(), request->object_id());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetScene(grpc::CallbackServerContext* ctx, const pb::GetSceneRequest* request,
                                                      pb::SceneInfo* response) {
  return unary(ctx, stats_, "GetScene", [&]() -> grpc::Status {
    auto scene = scenes_.get(request->scene_id());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::StartAudit(grpc::CallbackServerContext* ctx, const pb::StartAuditRequest* request,
                                                        pb::AuditJob* response) {
  const auto t0 = Clock::now();
  if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return finish(ctx, stats_, "StartAudit", t0, allowed);
  auto checked = to_audit_options(*request, options_.audit_threads);
  if (!checked.ok()) return finish(ctx, stats_, "StartAudit", t0, to_status(checked.error()));
  auto scene = scenes_.get(request->scene_id());
  if (!scene.ok()) return finish(ctx, stats_, "StartAudit", t0, to_status(scene.error()));
  std::shared_ptr<const AuditJob> baseline;
  if (!request->baseline_job_id().empty()) {
    auto base = audits_.get(request->baseline_job_id());
    if (!base.ok()) return finish(ctx, stats_, "StartAudit", t0, to_status(Error{base.error().code, "baseline_job_id", base.error().message}));
    if (base.value()->scene().id != request->scene_id())
      return finish(ctx, stats_, "StartAudit", t0, {grpc::StatusCode::INVALID_ARGUMENT, "baseline_job_id: audited another scene"});
    if (base.value()->snapshot().status != AuditStatus::kDone)
      return finish(ctx, stats_, "StartAudit", t0, {grpc::StatusCode::FAILED_PRECONDITION, "baseline_job_id: has not finished"});
    // The baseline's answers carry over only when they were computed with the same options.
    const std::vector<std::string> then = base.value()->answer_options();
    const std::vector<std::string> now = AuditJob(scene.value(), checked.value()).answer_options();
    for (std::size_t i = 0; i < now.size(); ++i)
      if (i >= then.size() || then[i] != now[i]) {
        const std::string name = now[i].substr(0, now[i].find('='));
        return finish(ctx, stats_, "StartAudit", t0,
                      {grpc::StatusCode::FAILED_PRECONDITION,
                       name + ": the baseline was audited with " + (i < then.size() ? then[i] : std::string("unknown options")) +
                           ", this audit asks " + now[i] + "; re-audit against a baseline with the same options, or audit in full"});
      }
    baseline = base.value();
  }
  auto job = std::make_shared<AuditJob>(scene.value(), checked.value(), baseline);
  const std::string id = audits_.add(job);
  PartRegistry* parts = &parts_;
  AuditArchive* archive = archive_;
  AuditJobs* audits = &audits_;
  if (!audit_pool_.try_submit([job, id, parts, archive, audits] {
        const grpc::Status ran = guarded_status("StartAudit", [&] {
          job->run(*parts, [&](const AuditSnapshot& final_state) {
            if (!archive) return;
            auto saved = archive->save(id, *job, final_state);
            if (!saved.ok()) spdlog::warn("audit {} not archived (kept in memory): {}", id, saved.error().to_string());
            else audits->archived(id);
          });
          return grpc::Status::OK;
        });
        if (!ran.ok()) job->fail_unexpectedly(ran.error_message());
      })) {
    audits_.remove(id);
    return finish(ctx, stats_, "StartAudit", t0, {grpc::StatusCode::RESOURCE_EXHAUSTED, "audit queue full: retry later"});
  }
  response->set_job_id(id);
  return finish(ctx, stats_, "StartAudit", t0, grpc::Status::OK);
}

grpc::ServerWriteReactor<pb::AuditProgress>* GatekeeperService::WatchAudit(grpc::CallbackServerContext* /*ctx*/,
                                                                          const pb::WatchAuditRequest* request) {
  auto job = audits_.get(request->job_id());
  if (!job.ok()) {
    struct Refused : grpc::ServerWriteReactor<pb::AuditProgress> {
      explicit Refused(const grpc::Status& s) { Finish(s); }
      void OnDone() override { delete this; }
    };
    return new Refused(to_status(job.error()));
  }
  return new WatchReactor(job.value(), request->job_id());
}

grpc::ServerUnaryReactor* GatekeeperService::CancelAudit(grpc::CallbackServerContext* ctx, const pb::CancelAuditRequest* request,
                                                         pb::AuditProgress* response) {
  return unary(ctx, stats_, "CancelAudit", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto job = audits_.get(request->job_id());
    if (!job.ok()) return grpc::Status(to_status(job.error()));
    job.value()->cancel();
    progress_to_proto(request->job_id(), job.value()->snapshot(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetAuditReport(grpc::CallbackServerContext* ctx,
                                                            const pb::GetAuditReportRequest* request, pb::AuditReport* response) {
  // Read back from the archive when evicted, and rendered as a page on request: off the callback thread.
  return run_queued(record_pool_, stats_, ctx, "GetAuditReport", request, response,
                    [this](const pb::GetAuditReportRequest& get, pb::AuditReport* out) -> grpc::Status {
    auto job = audits_.get(get.job_id());
    if (!job.ok()) return grpc::Status(to_status(job.error()));
    const AuditSnapshot snapshot = job.value()->snapshot();
    progress_to_proto(get.job_id(), snapshot, out->mutable_progress());
    report_to_proto(snapshot, out);
    if (get.html()) out->set_html(audit_report_page(*out, job.value()->scene().name, job.value()->objects()));
    return grpc::Status(grpc::Status::OK);
  });
}

}  // namespace gk::server
