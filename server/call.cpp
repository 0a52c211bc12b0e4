#include "server/call.h"

#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/request_log.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <iterator>
#include <vector>

namespace gk::server {
namespace {

namespace pb = ::gatekeeper::v1;

// A client's request id is kept when it is 1..64 characters of [A-Za-z0-9._:-]; anything else
// (it would be written into logs) is replaced.
bool sane_request_id(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  for (const char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
                    c == ':' || c == '-';
    if (!ok) return false;
  }
  return true;
}

// "gk-<this process's start, ms since the epoch, hex>-<count>": unique across restarts too (a
// log file is appended to by every run).
std::string new_request_id() {
  static const std::string prefix = [] {
    char hex[32];
    std::snprintf(hex, sizeof hex, "gk-%llx-",
                  static_cast<unsigned long long>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                                      std::chrono::system_clock::now().time_since_epoch())
                                                      .count()));
    return std::string(hex);
  }();
  static std::atomic<unsigned long long> counter{0};
  return prefix + std::to_string(++counter);
}

const char* status_code_name(grpc::StatusCode code) {
  static const char* const names[] = {"OK", "CANCELLED", "UNKNOWN", "INVALID_ARGUMENT", "DEADLINE_EXCEEDED", "NOT_FOUND",
                                      "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION",
                                      "ABORTED", "OUT_OF_RANGE", "UNIMPLEMENTED", "INTERNAL", "UNAVAILABLE", "DATA_LOSS",
                                      "UNAUTHENTICATED"};
  const int i = static_cast<int>(code);
  return i >= 0 && i < static_cast<int>(std::size(names)) ? names[i] : "UNKNOWN";
}

std::string number(double v) {
  char out[32];
  std::snprintf(out, sizeof out, "%.1f", v);
  return out;
}

// The verdict and deciding stage of the answers that carry them.
void add_answer_fields(const google::protobuf::Message* answer, std::vector<LogField>& fields) {
  if (answer == nullptr) return;
  if (const auto* step = dynamic_cast<const pb::ValidateStepResponse*>(answer)) {
    fields.push_back({"verdict", pb::Verdict_Name(step->verdict())});
    fields.push_back({"deciding_stage", pb::DecidingStage_Name(step->deciding_stage())});
    if (step->inconclusive_reason() != pb::INCONCLUSIVE_REASON_UNSPECIFIED)
      fields.push_back({"inconclusive_reason", pb::InconclusiveReason_Name(step->inconclusive_reason())});
  } else if (const auto* steps = dynamic_cast<const pb::ValidateStepsResponse*>(answer)) {
    fields.push_back({"steps", std::to_string(steps->results_size()), true});
    fields.push_back({"first_failure", std::to_string(steps->first_failure()), true});
  } else if (const auto* clearance = dynamic_cast<const pb::ClearanceQueryResponse*>(answer)) {
    fields.push_back({"verdict", pb::Verdict_Name(clearance->verdict())});
    if (clearance->inconclusive_reason() != pb::INCONCLUSIVE_REASON_UNSPECIFIED)
      fields.push_back({"inconclusive_reason", pb::InconclusiveReason_Name(clearance->inconclusive_reason())});
    if (clearance->depth_method_kind() != pb::DEPTH_METHOD_UNSPECIFIED)
      fields.push_back({"depth_method", pb::DepthMethod_Name(clearance->depth_method_kind())});
    if (clearance->volume_method_kind() != pb::VOLUME_METHOD_UNSPECIFIED)
      fields.push_back({"volume_method", pb::VolumeMethod_Name(clearance->volume_method_kind())});
  } else if (const auto* move = dynamic_cast<const pb::MoveResult*>(answer)) {
    fields.push_back({"verdict", pb::Verdict_Name(move->verdict())});
    fields.push_back({"contacts", std::to_string(move->contacts_size()), true});
  } else if (const auto* job = dynamic_cast<const pb::AuditJob*>(answer)) {
    fields.push_back({"job_id", job->job_id()});
  }
}

}  // namespace

Call begin_call(grpc::CallbackServerContext* ctx, const char* method) {
  Call call;
  call.method = method;
  const auto& metadata = ctx->client_metadata();
  const auto given = metadata.find(kRequestIdMetadata);
  if (given != metadata.end()) call.request_id.assign(given->second.data(), given->second.size());
  if (!sane_request_id(call.request_id)) call.request_id = new_request_id();
  ctx->AddInitialMetadata(kRequestIdMetadata, call.request_id);
  return call;
}

Call begin_frame(const Call& stream, const char* method) {
  Call frame;
  frame.method = method;
  frame.request_id = stream.request_id;
  return frame;
}

void end_call(RpcStats& stats, const Call& call, const grpc::Status& status, const google::protobuf::Message* answer) {
  const double micros = us_since(call.t0);
  stats.record(call.method, micros, !status.ok());
  const grpc::StatusCode code = status.error_code();
  const bool server_fault =
      code == grpc::StatusCode::INTERNAL || code == grpc::StatusCode::UNKNOWN || code == grpc::StatusCode::DATA_LOSS;
  if (!call_line_wanted(server_fault)) return;  // no line: no fields gathered on the answer's path
  std::vector<LogField> fields = {{"request_id", call.request_id}, {"method", call.method}};
  fields.push_back({"status", status_code_name(status.error_code())});
  fields.push_back({"micros", number(micros), true});
  if (status.ok()) add_answer_fields(answer, fields);
  else fields.push_back({"error", status.error_message()});
  log_call(fields, server_fault);
}

}  // namespace gk::server
