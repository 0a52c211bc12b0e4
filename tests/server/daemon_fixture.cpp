#include "tests/server/daemon_fixture.h"

#include "clients/gatekeeper_client/audit_report.h"
#include "clients/gatekeeper_client/upload.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace gk::testing {

std::string temp_dir(const std::string& tag) {
  static int counter = 0;
  const auto dir = std::filesystem::temp_directory_path() /
                   ("gk-e2e-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Daemon::Daemon(const std::string& data_dir, std::vector<std::string> extra_args,
               std::shared_ptr<grpc::ChannelCredentials> credentials, grpc::ChannelArguments channel_args) {
  const std::string port_file = data_dir + "/port";
  std::filesystem::remove(port_file);
  std::vector<std::string> args = {GATEKEEPERD_PATH, "--data-dir", data_dir, "--port-file", port_file};
  if (std::find(extra_args.begin(), extra_args.end(), "--drain-seconds") == extra_args.end()) {
    args.push_back("--drain-seconds");
    args.push_back("1");
  }
  if (std::find(extra_args.begin(), extra_args.end(), "--log-level") == extra_args.end()) {
    args.push_back("--log-level");
    args.push_back("warn");
  }
  if (std::find(extra_args.begin(), extra_args.end(), "--listen") == extra_args.end()) {
    args.push_back("--listen");
    args.push_back("127.0.0.1:0");
  }
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  pid_ = ::fork();
  if (pid_ == 0) {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  for (int i = 0; i < 400 && port_ == 0; ++i) {
    std::ifstream in(port_file);
    if (!(in >> port_)) {
      port_ = 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
  }
  if (port_ == 0) {
    ADD_FAILURE() << "gatekeeperd did not start";
    return;
  }
  channel_ = grpc::CreateCustomChannel(address(), credentials ? credentials : grpc::InsecureChannelCredentials(), channel_args);
  EXPECT_TRUE(channel_->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10)));
}

Daemon::~Daemon() {
  if (pid_ > 0) stop(SIGTERM);
}

std::unique_ptr<gatekeeper::v1::Gatekeeper::Stub> Daemon::stub() const { return gatekeeper::v1::Gatekeeper::NewStub(channel_); }

int Daemon::stop(int signal_number) {
  if (pid_ <= 0) return 0;
  ::kill(pid_, signal_number);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
  channel_.reset();
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return WIFSIGNALED(status) ? -WTERMSIG(status) : -1;
}

grpc::Status upload_part(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format,
                         gatekeeper::v1::PartInfo* info, const std::string& declared_sha, std::size_t chunk) {
  client::UploadOptions options;
  options.format = format;
  options.declared_sha = declared_sha;
  options.chunk_bytes = chunk;
  options.deadline = std::chrono::seconds(60);
  return client::upload_part(stub, bytes, options, info);
}

std::string upload_part_id(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format) {
  gatekeeper::v1::PartInfo info;
  EXPECT_TRUE(upload_part(stub, bytes, format, &info).ok());
  return info.part_id();
}

std::string box_obj(double lo_x, double lo_y, double lo_z, double hi_x, double hi_y, double hi_z) {
  std::string obj;
  for (int k = 0; k < 8; ++k)
    obj += "v " + std::to_string((k & 1) ? hi_x : lo_x) + " " + std::to_string((k & 2) ? hi_y : lo_y) + " " +
           std::to_string((k & 4) ? hi_z : lo_z) + "\n";
  return obj + "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";
}

gatekeeper::v1::ValidateStepRequest bend_request(double flange_mm, double angle_deg) {
  gatekeeper::v1::ValidateStepRequest r;
  r.mutable_part()->set_width_mm(1000.0);
  r.mutable_part()->set_depth_mm(800.0);
  r.mutable_part()->set_thickness_mm(1.5);
  r.mutable_step()->set_kind(gatekeeper::v1::BEND_UP);
  r.mutable_step()->mutable_bend_point()->set_y_mm(800.0 - flange_mm);
  r.mutable_step()->mutable_bend_direction()->set_x_mm(1.0);
  r.mutable_step()->set_target_angle_deg(angle_deg);
  r.mutable_state()->set_clamp_z_mm(1.5);
  r.mutable_state()->set_manipulator_y_mm(-400.0);  // on the held side, behind the blankholder
  return r;
}

gatekeeper::v1::SceneInfo get_scene(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& scene_id) {
  grpc::ClientContext ctx;
  gatekeeper::v1::GetSceneRequest get;
  get.set_scene_id(scene_id);
  gatekeeper::v1::SceneInfo scene;
  EXPECT_TRUE(stub.GetScene(&ctx, get, &scene).ok());
  return scene;
}

gatekeeper::v1::AuditReport run_audit(gatekeeper::v1::Gatekeeper::Stub& stub, const gatekeeper::v1::StartAuditRequest& start, bool html) {
  namespace pb = ::gatekeeper::v1;
  pb::AuditJob job;
  grpc::ClientContext sctx;
  EXPECT_TRUE(stub.StartAudit(&sctx, start, &job).ok());
  grpc::ClientContext wctx;
  pb::WatchAuditRequest watch;
  watch.set_job_id(job.job_id());
  auto reader = stub.WatchAudit(&wctx, watch);
  pb::AuditProgress progress;
  while (reader->Read(&progress)) {
  }
  EXPECT_TRUE(reader->Finish().ok());
  // Read page by page (pages of 7: most reports here span several), the page separately.
  pb::AuditReport report;
  client::ReportOptions paging;
  paging.page_size = 7;
  EXPECT_TRUE(client::read_audit_report(stub, job.job_id(), &report, paging).ok());
  EXPECT_EQ(static_cast<std::uint64_t>(report.clashes_size()), report.clashes_total());
  if (html) {
    grpc::ClientContext rctx;
    rctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    pb::GetAuditReportRequest get;
    get.set_job_id(job.job_id());
    get.set_html(true);
    pb::AuditReport with_page;
    EXPECT_TRUE(stub.GetAuditReport(&rctx, get, &with_page).ok());
    report.set_html(with_page.html());
  }
  return report;
}

}  // namespace gk::testing
