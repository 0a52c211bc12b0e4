// gatekeeper-cli: every gatekeeperd RPC from the command line, requests and replies as JSON
// (protobuf's JSON mapping of gatekeeper.v1, field names in lowerCamelCase or as in the proto).
//
//   gatekeeper-cli [--address 127.0.0.1:50051] [--tls-ca PEM [--tls-cert PEM --tls-key PEM]] [--token-file F] server-info
//   gatekeeper-cli machines | machine [ID] | set-state '{"state": {"clampZMm": 1.5}}'
//   gatekeeper-cli validate-step '{"part": {...}, "step": {"kind": "BEND_UP", ...}}'
//   gatekeeper-cli validate-steps '{"steps": [...], "stopAtFirstFailure": true}'
//   gatekeeper-cli upload FILE [--name NAME]        (streams 1 MiB chunks, sha256 declared first)
//   gatekeeper-cli part-info PART_ID
//   gatekeeper-cli clearance '{"a": {"partId": "..."}, "b": {"partId": "...", "pose": {...}}, "safetyGapMm": 5}'
//   gatekeeper-cli put-model ID FILE.toml
//   gatekeeper-cli create-scene NAME | scene SCENE_ID | delete-object SCENE_ID OBJECT_ID
//   gatekeeper-cli put-object '{"sceneId": "...", "object": {"partId": "...", "pose": {...}}}'
//   gatekeeper-cli put-objects '{"sceneId": "...", "objects": [{"partId": "...", "group": "cell 1"}, ...]}'
//   gatekeeper-cli move-object '{"sceneId": "...", "objectId": "...", "pose": {...}}'
//   gatekeeper-cli drag < moves.jsonl                (one MoveObjectRequest JSON per line)
//   gatekeeper-cli start-audit '{"sceneId": "...", "clearanceMm": 10, "rules": [...]}' | watch-audit JOB | cancel-audit JOB
//   gatekeeper-cli audit-report JOB [--html report.html] [--bcf clashes.bcfzip]
//   gatekeeper-cli set-clash-status '{"sceneId": "...", "clashId": "...", "status": "CLASH_REVIEWED"}' | clash-statuses SCENE
// Exit status: 0 on OK, 1 on an RPC error (printed as JSON with its code), 2 on bad usage.
#include "clients/channel_options.h"
#include "clients/gatekeeper_client/audit_report.h"
#include "clients/gatekeeper_client/bcf_export.h"
#include "clients/gatekeeper_client/upload.h"
#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <CLI/CLI.hpp>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace pb = ::gatekeeper::v1;
using google::protobuf::Message;

namespace {

int print_reply(const grpc::Status& status, const Message& reply) {
  if (!status.ok()) {
    std::printf("{\"error\": {\"code\": %d, \"message\": \"%s\"}}\n", static_cast<int>(status.error_code()),
                status.error_message().c_str());
    return 1;
  }
  std::string json;
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(reply, &json, options);
  std::printf("%s", json.c_str());
  return 0;
}

bool parse(const std::string& json, Message* request) {
  if (json.empty()) return true;
  const auto status = google::protobuf::util::JsonStringToMessage(json, request);
  if (!status.ok()) {
    std::fprintf(stderr, "request JSON: %s\n", status.ToString().c_str());
    return false;
  }
  return true;
}


}  // namespace

