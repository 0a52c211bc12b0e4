#include "server/gatekeeper_service.h"

#include "server/access_control.h"
#include "server/proto_convert.h"
#include "server/rpc_helpers.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <set>
#include <cmath>
#include <thread>

namespace gk::server {
namespace {

constexpr std::size_t kMaxChunkBytes = 1u << 20;

// Reads an upload: the header, then chunks of at most 1 MiB into the store's temporary file;
// finishing (hash check, fsync, parsing, record) runs on the work pool.
class UploadReactor final : public grpc::ServerReadReactor<pb::UploadPartChunk> {
 public:
  UploadReactor(GatekeeperService& service, grpc::CallbackServerContext* ctx, pb::PartInfo* reply)
      : service_(service), ctx_(ctx), reply_(reply), call_(begin_call(ctx, "UploadPart")) {
    slot_ = service_.upload_slots().open(ctx_);
    if (slot_ == 0) {
      done({grpc::StatusCode::RESOURCE_EXHAUSTED, "too many uploads open at once: retry later"});
      return;
    }
    StartRead(&chunk_);
  }

  void OnReadDone(bool ok) override {
    const grpc::Status read = guarded_status(call_, [&] {
      on_read(ok);
      return grpc::Status::OK;
    });
    if (!read.ok()) fail_with(read);
  }

  void OnDone() override {
    if (slot_ != 0) service_.upload_slots().release(slot_);
    delete this;
  }

 private:
  void on_read(bool ok) {
    if (!ok && ctx_->IsCancelled()) return fail_with({grpc::StatusCode::CANCELLED, "the upload was cancelled or idle too long"});
    if (!ok) {  // the client closed its side: finish what arrived
      complete();
      return;
    }
    service_.upload_slots().touch(slot_);
    if (!upload_) {
      if (!chunk_.has_header()) return fail(invalid_argument("header", "the first message must carry the header"));
      const pb::UploadHeader& h = chunk_.header();
      auto begun = service_.engine().begin_upload(h.name(), h.format(), h.size_bytes(), h.sha256());
      if (!begun.ok()) return fail(begun.error());
      upload_ = std::move(begun.value());
    } else {
      if (!chunk_.has_data()) return fail(invalid_argument("header", "sent twice"));
      if (chunk_.data().size() > kMaxChunkBytes) return fail(invalid_argument("data", "chunk larger than 1 MiB"));
      auto appended = upload_->append(chunk_.data());
      if (!appended.ok()) return fail(appended.error());
    }
    StartRead(&chunk_);
  }

  void fail(const Error& e) { fail_with(to_status(e)); }
  void fail_with(const grpc::Status& status) {
    upload_.reset();  // removes the temporary file
    done(status);
  }

  void done(const grpc::Status& status) {
    end_call(service_.stats(), call_, status, nullptr);
    Finish(status);
  }

  void complete() {
    // The client has sent everything: no longer an idle stream to reap (finishing may take long).
    service_.upload_slots().release(slot_);
    slot_ = 0;
    if (!upload_) return done({grpc::StatusCode::INVALID_ARGUMENT, "header: no upload header received"});
    auto* self = this;
    // CAD files are read in a child that may take up to --cad-check-seconds: on their own pool, so
    // that a file that keeps the reader busy never holds up mesh uploads.
    WorkPool& pool = engine::is_cad_format(upload_->format()) ? service_.cad_upload_pool() : service_.upload_pool();
    const bool queued = pool.try_submit([self] {
      const grpc::Status status = guarded_status(self->call_, [&]() -> grpc::Status {
        return self->finish_upload();
      });
      self->done(status);
    });
    if (!queued) done({grpc::StatusCode::RESOURCE_EXHAUSTED, "work queue full: retry later"});
  }

  // On a worker: reads the upload (the mesh it describes) and records it.
  grpc::Status finish_upload() {
    auto record = service_.engine().finish_upload(std::move(upload_));
    if (!record.ok()) return to_status(record.error());
    to_proto(record.value(), reply_);
    return grpc::Status::OK;
  }

