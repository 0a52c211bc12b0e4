// Private to server/: timing and finishing of unary calls, shared by the RPC handler files.
#pragma once

#include "server/rpc_stats.h"

#include <grpcpp/grpcpp.h>

#include <chrono>

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

}  // namespace gk::server