int main(int argc, char** argv) {
  gk::clients::ChannelOptions connection;
  double timeout_s = 30.0;
  CLI::App app{"gatekeeper-cli: every gatekeeperd RPC, JSON in and out"};
  connection.add_to(app);
  app.add_option("--timeout", timeout_s, "deadline per call, seconds");
  app.require_subcommand(1);
  std::string json, id, file, name;
  auto* server_info = app.add_subcommand("server-info", "version, machines, per-RPC counts and latencies");
  auto* machines = app.add_subcommand("machines", "list the machines");
  auto* machine = app.add_subcommand("machine", "one machine with its model file and state");
  machine->add_option("id", id);
  auto* set_state = app.add_subcommand("set-state", "set a machine's state (SetMachineStateRequest JSON)");
  set_state->add_option("json", json)->required();
  auto* validate = app.add_subcommand("validate-step", "ValidateStepRequest JSON");
  validate->add_option("json", json)->required();
  auto* validate_many = app.add_subcommand("validate-steps", "ValidateStepsRequest JSON");
  validate_many->add_option("json", json)->required();
  auto* upload = app.add_subcommand("upload", "upload a part file (STL, OBJ, OFF, PLY, glTF, STEP, BREP, IGES)");
  upload->add_option("file", file)->required()->check(CLI::ExistingFile);
  upload->add_option("--name", name);
  auto* part_info = app.add_subcommand("part-info", "a stored part");
  part_info->add_option("id", id)->required();
  auto* clearance = app.add_subcommand("clearance", "ClearanceQueryRequest JSON");
  clearance->add_option("json", json)->required();
  std::string id2;
  auto* put_model = app.add_subcommand("put-model", "add or replace a machine from a model file");
  put_model->add_option("id", id)->required();
  put_model->add_option("file", file)->required()->check(CLI::ExistingFile);
  auto* create_scene = app.add_subcommand("create-scene", "a new, empty scene");
  create_scene->add_option("name", name);
  auto* scene = app.add_subcommand("scene", "a scene and its objects");
  scene->add_option("id", id)->required();
  auto* put_object = app.add_subcommand("put-object", "PutObjectRequest JSON");
  put_object->add_option("json", json)->required();
  auto* put_objects = app.add_subcommand("put-objects", "PutObjectsRequest JSON (a batch, all or nothing)");
  put_objects->add_option("json", json)->required();
  auto* move_object = app.add_subcommand("move-object", "MoveObjectRequest JSON");
  move_object->add_option("json", json)->required();
  auto* drag = app.add_subcommand("drag", "MoveObjectRequest JSON lines on stdin, each answered");
  auto* delete_object = app.add_subcommand("delete-object", "remove an object from a scene");
  delete_object->add_option("scene", id)->required();
  delete_object->add_option("object", id2)->required();
  auto* start_audit = app.add_subcommand("start-audit", "StartAuditRequest JSON");
  start_audit->add_option("json", json)->required();
  auto* watch_audit = app.add_subcommand("watch-audit", "stream an audit's progress");
  watch_audit->add_option("job", id)->required();
  auto* cancel_audit = app.add_subcommand("cancel-audit", "cancel an audit (its results so far are kept)");
  cancel_audit->add_option("job", id)->required();
  auto* set_clash_status = app.add_subcommand("set-clash-status", "SetClashStatusRequest JSON (a clash's review status)");
  set_clash_status->add_option("json", json)->required();
  auto* clash_statuses = app.add_subcommand("clash-statuses", "every clash's review status in a scene");
  clash_statuses->add_option("scene", id)->required();
  auto* audit_report = app.add_subcommand("audit-report", "an audit's progress and clashes");
  audit_report->add_option("job", id)->required();
  std::string html_file;
  audit_report->add_option("--html", html_file, "also write the report page (3D view, sortable clash table) to this file");
  std::string bcf_file;
  audit_report->add_option("--bcf", bcf_file,
                           "also write the clashes as BCF 2.1 (one topic and viewpoint per clash) to this .bcfzip file");
  CLI11_PARSE(app, argc, argv);

  grpc::ChannelArguments channel_args;
  // The report's clashes come in pages; its HTML page holds every clash in one message.
  if (!html_file.empty()) channel_args.SetMaxReceiveMessageSize(512 << 20);
  std::shared_ptr<grpc::Channel> channel;
  try {
    channel = connection.open(channel_args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  auto stub = pb::Gatekeeper::NewStub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(static_cast<long>(timeout_s * 1000)));

  if (*server_info) {
    pb::ServerInfo reply;
    return print_reply(stub->GetServerInfo(&ctx, {}, &reply), reply);
  }
  if (*machines) {
    pb::ListMachinesResponse reply;
    return print_reply(stub->ListMachines(&ctx, {}, &reply), reply);
  }
  if (*machine) {
    pb::GetMachineRequest request;
    request.set_machine_id(id);
    pb::MachineInfo reply;
    return print_reply(stub->GetMachine(&ctx, request, &reply), reply);
  }
  if (*set_state) {
    pb::SetMachineStateRequest request;
    if (!parse(json, &request)) return 2;
    pb::MachineInfo reply;
    return print_reply(stub->SetMachineState(&ctx, request, &reply), reply);
  }
  if (*validate) {
    pb::ValidateStepRequest request;
    if (!parse(json, &request)) return 2;
    pb::ValidateStepResponse reply;
    return print_reply(stub->ValidateStep(&ctx, request, &reply), reply);
  }
  if (*validate_many) {
    pb::ValidateStepsRequest request;
    if (!parse(json, &request)) return 2;
    pb::ValidateStepsResponse reply;
    return print_reply(stub->ValidateSteps(&ctx, request, &reply), reply);
  }
  if (*part_info) {
    pb::GetPartInfoRequest request;
    request.set_part_id(id);
    pb::PartInfo reply;
    return print_reply(stub->GetPartInfo(&ctx, request, &reply), reply);
  }
  if (*clearance) {
    pb::ClearanceQueryRequest request;
    if (!parse(json, &request)) return 2;
    pb::ClearanceQueryResponse reply;
    return print_reply(stub->ClearanceQuery(&ctx, request, &reply), reply);
  }
  if (*put_model) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    pb::PutMachineModelRequest request;
    request.set_machine_id(id);
    request.set_model_toml(text.str());
    pb::MachineInfo reply;
    return print_reply(stub->PutMachineModel(&ctx, request, &reply), reply);
  }
  if (*create_scene) {
    pb::CreateSceneRequest request;
    request.set_name(name);
    pb::SceneInfo reply;
    return print_reply(stub->CreateScene(&ctx, request, &reply), reply);
  }
  if (*scene) {
    pb::GetSceneRequest request;
    request.set_scene_id(id);
    pb::SceneInfo reply;
    return print_reply(stub->GetScene(&ctx, request, &reply), reply);
  }
  if (*put_object) {
    pb::PutObjectRequest request;
    if (!parse(json, &request)) return 2;
    pb::MoveResult reply;
    return print_reply(stub->PutObject(&ctx, request, &reply), reply);
  }
  if (*put_objects) {
    pb::PutObjectsRequest request;
    if (!parse(json, &request)) return 2;
    pb::PutObjectsResponse reply;
    return print_reply(stub->PutObjects(&ctx, request, &reply), reply);
  }
  if (*move_object) {
    pb::MoveObjectRequest request;
    if (!parse(json, &request)) return 2;
    pb::MoveResult reply;
    return print_reply(stub->MoveObject(&ctx, request, &reply), reply);
  }
  if (*drag) {
    auto stream = stub->DragObject(&ctx);
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line.empty()) continue;
      pb::MoveObjectRequest request;
      if (!parse(line, &request)) return 2;
      if (!stream->Write(request)) break;
      pb::MoveResult reply;
      if (!stream->Read(&reply)) break;
      print_reply(grpc::Status::OK, reply);
      std::printf("\n");
    }
    stream->WritesDone();
    pb::MoveResult none;
    const grpc::Status status = stream->Finish();
    return status.ok() ? 0 : print_reply(status, none);
  }
  if (*delete_object) {
    pb::DeleteObjectRequest request;
    request.set_scene_id(id);
    request.set_object_id(id2);
    pb::SceneInfo reply;
    return print_reply(stub->DeleteObject(&ctx, request, &reply), reply);
  }
  if (*start_audit) {
    pb::StartAuditRequest request;
    if (!parse(json, &request)) return 2;
    pb::AuditJob reply;
    return print_reply(stub->StartAudit(&ctx, request, &reply), reply);
  }
  if (*watch_audit) {
    pb::WatchAuditRequest request;
    request.set_job_id(id);
    auto reader = stub->WatchAudit(&ctx, request);
    pb::AuditProgress progress;
    while (reader->Read(&progress)) {
      print_reply(grpc::Status::OK, progress);
      std::printf("\n");
    }
    const grpc::Status status = reader->Finish();
    return status.ok() ? 0 : print_reply(status, progress);
  }
  if (*cancel_audit) {
    pb::CancelAuditRequest request;
    request.set_job_id(id);
    pb::AuditProgress reply;
    return print_reply(stub->CancelAudit(&ctx, request, &reply), reply);
  }
  if (*set_clash_status) {
    pb::SetClashStatusRequest request;
    if (!parse(json, &request)) return 2;
    pb::ClashStatusInfo reply;
    return print_reply(stub->SetClashStatus(&ctx, request, &reply), reply);
  }
  if (*clash_statuses) {
    pb::ListClashStatusesRequest request;
    request.set_scene_id(id);
    pb::ListClashStatusesResponse reply;
    return print_reply(stub->ListClashStatuses(&ctx, request, &reply), reply);
  }
  if (*audit_report) {
    pb::AuditReport reply;
    const grpc::Status status = gk::client::read_audit_report(*stub, id, &reply);
    if (status.ok() && !bcf_file.empty()) {
      if (bcf_file == html_file) {
        std::fprintf(stderr, "--bcf and --html name the same file\n");
        return 2;
      }
      if (reply.progress().state() != pb::DONE)
        std::fprintf(stderr, "--bcf: the audit is %s: the file holds the clashes found so far\n",
                     pb::AuditState_Name(reply.progress().state()).c_str());
      std::string archive, error;
      bool written = false;
      try {
        written = gk::client::write_bcf(reply, {}, &archive, &error);
      } catch (const std::exception& e) {
        error = e.what();
      }
      if (!written) {
        std::fprintf(stderr, "--bcf: %s\n", error.c_str());
        return 1;
      }
      std::ofstream out(bcf_file, std::ios::binary);
      out << archive;
      if (!out) {
        std::fprintf(stderr, "--bcf: cannot write %s\n", bcf_file.c_str());
        return 1;
      }
    }
    if (status.ok() && !html_file.empty()) {
      pb::GetAuditReportRequest request;
      request.set_job_id(id);
      request.set_html(true);
      request.set_page_size(1);  // the page holds every clash; the reply's own list need not
      pb::AuditReport with_page;
      const grpc::Status page = stub->GetAuditReport(&ctx, request, &with_page);
      if (!page.ok()) return print_reply(page, with_page);
      std::ofstream(html_file, std::ios::binary) << with_page.html();
    }
    return print_reply(status, reply);
  }
  if (*upload) {
    std::ifstream in(file, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    const std::string bytes = buffer.str();
    gk::client::UploadOptions upload_options;
    upload_options.format = gk::client::format_of(file);
    upload_options.name = name.empty() ? std::filesystem::path(file).filename().string() : name;
    pb::PartInfo reply;
    return print_reply(gk::client::upload_part(*stub, bytes, upload_options, &reply), reply);
  }
  return 2;
}
