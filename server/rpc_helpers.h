// Private to server/: finishing of unary calls and the exception guard, shared by the RPC
// handler files (each call is begun and ended through server/call.h).
#pragma once

#include "server/call.h"
#include "server/engine_names.h"
#include "server/rpc_stats.h"

#include <grpcpp/grpcpp.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <exception>
#include <string>

namespace gk::server {

inline bool past_deadline(const grpc::CallbackServerContext* ctx) {
  return ctx->deadline() < std::chrono::system_clock::now();
}

// Finishes a unary call, recording its latency and outcome.
inline grpc::ServerUnaryReactor* finish(grpc::CallbackServerContext* ctx, RpcStats& stats, const Call& call,
                                        const grpc::Status& status, const google::protobuf::Message* answer = nullptr) {
  end_call(stats, call, status, answer);
  auto* reactor = ctx->DefaultReactor();
  reactor->Finish(status);
  return reactor;
}

// A streaming call refused before it starts: its reactor finishes at once and frees itself.
template <typename Reactor>
class RefusedStream final : public Reactor {
 public:
  explicit RefusedStream(const grpc::Status& status) { this->Finish(status); }
  void OnDone() override { delete this; }
};

// Runs a handler's body; whatever it throws is logged with the call's request id and answered
// INTERNAL (never a terminate, never UNIMPLEMENTED).
template <typename Body>
grpc::Status guarded_status(const Call& call, Body&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    spdlog::error("{} {}: unexpected exception: {}", call.method, call.request_id, e.what());
    return {grpc::StatusCode::INTERNAL, "internal error (" + call.request_id + "): " + e.what()};
  } catch (...) {
    spdlog::error("{} {}: unexpected exception of unknown type", call.method, call.request_id);
    return {grpc::StatusCode::INTERNAL, "internal error (" + call.request_id + ")"};
  }
}

// A unary call: its body returns the status; timing, finishing and the exception guard are here.
// `answer`, when given, is the reply the call line reads its verdict from.
template <typename Body>
grpc::ServerUnaryReactor* unary(grpc::CallbackServerContext* ctx, RpcStats& stats, const char* method, Body&& body,
                                const google::protobuf::Message* answer = nullptr) {
  const Call call = begin_call(ctx, method);
  const grpc::Status status = guarded_status(call, std::forward<Body>(body));
  return finish(ctx, stats, call, status, answer);
}

// A unary call whose work runs on `pool`, not on gRPC's callback thread: queued (RESOURCE_EXHAUSTED
// when the queue is full), skipped when the client has gone or its deadline passed while queued.
// body(request, response) returns the status; timing, finishing and the exception guard are here.
template <typename Request, typename Response, typename Body>
grpc::ServerUnaryReactor* run_queued(WorkPool& pool, RpcStats& stats, grpc::CallbackServerContext* ctx, Call call,
                                     const Request* request, Response* response, Body body) {
  auto* reactor = ctx->DefaultReactor();
  const bool queued = pool.try_submit([&stats, ctx, call, request, response, reactor, body] {
    grpc::Status status;
    if (ctx->IsCancelled()) status = {grpc::StatusCode::CANCELLED, "cancelled by the client"};
    else if (past_deadline(ctx)) status = {grpc::StatusCode::DEADLINE_EXCEEDED, "deadline passed while queued"};
    else status = guarded_status(call, [&] { return body(*request, response); });
    end_call(stats, call, status, response);
    reactor->Finish(status);
  });
  if (!queued) {
    const grpc::Status refused{grpc::StatusCode::RESOURCE_EXHAUSTED, std::string(call.method) + ": too much work queued, retry later"};
    end_call(stats, call, refused);
    reactor->Finish(refused);
  }
  return reactor;
}
template <typename Request, typename Response, typename Body>
grpc::ServerUnaryReactor* run_queued(WorkPool& pool, RpcStats& stats, grpc::CallbackServerContext* ctx, const char* method,
                                     const Request* request, Response* response, Body body) {
  return run_queued(pool, stats, ctx, begin_call(ctx, method), request, response, std::move(body));
}

}  // namespace gk::server
