// One call to the service from its start to its answer: its request id (the client's
// "x-request-id" metadata when it sends a sane one, else a new one; echoed to the client in the
// initial metadata), its timing, and at its end the count in RpcStats and the call line in the
// log (server/request_log.h) with the answer's verdict and deciding stage.
#pragma once

#include "server/rpc_stats.h"

#include <google/protobuf/message.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <string>

namespace gk::server {

using Clock = std::chrono::steady_clock;

inline double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

struct Call {
  const char* method = "";
  std::string request_id;
  Clock::time_point t0 = Clock::now();
};

inline constexpr const char* kRequestIdMetadata = "x-request-id";

// Starts a call. Must run before the call's initial metadata is sent (its first write or finish).
Call begin_call(grpc::CallbackServerContext* ctx, const char* method);
// A call without a client context (a frame of a stream: it keeps the stream's request id).
Call begin_frame(const Call& stream, const char* method);

// The call is answered: counted, timed and logged. `answer` (may be null) is the reply message,
// read for the verdict and deciding stage of the answers that have them.
void end_call(RpcStats& stats, const Call& call, const grpc::Status& status,
              const google::protobuf::Message* answer = nullptr);

}  // namespace gk::server
