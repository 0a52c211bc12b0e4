// The gRPC service: translates gatekeeper.v1 to the engine (engine/gatekeeper_engine.h) and back,
// and decides only where the work runs. Callback API: gRPC's threads translate and answer repeated
// ValidateStep questions from the engine's cache; everything that takes longer runs on bounded
// work pools (RESOURCE_EXHAUSTED when full). Constructed over an engine, so that its tests run it
// in process (an in-process channel) as well as in the real daemon.
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"
#include "engine/gatekeeper_engine.h"
#include "engine/work_pool.h"
#include "kernel/core/stop_token.h"
#include "server/engine_names.h"
#include "server/metrics_text.h"
#include "server/rpc_stats.h"
#include "server/upload_slots.h"

#include <atomic>
#include <chrono>
#include <memory>
#include <string>

namespace gk::server {

namespace pb = ::gatekeeper::v1;

struct ServiceOptions {
  int workers = 2;                 // clearance query threads
  std::size_t max_queued = 64;     // clearance queries and upload finishings queued; beyond, RESOURCE_EXHAUSTED
  int upload_workers = 1;          // threads reading finished uploads: as many for mesh files, as many for CAD files
  // ValidateStep(s) run on their own threads (gRPC's only translate and answer from the cache):
  // parametric parts on validation_workers, uploaded parts (seconds cold on a large mesh) on
  // part_validation_workers, so that they never queue the others. Each queue holds at most
  // max_validations_in_flight; beyond, RESOURCE_EXHAUSTED.
  int validation_workers = 2;
  int part_validation_workers = 1;
  int scene_workers = 2;           // PutObject(s), MoveObject and drag frames (their contacts); queue: max_queued
  int max_validations_in_flight = 64;
  // Stored records that take milliseconds to write or render (PutObjects batches, machine models,
  // audit reports and their pages): off the callback threads, apart from the geometry; queue: max_queued.
  int record_workers = 1;
  std::size_t max_open_uploads = 64;             // upload streams open at once; beyond, RESOURCE_EXHAUSTED
  std::chrono::milliseconds upload_idle_limit{60000};  // an upload silent this long is cancelled
  std::string version = "0.1.0";
};

class GatekeeperService final : public ::gatekeeper::v1::Gatekeeper::CallbackService {
 public:
  GatekeeperService(Engine& engine, ServiceOptions options);
  ~GatekeeperService() override;

  void stop_work() {
    engine_.stop();  // a running audit would hold the stop past any drain time
    validation_pool_.stop();
    part_validation_pool_.stop();
    scene_pool_.stop();
    record_pool_.stop();
    pool_.stop();
    upload_pool_.stop();
    cad_upload_pool_.stop();
  }
  RpcStats& stats() { return stats_; }
  // What /metrics reports (server/metrics_endpoint.h): calls, queues, caches, memory.
  MetricsSnapshot metrics();
  Engine& engine() { return engine_; }
  WorkPool& upload_pool() { return upload_pool_; }
  WorkPool& cad_upload_pool() { return cad_upload_pool_; }
  WorkPool& scene_pool() { return scene_pool_; }
  // Drag frames being answered on gRPC's own threads right now (scene_rpcs.cpp's DragReactor).
  std::atomic<int>& drag_frames_on_grpc_threads() { return drag_frames_on_grpc_threads_; }
  UploadSlots& upload_slots() { return upload_slots_; }

