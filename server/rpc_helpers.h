// Private to server/: timing and finishing of unary calls, shared by the RPC handler files.
#pragma once

#include "server/rpc_stats.h"
#include "server/engine_names.h"

#include <grpcpp/grpcpp.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <string>

namespace gk::server {

using Clock = std::chrono::steady_clock;

inline double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

inline bool past_deadline(const grpc::CallbackServerContext* ctx) {
  return ctx->deadline() < std::chrono::system_clock::now();
}

// Finishes a unary call, recording its latency and outcome.
inline grpc::ServerUnaryReactor* finish(grpc::CallbackServerContext* ctx, RpcStats& stats, const char* method,
                                 Clock::time_point t0, const grpc::Status& status) {
  stats.record(method, us_since(t0), !status.ok());
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

// A request id for the log, unique within this process.
inline std::string next_request_id() {
  static std::atomic<unsigned long long> counter{0};
  return "req-" + std::to_string(++counter);
}

// Runs a handler's body; whatever it throws is logged with a request id and answered INTERNAL
// (never a terminate, never UNIMPLEMENTED).
template <typename Body>
grpc::Status guarded_status(const char* method, Body&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    const std::string id = next_request_id();
    spdlog::error("{} {}: unexpected exception: {}", method, id, e.what());
    return {grpc::StatusCode::INTERNAL, std::string("internal error (") + id + "): " + e.what()};
  } catch (...) {
    const std::string id = next_request_id();
    spdlog::error("{} {}: unexpected exception of unknown type", method, id);
    return {grpc::StatusCode::INTERNAL, "internal error (" + id + ")"};
  }
}

// A unary call: its body returns the status; timing, finishing and the exception guard are here.
template <typename Body>
grpc::ServerUnaryReactor* unary(grpc::CallbackServerContext* ctx, RpcStats& stats, const char* method, Body&& body) {
  const auto t0 = Clock::now();
  return finish(ctx, stats, method, t0, guarded_status(method, std::forward<Body>(body)));
}

// A unary call whose work runs on `pool`, not on gRPC's callback thread: queued (RESOURCE_EXHAUSTED
// when the queue is full), skipped when the client has gone or its deadline passed while queued.
// body(request, response) returns the status; timing, finishing and the exception guard are here.
template <typename Request, typename Response, typename Body>
grpc::ServerUnaryReactor* run_queued(WorkPool& pool, RpcStats& stats, grpc::CallbackServerContext* ctx, const char* method,
                                     const Request* request, Response* response, Body body) {
  const auto t0 = Clock::now();
  auto* reactor = ctx->DefaultReactor();
  const bool queued = pool.try_submit([&stats, ctx, method, request, response, reactor, t0, body] {
    grpc::Status status;
    if (ctx->IsCancelled()) status = {grpc::StatusCode::CANCELLED, "cancelled by the client"};
    else if (past_deadline(ctx)) status = {grpc::StatusCode::DEADLINE_EXCEEDED, "deadline passed while queued"};
    else status = guarded_status(method, [&] { return body(*request, response); });
    stats.record(method, us_since(t0), !status.ok());
    reactor->Finish(status);
  });
  if (!queued) {
    stats.record(method, us_since(t0), true);
    reactor->Finish({grpc::StatusCode::RESOURCE_EXHAUSTED, std::string(method) + ": too much work queued, retry later"});
  }
  return reactor;
}

}  // namespace gk::server
