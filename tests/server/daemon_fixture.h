// Starts the real gatekeeperd binary on an ephemeral loopback port, with its own data directory,
// and stops it by signal: the service tests talk to it through real channels.
#pragma once

#include "gatekeeper/v1/gatekeeper.grpc.pb.h"
#include "tests/support/file_text.h"  // sha256_hex, obj_text

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>
#include <vector>

namespace gk::testing {

class Daemon {
 public:
  // Starts gatekeeperd; data_dir is created if needed. Fails the test if it does not come up.
  // The channel uses `credentials` (default: plain, which loopback accepts).
  explicit Daemon(const std::string& data_dir, std::vector<std::string> extra_args = {},
                  std::shared_ptr<grpc::ChannelCredentials> credentials = nullptr, grpc::ChannelArguments channel_args = {});
  ~Daemon();  // SIGTERM, then waits

  int port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  std::unique_ptr<gatekeeper::v1::Gatekeeper::Stub> stub() const;
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  // Sends a signal and waits; returns the exit status (or -signal when killed by one).
  int stop(int signal_number);

 private:
  int pid_ = -1;
  int port_ = 0;
  std::shared_ptr<grpc::Channel> channel_;
};

std::string temp_dir(const std::string& tag);
std::string read_file(const std::string& path);

// Uploads and returns the part id (a failed upload fails the test and returns "").
std::string upload_part_id(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format);

// A closed, outward-wound box from lo to hi as OBJ text (12 triangles).
std::string box_obj(double lo_x, double lo_y, double lo_z, double hi_x, double hi_y, double hi_z);

// Streams bytes to UploadPart in chunks of at most `chunk` bytes (header first); declared_sha
// empty means the true sha256.
grpc::Status upload_part(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format,
                         gatekeeper::v1::PartInfo* info, const std::string& declared_sha = "", std::size_t chunk = 1u << 20);

// A flange of flange_mm bent up to angle_deg on a 1000 x 800 x 1.5 mm blank, the manipulator on
// the held side: CLEAR below 203 mm (the beam's underside over the table), a collision above.
gatekeeper::v1::ValidateStepRequest bend_request(double flange_mm, double angle_deg);

// Starts an audit, watches it to its end and returns its report (failures fail the test).
// The scene as GetScene returns it (a failed call fails the test).
gatekeeper::v1::SceneInfo get_scene(gatekeeper::v1::Gatekeeper::Stub& stub, const std::string& scene_id);

gatekeeper::v1::AuditReport run_audit(gatekeeper::v1::Gatekeeper::Stub& stub, const gatekeeper::v1::StartAuditRequest& start,
                                      bool html = false);

}  // namespace gk::testing