  grpc::ServerUnaryReactor* ValidateStep(grpc::CallbackServerContext* ctx, const pb::ValidateStepRequest* request,
                                         pb::ValidateStepResponse* response) override;
  grpc::ServerUnaryReactor* ValidateSteps(grpc::CallbackServerContext* ctx, const pb::ValidateStepsRequest* request,
                                          pb::ValidateStepsResponse* response) override;
  grpc::ServerUnaryReactor* ClearanceQuery(grpc::CallbackServerContext* ctx, const pb::ClearanceQueryRequest* request,
                                           pb::ClearanceQueryResponse* response) override;
  grpc::ServerReadReactor<pb::UploadPartChunk>* UploadPart(grpc::CallbackServerContext* ctx, pb::PartInfo* response) override;
  grpc::ServerUnaryReactor* GetPartInfo(grpc::CallbackServerContext* ctx, const pb::GetPartInfoRequest* request,
                                        pb::PartInfo* response) override;
  grpc::ServerUnaryReactor* ListMachines(grpc::CallbackServerContext* ctx, const pb::ListMachinesRequest* request,
                                         pb::ListMachinesResponse* response) override;
  grpc::ServerUnaryReactor* GetMachine(grpc::CallbackServerContext* ctx, const pb::GetMachineRequest* request,
                                       pb::MachineInfo* response) override;
  grpc::ServerUnaryReactor* SetMachineState(grpc::CallbackServerContext* ctx, const pb::SetMachineStateRequest* request,
                                            pb::MachineInfo* response) override;
  grpc::ServerUnaryReactor* PutMachineModel(grpc::CallbackServerContext* ctx, const pb::PutMachineModelRequest* request,
                                            pb::MachineInfo* response) override;
  grpc::ServerUnaryReactor* CreateScene(grpc::CallbackServerContext* ctx, const pb::CreateSceneRequest* request,
                                        pb::SceneInfo* response) override;
  grpc::ServerUnaryReactor* PutObject(grpc::CallbackServerContext* ctx, const pb::PutObjectRequest* request,
                                      pb::MoveResult* response) override;
  grpc::ServerUnaryReactor* PutObjects(grpc::CallbackServerContext* ctx, const pb::PutObjectsRequest* request,
                                       pb::PutObjectsResponse* response) override;
  grpc::ServerUnaryReactor* MoveObject(grpc::CallbackServerContext* ctx, const pb::MoveObjectRequest* request,
                                       pb::MoveResult* response) override;
  grpc::ServerBidiReactor<pb::MoveObjectRequest, pb::MoveResult>* DragObject(grpc::CallbackServerContext* ctx) override;
  grpc::ServerUnaryReactor* DeleteObject(grpc::CallbackServerContext* ctx, const pb::DeleteObjectRequest* request,
                                         pb::SceneInfo* response) override;
  grpc::ServerUnaryReactor* GetScene(grpc::CallbackServerContext* ctx, const pb::GetSceneRequest* request,
                                     pb::SceneInfo* response) override;
  grpc::ServerUnaryReactor* StartAudit(grpc::CallbackServerContext* ctx, const pb::StartAuditRequest* request,
                                       pb::AuditJob* response) override;
  grpc::ServerWriteReactor<pb::AuditProgress>* WatchAudit(grpc::CallbackServerContext* ctx,
                                                          const pb::WatchAuditRequest* request) override;
  grpc::ServerUnaryReactor* CancelAudit(grpc::CallbackServerContext* ctx, const pb::CancelAuditRequest* request,
                                        pb::AuditProgress* response) override;
  grpc::ServerUnaryReactor* GetAuditReport(grpc::CallbackServerContext* ctx, const pb::GetAuditReportRequest* request,
                                           pb::AuditReport* response) override;
  grpc::ServerUnaryReactor* SetClashStatus(grpc::CallbackServerContext* ctx, const pb::SetClashStatusRequest* request,
                                           pb::ClashStatusInfo* response) override;
  grpc::ServerUnaryReactor* ListClashStatuses(grpc::CallbackServerContext* ctx, const pb::ListClashStatusesRequest* request,
                                              pb::ListClashStatusesResponse* response) override;
  grpc::ServerBidiReactor<pb::FixtureRequest, pb::FixtureReply>* AssembleFixture(grpc::CallbackServerContext* ctx) override;
  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* ctx, const pb::GetServerInfoRequest* request,
                                          pb::ServerInfo* response) override;

 private:
  grpc::Status validate_one(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part,
                            const std::string& default_machine, pb::ValidateStepResponse* response);
  grpc::Status machine_info(const MachineSnapshot& machine, pb::MachineInfo* response);

 public:
  // One move (unary, or one frame of a drag, which passes its session): stored, then its contacts.
  grpc::Status move(const pb::MoveObjectRequest& request, pb::MoveResult* response, DragSession* drag = nullptr,
                    const StopToken& stop = {});

 private:
  Engine& engine_;
  ServiceOptions options_;
  RpcStats stats_;
  WorkPool validation_pool_;
  WorkPool part_validation_pool_;
  WorkPool scene_pool_;  // scene edits (PutObject(s), MoveObject, drag frames)
  WorkPool record_pool_;  // PutObjects batches, machine models, audit reports
  WorkPool pool_;  // clearance queries
  WorkPool upload_pool_;      // finishing mesh uploads
  WorkPool cad_upload_pool_;  // finishing CAD uploads (checked in a child first)
  UploadSlots upload_slots_;
  std::atomic<int> drag_frames_on_grpc_threads_{0};
};

}  // namespace gk::server
