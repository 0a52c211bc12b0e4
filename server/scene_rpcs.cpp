// The scene and audit RPCs of GatekeeperService: scenes a layout tool edits and drags objects
// through, and interference audits of a scene run as jobs.
#include "server/gatekeeper_service.h"

#include "server/access_control.h"
#include "server/audit_report.h"
#include "server/audit_report_page.h"
#include "server/proto_convert.h"
#include "server/rpc_helpers.h"

#include <atomic>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <thread>

namespace gk::server {
namespace {

// At most this many drag frames, over all streams, are answered on gRPC's own threads at once.
// Such a frame saves the hand-over to a scene worker and back, about a quarter of a heavy frame's
// round trip on this machine kind (docs/PERFORMANCE.md, "Layout frame"). It blocks that gRPC
// thread for one frame, so only short frames may: one whose session is built for this scene,
// object and clearance and whose parts are all meshes (DragSession::answers_on_triangles: usually
// a tenth of a millisecond, and it stops on the client's deadline or cancel). A stream's first
// frame, a switch of object, scene or clearance, and any CAD part go to the scene workers. (A
// frame can still place the scene again on a gRPC thread when another client edited the scene
// in the moment before it: one placement, milliseconds at 10,000 objects.)
constexpr int kDragFramesOnGrpcThreads = 1;

// The drag stream: each move is stored and answered with its contacts before the next is read.
// A frame's work runs on the scene pool like a unary move (gRPC's callback thread only hands it
// over), but for the frames above; a full pool ends the stream with RESOURCE_EXHAUSTED, a
// cancelled client skips the work.
class DragReactor final : public grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult> {
 public:
  // Each frame is counted as "DragObject.move" (its latency in RpcStats; no call line, a drag
  // sends one per rendered frame); the stream is one call with one call line at its end.
  DragReactor(GatekeeperService& service, grpc::CallbackServerContext* ctx)
      : service_(service), ctx_(ctx), call_(begin_call(ctx, "DragObject")) {
    StartRead(&request_);
  }
  void OnReadDone(bool ok) override {
    if (!ok) {  // the client is done dragging, or gone
      return end(ctx_->IsCancelled() ? grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client") : grpc::Status::OK);
    }
    const Call frame = begin_frame(call_, "DragObject.move");
    std::atomic<int>& on_grpc_threads = service_.drag_frames_on_grpc_threads();
    const bool short_frame = moved_ && session_.answers_on_triangles(request_.scene_id(), request_.object_id(), request_.clearance_mm());
    if (short_frame && on_grpc_threads.fetch_add(1) < kDragFramesOnGrpcThreads) {
      // The slot is given back before the reply is written: the next frame, read once the client
      // has the reply, must find it free (OnDone cannot run before this reaction returns).
      answer_frame(frame, &on_grpc_threads);
      return;
    }
    if (short_frame) on_grpc_threads.fetch_sub(1);
    const bool queued = service_.scene_pool().try_submit([this, frame] { answer_frame(frame); });
    if (!queued) {
      service_.stats().record(frame.method, us_since(frame.t0), true);
      end({grpc::StatusCode::RESOURCE_EXHAUSTED, "DragObject: too much scene work queued, retry later"});
    }
  }
  void OnWriteDone(bool ok) override {
    if (!ok) return end({grpc::StatusCode::CANCELLED, "the client went away"});
    StartRead(&request_);
  }
  void OnDone() override { delete this; }

 private:
  // On a scene worker (or a gRPC thread, holding `slot`, given back before the reply): the frame's
  // move and contacts, then its reply (or the stream's end).
  void answer_frame(const Call& frame, std::atomic<int>* slot = nullptr) {
    auto give_back = [slot] {
      if (slot) slot->fetch_sub(1);
    };
    if (ctx_->IsCancelled()) {
      service_.stats().record(frame.method, us_since(frame.t0), true);
      give_back();
      return end({grpc::StatusCode::CANCELLED, "cancelled by the client"});
    }
    reply_.Clear();
    const StopToken stop([this] { return ctx_->IsCancelled() || past_deadline(ctx_); });
    const grpc::Status s = guarded_status(frame, [&] { return service_.move(request_, &reply_, &session_, stop); });
    service_.stats().record(frame.method, us_since(frame.t0), !s.ok());
    moved_ = true;
    give_back();
    if (!s.ok()) return end(s);
    StartWrite(&reply_);
  }
  // The frames' poses were logged, not synced one by one: the stream ends once they are on disk.
  void end(const grpc::Status& status) {
    grpc::Status final_status = status;
    if (moved_) {
      auto synced = service_.engine().end_drag();
      if (!synced.ok() && status.ok())
        final_status = {grpc::StatusCode::UNAVAILABLE, "DragObject: the drag's poses could not be synced to disk: " +
                                                           synced.error().to_string()};
    }
    end_call(service_.stats(), call_, final_status);
    Finish(final_status);
  }

  GatekeeperService& service_;
  grpc::CallbackServerContext* ctx_;
  const Call call_;
  pb::MoveObjectRequest request_;
  pb::MoveResult reply_;
  DragSession session_;
  std::atomic<bool> moved_{false};  // a frame was stored (logged): the end syncs
};

SceneObjectRecord to_record(const pb::SceneObject& in) {
  return {in.object_id(), in.name(), in.category(), in.part_id(), to_stored_pose(in.pose()), in.group()};
}

// Streams an audit's progress until it ends; the job itself runs whether or not anyone watches.
// Driven by the job's change notifications: no thread of its own. A change that arrives while a
// write is in flight is coalesced into one write of the latest state when that write completes.
class WatchReactor final : public grpc::ServerWriteReactor<pb::AuditProgress> {
 public:
  WatchReactor(std::shared_ptr<AuditJob> job, std::string job_id, RpcStats& stats, Call call)
      : job_(std::move(job)), id_(std::move(job_id)), stats_(stats), call_(std::move(call)) {
    std::lock_guard<std::recursive_mutex> lock(mutex_);
    token_ = job_->subscribe([this] { on_change(); });
    if (token_ == 0) {
      finish({grpc::StatusCode::RESOURCE_EXHAUSTED, "too many watchers of this audit: retry later"});
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
    end_call(stats_, call_, status);
    Finish(status);
  }

  std::shared_ptr<AuditJob> job_;
  std::string id_;
  RpcStats& stats_;
  const Call call_;
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
    auto scene = engine_.create_scene(request->name());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::Status GatekeeperService::move(const pb::MoveObjectRequest& request, pb::MoveResult* response, DragSession* drag,
                                     const StopToken& stop) {
  const auto t0 = Clock::now();
  auto moved = engine_.move_object(request.scene_id(), request.object_id(), to_stored_pose(request.pose()), request.clearance_mm(),
                                   drag, stop);
  if (!moved.ok()) return to_status(moved.error());
  response->set_object_id(request.object_id());
  to_proto(moved.value(), response);
  response->set_elapsed_us(us_since(t0));
  return grpc::Status::OK;
}

grpc::ServerUnaryReactor* GatekeeperService::PutObject(grpc::CallbackServerContext* ctx, const pb::PutObjectRequest* request,
                                                       pb::MoveResult* response) {
  return run_queued(scene_pool_, stats_, ctx, "PutObject", request, response,
                    [this, ctx](const pb::PutObjectRequest& put, pb::MoveResult* out) -> grpc::Status {
    const auto t0 = Clock::now();
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    const StopToken stop([ctx] { return ctx->IsCancelled() || past_deadline(ctx); });
    auto placed = engine_.put_object(put.scene_id(), to_record(put.object()), put.clearance_mm(), stop);
    if (!placed.ok()) return to_status(placed.error());
    out->set_object_id(placed.value().object_id);
    to_proto(placed.value().outcome, out);
    out->set_elapsed_us(us_since(t0));
    return grpc::Status::OK;
  });
}

grpc::ServerUnaryReactor* GatekeeperService::PutObjects(grpc::CallbackServerContext* ctx, const pb::PutObjectsRequest* request,
                                                        pb::PutObjectsResponse* response) {
  return run_queued(record_pool_, stats_, ctx, "PutObjects", request, response,
                    [this, ctx](const pb::PutObjectsRequest& put, pb::PutObjectsResponse* out) -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    std::vector<SceneObjectRecord> objects;
    for (const pb::SceneObject& o : put.objects()) objects.push_back(to_record(o));
    // All or nothing: a bad object leaves the scene as it was.
    auto stored = engine_.put_objects(put.scene_id(), std::move(objects));
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
    end_call(stats_, begin_call(ctx, "DragObject"), allowed);
    return new RefusedStream<grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult>>(allowed);
  }
  return new DragReactor(*this, ctx);
}

grpc::ServerUnaryReactor* GatekeeperService::DeleteObject(grpc::CallbackServerContext* ctx, const pb::DeleteObjectRequest* request,
                                                          pb::SceneInfo* response) {
  return unary(ctx, stats_, "DeleteObject", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto scene = engine_.delete_object(request->scene_id(), request->object_id());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetScene(grpc::CallbackServerContext* ctx, const pb::GetSceneRequest* request,
                                                      pb::SceneInfo* response) {
  return unary(ctx, stats_, "GetScene", [&]() -> grpc::Status {
    auto scene = engine_.scene(request->scene_id());
    if (!scene.ok()) return grpc::Status(to_status(scene.error()));
    scene_to_proto(scene.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::StartAudit(grpc::CallbackServerContext* ctx, const pb::StartAuditRequest* request,
                                                        pb::AuditJob* response) {
  return unary(ctx, stats_, "StartAudit", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto asked = to_audit_options(*request);
    if (!asked.ok()) return to_status(asked.error());
    auto started = engine_.start_audit(request->scene_id(), asked.value(), request->baseline_job_id());
    if (!started.ok()) return to_status(started.error());
    response->set_job_id(started.value());
    return grpc::Status::OK;
  }, response);
}

grpc::ServerWriteReactor<pb::AuditProgress>* GatekeeperService::WatchAudit(grpc::CallbackServerContext* ctx,
                                                                          const pb::WatchAuditRequest* request) {
  Call call = begin_call(ctx, "WatchAudit");
  auto job = engine_.audit(request->job_id());
  if (!job.ok()) {
    const grpc::Status refused = to_status(job.error());
    end_call(stats_, call, refused);
    return new RefusedStream<grpc::ServerWriteReactor<pb::AuditProgress>>(refused);
  }
  return new WatchReactor(job.value(), request->job_id(), stats_, std::move(call));
}

grpc::ServerUnaryReactor* GatekeeperService::CancelAudit(grpc::CallbackServerContext* ctx, const pb::CancelAuditRequest* request,
                                                         pb::AuditProgress* response) {
  return unary(ctx, stats_, "CancelAudit", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto job = engine_.cancel_audit(request->job_id());
    if (!job.ok()) return grpc::Status(to_status(job.error()));
    progress_to_proto(request->job_id(), job.value()->snapshot(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetAuditReport(grpc::CallbackServerContext* ctx,
                                                            const pb::GetAuditReportRequest* request, pb::AuditReport* response) {
  // Read back from the archive when evicted, and rendered as a page on request: off the callback thread.
  return run_queued(record_pool_, stats_, ctx, "GetAuditReport", request, response,
                    [this](const pb::GetAuditReportRequest& get, pb::AuditReport* out) -> grpc::Status {
    auto job = engine_.audit(get.job_id());
    if (!job.ok()) return grpc::Status(to_status(job.error()));
    const AuditSnapshot snapshot = job.value()->snapshot();
    auto page = report_page(get, snapshot.clashes.size());
    if (!page.ok()) return grpc::Status(to_status(page.error()));
    progress_to_proto(get.job_id(), snapshot, out->mutable_progress());
    report_to_proto(snapshot, job.value()->scene().id, out, page.value().begin, page.value().end);
    auto statuses = engine_.clash_statuses(job.value()->scene().id);
    // The scene may be gone since the audit: its clashes then have no kept status.
    const std::vector<engine::ClashStatusRecord> kept = statuses.ok() ? statuses.value() : std::vector<engine::ClashStatusRecord>{};
    add_clash_statuses(kept, out);
    out->set_clashes_total(snapshot.clashes.size());
    out->set_page_offset(page.value().begin);
    out->set_next_page_token(page.value().next_token);
    if (get.html()) {
      // The page shows every clash, whichever page of them this reply holds.
      pb::AuditReport whole;
      progress_to_proto(get.job_id(), snapshot, whole.mutable_progress());
      report_to_proto(snapshot, job.value()->scene().id, &whole);
      add_clash_statuses(kept, &whole);
      // Every object in a clash is drawn with its part's mesh, thinned: about 300,000 triangles in
      // all, 50 to 20,000 a part, so at most 6,000 distinct parts (those of the first clashes in
      // the report's order); the other objects, and a part that cannot be loaded now, are boxes.
      constexpr std::size_t kPageTriangles = 300000, kPartTrianglesMin = 50, kPartTrianglesMax = 20000;
      const SceneRecord& audited = job.value()->scene();
      std::map<std::string, PlacedMesh> placed;
      std::set<std::string> part_ids;
      for (const pb::Clash& c : whole.clashes())
        for (const std::string& id : {c.object_a(), c.object_b()}) {
          const auto o = audited.objects.find(id);
          if (o == audited.objects.end()) continue;
          if (!part_ids.count(o->second.part_id) && part_ids.size() >= kPageTriangles / kPartTrianglesMin) continue;
          part_ids.insert(o->second.part_id);
          placed[id] = {o->second.part_id, o->second.pose.transform()};
        }
      const std::size_t per_part =
          std::clamp<std::size_t>(kPageTriangles / std::max<std::size_t>(part_ids.size(), 1), kPartTrianglesMin, kPartTrianglesMax);
      std::map<std::string, DisplayMesh> meshes;
      for (const std::string& part : part_ids) {
        auto mesh = engine_.display_mesh(part, per_part);
        if (mesh.ok()) meshes[part] = std::move(mesh).value();
      }
      out->set_html(audit_report_page(whole, audited.name, job.value()->objects(), meshes, placed));
    }
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::SetClashStatus(grpc::CallbackServerContext* ctx, const pb::SetClashStatusRequest* request,
                                                            pb::ClashStatusInfo* response) {
  return run_queued(record_pool_, stats_, ctx, "SetClashStatus", request, response,
                    [this, ctx](const pb::SetClashStatusRequest& set, pb::ClashStatusInfo* out) -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto status = clash_status_from_proto(set.status());
    if (!status.ok()) return grpc::Status(to_status(status.error()));
    auto stored = engine_.set_clash_status(set.scene_id(), set.clash_id(), status.value());
    if (!stored.ok()) return grpc::Status(to_status(stored.error()));
    status_to_proto(stored.value(), out);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::ListClashStatuses(grpc::CallbackServerContext* ctx,
                                                               const pb::ListClashStatusesRequest* request,
                                                               pb::ListClashStatusesResponse* response) {
  return run_queued(record_pool_, stats_, ctx, "ListClashStatuses", request, response,
                    [this](const pb::ListClashStatusesRequest& list, pb::ListClashStatusesResponse* out) -> grpc::Status {
    auto statuses = engine_.clash_statuses(list.scene_id());
    if (!statuses.ok()) return grpc::Status(to_status(statuses.error()));
    for (const engine::ClashStatusRecord& r : statuses.value()) status_to_proto(r, out->add_statuses());
    return grpc::Status(grpc::Status::OK);
  });
}

}  // namespace gk::server
