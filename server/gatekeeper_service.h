// The gRPC service: a thin adapter from gatekeeper.v1 to the engine, the kernel and the stores.
// Callback API; ValidateStep is answered on the callback thread (microseconds, no blocking);
// clearance queries and upload finishing run on a bounded work pool.
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"
#include "kernel/stop_token.h"
#include "server/answer_cache.h"
#include "server/audit_archive.h"
#include "server/machine_registry.h"
#include "server/part_registry.h"
#include "server/rpc_stats.h"
#include "server/scene_queries.h"
#include "server/scene_store.h"
#include "server/upload_slots.h"
#include "server/work_pool.h"

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
  int audit_threads = 2;           // threads of one audit job (its tiles, then its pairs)
  // Audit jobs run on their own pool, so that a running audit never delays a clearance query.
  int audit_jobs = 1;              // audits run at once
  std::size_t audit_queue = 16;    // audits waiting; beyond, RESOURCE_EXHAUSTED
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
  // Ended audits kept in memory (the rest are read from the archive when asked for).
  std::size_t ended_audits_in_memory = 16;
  std::string version = "0.1.0";
};

class GatekeeperService final : public ::gatekeeper::v1::Gatekeeper::CallbackService {
 public:
  // archive: where ended audits are kept (and were restored from); may be null.
  GatekeeperService(MachineRegistry& machines, PartRegistry& parts, SceneStore& scenes, AuditArchive* archive,
                    ServiceOptions options);
  ~GatekeeperService() override;

  void stop_work() {
    audits_.cancel_all();  // a running audit would hold the stop past any drain time
    validation_pool_.stop();
    part_validation_pool_.stop();
    scene_pool_.stop();
    record_pool_.stop();
    pool_.stop();
    upload_pool_.stop();
    cad_upload_pool_.stop();
    audit_pool_.stop();
  }
  RpcStats& stats() { return stats_; }
  PartRegistry& parts() { return parts_; }
  WorkPool& upload_pool() { return upload_pool_; }
  WorkPool& cad_upload_pool() { return cad_upload_pool_; }
  WorkPool& scene_pool() { return scene_pool_; }
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
  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* ctx, const pb::GetServerInfoRequest* request,
                                          pb::ServerInfo* response) override;

 private:
  grpc::Status validate_one(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part,
                            const std::string& default_machine, pb::ValidateStepResponse* response);
  grpc::Status validate_one_unguarded(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part,
                            const std::string& default_machine, pb::ValidateStepResponse* response);
  grpc::Status clearance(const pb::ClearanceQueryRequest& request, const StopToken& stop, pb::ClearanceQueryResponse* response);
  grpc::Status machine_info(const std::string& id, pb::MachineInfo* response);
 public:
  // A move of one object (unary, or one message of a drag): stored, then its contacts; a drag
  // answers through its stream's layout session.
  grpc::Status move(const pb::MoveObjectRequest& request, pb::MoveResult* response, DragSession* drag = nullptr,
                    const StopToken& stop = {});
  // The stored object's contacts at its pose (through the drag's session when there is one).
  grpc::Status contacts(const std::string& scene_id, const std::string& object_id, double clearance_mm, const RigidTransform& pose,
                        DragSession* drag, std::chrono::steady_clock::time_point t0, pb::MoveResult* response,
                        const StopToken& stop = {});
  SceneStore& scenes() { return scenes_; }
  AuditJobs& audits() { return audits_; }

 private:
  static std::string answer_key(const pb::ValidateStepRequest& request, const pb::SheetPart& part_msg,
                                const MachineSnapshot& snapshot);
  bool answer_from_cache(const std::string& key, std::chrono::steady_clock::time_point t0, pb::ValidateStepResponse* response);
  // A repeated question (its own part, no default): answered on the calling thread.
  bool answered_from_cache(const pb::ValidateStepRequest& request, pb::ValidateStepResponse* response);

  MachineRegistry& machines_;
  PartRegistry& parts_;
  SceneStore& scenes_;
  AuditJobs audits_;
  AuditArchive* archive_;
  AnswerCache answers_;
  ServiceOptions options_;
  RpcStats stats_;
  WorkPool validation_pool_;
  WorkPool part_validation_pool_;
  WorkPool scene_pool_;  // scene edits (PutObject(s), MoveObject, drag frames)
  WorkPool record_pool_;  // PutObjects batches, machine models, audit reports
  WorkPool pool_;  // clearance queries
  WorkPool upload_pool_;      // finishing mesh uploads
  WorkPool cad_upload_pool_;  // finishing CAD uploads (checked in a child first)
  WorkPool audit_pool_;
  UploadSlots upload_slots_;
};

}  // namespace gk::server