  GatekeeperService& service_;
  grpc::CallbackServerContext* ctx_;
  std::uint64_t slot_ = 0;
  pb::PartInfo* reply_;
  const Call call_;
  pb::UploadPartChunk chunk_;
  std::unique_ptr<PartUpload> upload_;
};

}  // namespace

GatekeeperService::GatekeeperService(Engine& engine, ServiceOptions options)
    : engine_(engine), options_(options),
      validation_pool_(options.validation_workers, static_cast<std::size_t>(options.max_validations_in_flight)),
      part_validation_pool_(options.part_validation_workers, static_cast<std::size_t>(options.max_validations_in_flight)),
      scene_pool_(options.scene_workers, options.max_queued),
      record_pool_(options.record_workers, options.max_queued),
      pool_(options.workers, options.max_queued),
      upload_pool_(options.upload_workers, options.max_queued),
      cad_upload_pool_(options.upload_workers, options.max_queued),
      upload_slots_(options.max_open_uploads, options.upload_idle_limit) {
}

GatekeeperService::~GatekeeperService() { stop_work(); }

grpc::Status GatekeeperService::validate_one(const pb::ValidateStepRequest& request, const pb::SheetPart* default_part,
                                             const std::string& default_machine, pb::ValidateStepResponse* response) {
  auto question = to_question(request, default_part, default_machine);
  if (!question.ok()) return to_status(question.error());
  auto reply = engine_.steps().validate(question.value());
  if (!reply.ok()) return to_status(reply.error());
  to_proto(reply.value().answer, response);
  return grpc::Status::OK;
}

// Validations run on their own pools, never on gRPC's callback threads (which only translate
// and answer repeated questions from the cache): parametric parts on one, uploaded (mesh and CAD)
// parts, which can take seconds cold, on another, so that they never queue the others.
grpc::ServerUnaryReactor* GatekeeperService::ValidateStep(grpc::CallbackServerContext* ctx,
                                                          const pb::ValidateStepRequest* request,
                                                          pb::ValidateStepResponse* response) {
  const Call call = begin_call(ctx, "ValidateStep");
  // A repeated question is answered here, on the callback thread, from the engine's cache (any
  // trouble, even an exception, leaves it to a worker, which answers the error).
  const bool answered = [&] {
    try {
      auto question = to_question(*request, nullptr, "");
      if (!question.ok()) return false;
      auto hit = engine_.steps().cached(question.value());
      if (!hit) return false;
      to_proto(hit->answer, response);
      return true;
    } catch (...) {
      response->Clear();
      return false;
    }
  }();
  if (answered) return finish(ctx, stats_, call, grpc::Status::OK, response);
  return run_queued(request->part().part_id().empty() ? validation_pool_ : part_validation_pool_, stats_, ctx, call,
                    request, response, [this](const pb::ValidateStepRequest& r, pb::ValidateStepResponse* out) {
                      return validate_one(r, nullptr, "", out);
                    });
}

grpc::ServerUnaryReactor* GatekeeperService::ValidateSteps(grpc::CallbackServerContext* ctx,
                                                           const pb::ValidateStepsRequest* request,
                                                           pb::ValidateStepsResponse* response) {
  bool uploaded_part = !request->part().part_id().empty();
  for (const auto& step : request->steps()) uploaded_part = uploaded_part || !step.part().part_id().empty();
  return run_queued(uploaded_part ? part_validation_pool_ : validation_pool_, stats_, ctx, "ValidateSteps", request, response,
                        [this, ctx](const pb::ValidateStepsRequest& r, pb::ValidateStepsResponse* out) -> grpc::Status {
    out->set_first_failure(-1);
    for (int i = 0; i < r.steps_size(); ++i) {
      if (past_deadline(ctx) || ctx->IsCancelled())
        return grpc::Status({grpc::StatusCode::DEADLINE_EXCEEDED, "deadline passed after step " + std::to_string(i)});
      pb::ValidateStepResponse* one = out->add_results();
      grpc::Status s = validate_one(r.steps(i), r.has_part() ? &r.part() : nullptr, r.machine_id(), one);
      if (!s.ok())
        return grpc::Status({s.error_code(), "steps[" + std::to_string(i) + "]." + s.error_message()});
      if (one->verdict() != pb::CLEAR && out->first_failure() < 0) {
        out->set_first_failure(i);
        if (r.stop_at_first_failure()) break;
      }
    }
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::ClearanceQuery(grpc::CallbackServerContext* ctx,
                                                            const pb::ClearanceQueryRequest* request,
                                                            pb::ClearanceQueryResponse* response) {
  const Call call = begin_call(ctx, "ClearanceQuery");
  auto* reactor = ctx->DefaultReactor();
  const bool queued = pool_.try_submit([this, ctx, request, response, reactor, call] {
    grpc::Status status;
    if (ctx->IsCancelled()) status = {grpc::StatusCode::CANCELLED, "cancelled by the client"};
    else if (past_deadline(ctx)) status = {grpc::StatusCode::DEADLINE_EXCEEDED, "deadline passed while queued"};
    else {
      const StopToken stop([ctx] { return ctx->IsCancelled() || past_deadline(ctx); });
      status = guarded_status(call, [&]() -> grpc::Status {
        auto asked = to_clearance_request(*request);
        if (!asked.ok()) return to_status(asked.error());
        auto answer = engine_.clearance(asked.value(), stop);
        if (!answer.ok()) return to_status(answer.error());
        to_proto(answer.value(), response);
        return grpc::Status::OK;
      });
    }
    end_call(stats_, call, status, response);
    reactor->Finish(status);
  });
  if (!queued) {
    const grpc::Status refused{grpc::StatusCode::RESOURCE_EXHAUSTED, "clearance queue full: retry later"};
    end_call(stats_, call, refused);
    reactor->Finish(refused);
  }
  return reactor;
}

grpc::ServerReadReactor<pb::UploadPartChunk>* GatekeeperService::UploadPart(grpc::CallbackServerContext* ctx,
                                                                           pb::PartInfo* response) {
  if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) {
    end_call(stats_, begin_call(ctx, "UploadPart"), allowed);
    return new RefusedStream<grpc::ServerReadReactor<pb::UploadPartChunk>>(allowed);
  }
  return new UploadReactor(*this, ctx, response);
}

grpc::ServerUnaryReactor* GatekeeperService::GetPartInfo(grpc::CallbackServerContext* ctx, const pb::GetPartInfoRequest* request,
                                                         pb::PartInfo* response) {
  return unary(ctx, stats_, "GetPartInfo", [&]() -> grpc::Status {
    auto record = engine_.part(request->part_id());
    if (!record.ok()) return grpc::Status(to_status(record.error()));
    to_proto(record.value(), response);
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::Status GatekeeperService::machine_info(const MachineSnapshot& m, pb::MachineInfo* response) {
  response->set_machine_id(m.id);
  response->set_name(m.model.name);
  response->set_aba_segments(static_cast<std::uint32_t>(m.model.aba.segment_widths_mm.size()));
  response->set_max_bend_length_mm(m.model.max_bend_length_mm);
  response->set_max_bend_angle_deg(m.model.max_bend_angle_deg);
  to_proto(m.state, response->mutable_state());
  response->set_model_toml(m.model_toml);
  return grpc::Status::OK;
}

grpc::ServerUnaryReactor* GatekeeperService::ListMachines(grpc::CallbackServerContext* ctx, const pb::ListMachinesRequest*,
                                                          pb::ListMachinesResponse* response) {
  return unary(ctx, stats_, "ListMachines", [&]() -> grpc::Status {
    for (const MachineSnapshot& m : engine_.machines()) {
      grpc::Status s = machine_info(m, response->add_machines());
      if (!s.ok()) return grpc::Status(s);
    }
    return grpc::Status(grpc::Status::OK);
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetMachine(grpc::CallbackServerContext* ctx, const pb::GetMachineRequest* request,
                                                        pb::MachineInfo* response) {
  return unary(ctx, stats_, "GetMachine", [&]() -> grpc::Status {
    auto m = engine_.machine(request->machine_id());
    if (!m.ok()) return grpc::Status(to_status(m.error()));
    return grpc::Status(machine_info(m.value(), response));
  });
}

grpc::ServerUnaryReactor* GatekeeperService::SetMachineState(grpc::CallbackServerContext* ctx,
                                                             const pb::SetMachineStateRequest* request, pb::MachineInfo* response) {
  return unary(ctx, stats_, "SetMachineState", [&]() -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kWrite); !allowed.ok()) return allowed;
    auto set = engine_.set_machine_state(request->machine_id(), to_state(request->state()));
    if (!set.ok()) return grpc::Status(to_status(set.error()));
    return grpc::Status(machine_info(set.value(), response));
  });
}

grpc::ServerUnaryReactor* GatekeeperService::PutMachineModel(grpc::CallbackServerContext* ctx,
                                                             const pb::PutMachineModelRequest* request, pb::MachineInfo* response) {
  return run_queued(record_pool_, stats_, ctx, "PutMachineModel", request, response,
                    [this, ctx](const pb::PutMachineModelRequest& put, pb::MachineInfo* out) -> grpc::Status {
    if (auto allowed = require_role(ctx, Role::kAdmin); !allowed.ok()) return allowed;
    auto stored = engine_.put_machine_model(put.machine_id(), put.model_toml());
    if (!stored.ok()) return grpc::Status(to_status(stored.error()));
    return grpc::Status(machine_info(stored.value(), out));
  });
}

grpc::ServerUnaryReactor* GatekeeperService::GetServerInfo(grpc::CallbackServerContext* ctx, const pb::GetServerInfoRequest*,
                                                           pb::ServerInfo* response) {
  return unary(ctx, stats_, "GetServerInfo", [&]() -> grpc::Status {
    response->set_version(options_.version);
    for (const MachineSnapshot& m : engine_.machines()) response->add_machines(m.id);
    for (const RpcStats::Summary& s : stats_.summaries()) {
      pb::RpcStats* r = response->add_rpcs();
      r->set_method(s.method);
      r->set_calls(s.calls);
      r->set_errors(s.errors);
      r->set_p50_us(s.p50_us);
      r->set_p99_us(s.p99_us);
      for (std::size_t b = 0; b < RpcStats::kBuckets; ++b) {
        // The last bucket has no bound.
        r->add_histogram_bounds_us(b < RpcStats::kBounded ? RpcStats::bucket_bound_us(b)
                                                          : std::numeric_limits<double>::infinity());
        r->add_histogram_counts(s.histogram[b]);
      }
    }
    response->set_parts_stored(engine_.parts_stored());
    const engine::PartRegistry::MemoryStats memory = engine_.part_memory();
    response->set_parts_in_memory(memory.parts);
    response->set_part_memory_bytes(memory.bytes);
    response->set_parts_evicted(memory.evicted);
    response->set_audits_in_memory(engine_.audits().in_memory());
    return grpc::Status(grpc::Status::OK);
  });
}

MetricsSnapshot GatekeeperService::metrics() {
  MetricsSnapshot m;
  m.rpcs = stats_.summaries();
  const auto pool = [&](const char* name, const WorkPool& p) { m.pools.push_back({name, p.queued(), p.capacity(), p.threads()}); };
  pool("validation", validation_pool_);
  pool("part_validation", part_validation_pool_);
  pool("scene", scene_pool_);
  pool("record", record_pool_);
  pool("clearance", pool_);
  pool("upload", upload_pool_);
  pool("cad_upload", cad_upload_pool_);
  m.step_cache = engine_.steps().cache_stats();
  m.parts = engine_.part_memory();
  m.parts_stored = engine_.parts_stored();
  m.audits_running = engine_.audits().running();
  m.audits_in_memory = engine_.audits().in_memory();
  m.uploads_open = upload_slots_.open_count();
  m.process = read_process_memory();
  return m;
}

}  // namespace gk::server
