// Who may call the daemon (issue: hardened service §4), through the real daemon: loopback only
// without TLS, bearer tokens with roles, TLS and mutual TLS with certificates generated here by
// the openssl command, and private files in the data directory.
#include "tests/server/daemon_fixture.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/security/credentials.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

constexpr char kReadToken[] = "read-token-0123456789abcdef";
constexpr char kWriteToken[] = "write-token-0123456789abcdef";
constexpr char kAdminToken[] = "admin-token-0123456789abcdef";

std::string write_file(const std::string& path, const std::string& text, mode_t mode) {
  std::ofstream(path) << text;
  ::chmod(path.c_str(), mode);
  return path;
}

std::string token_file(const std::string& dir, mode_t mode = 0600) {
  return write_file(dir + "/tokens", std::string("# role token\nread ") + kReadToken + "\nwrite " + kWriteToken + "\nadmin " +
                                         kAdminToken + "\n",
                    mode);
}

// Runs gatekeeperd expecting it to refuse to start; returns its exit status and what it logged.
int refused_start(const std::string& dir, const std::string& args, std::string* log) {
  const std::string out = dir + "/refused.log";
  const std::string cmd = std::string(GATEKEEPERD_PATH) + " --data-dir " + dir + "/data --drain-seconds 0 " + args + " > " + out +
                          " 2>&1 & pid=$!; for i in $(seq 50); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done; "
                          "if kill -0 $pid 2>/dev/null; then kill $pid; wait $pid; exit 99; fi; wait $pid";
  const int status = std::system(cmd.c_str());
  std::ifstream in(out);
  log->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::shared_ptr<grpc::ChannelCredentials> with_token(const char* token) {
  return grpc::CompositeChannelCredentials(grpc::experimental::LocalCredentials(LOCAL_TCP), grpc::AccessTokenCredentials(token));
}

grpc::Status server_info(const std::shared_ptr<grpc::Channel>& channel) {
  auto stub = pb::Gatekeeper::NewStub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pb::ServerInfo out;
  return stub->GetServerInfo(&ctx, pb::GetServerInfoRequest(), &out);
}

grpc::Status create_scene(pb::Gatekeeper::Stub& stub, const std::string& id) {
  grpc::ClientContext ctx;
  pb::CreateSceneRequest request;
  request.set_name(id);
  pb::SceneInfo out;
  return stub.CreateScene(&ctx, request, &out);
}

grpc::Status put_machine_model(pb::Gatekeeper::Stub& stub) {
  grpc::ClientContext ctx;
  pb::PutMachineModelRequest request;
  request.set_machine_id("p4-default");
  pb::MachineInfo out;
  return stub.PutMachineModel(&ctx, request, &out);
}

TEST(AccessControlE2E, WithoutTlsOnlyLoopbackIsServed) {
  const std::string dir = testing::temp_dir("access-loopback");
  std::string log;
  EXPECT_EQ(refused_start(dir, "--listen 0.0.0.0:0", &log), 2) << log;
  EXPECT_NE(log.find("listen"), std::string::npos) << log;
  EXPECT_NE(log.find("TLS"), std::string::npos) << log;
  EXPECT_EQ(refused_start(dir, "--listen 192.168.1.20:0", &log), 2) << log;
  // Loopback names are served.
  Daemon daemon(dir + "/ok", {});
  EXPECT_TRUE(server_info(daemon.channel()).ok());
}

TEST(AccessControlE2E, TokensDecideWhoMayReadWriteAndAdminister) {
  const std::string dir = testing::temp_dir("access-tokens");
  Daemon daemon(dir + "/data", {"--token-file", token_file(dir)}, with_token(kReadToken));
  const std::string address = daemon.address();
  auto plain = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
  auto local_no_token = grpc::CreateChannel(address, grpc::experimental::LocalCredentials(LOCAL_TCP));
  auto wrong = grpc::CreateChannel(address, with_token("not-a-token-0123456789abcdef"));
  EXPECT_EQ(server_info(plain).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(server_info(local_no_token).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(server_info(wrong).error_code(), grpc::StatusCode::UNAUTHENTICATED);

  auto reader = pb::Gatekeeper::NewStub(daemon.channel());
  auto writer = pb::Gatekeeper::NewStub(grpc::CreateChannel(address, with_token(kWriteToken)));
  auto admin = pb::Gatekeeper::NewStub(grpc::CreateChannel(address, with_token(kAdminToken)));
  EXPECT_TRUE(server_info(daemon.channel()).ok());

  // Reading is allowed to all; writing to writers and admins; models to admins.
  EXPECT_EQ(create_scene(*reader, "by-reader").error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(create_scene(*writer, "by-writer").ok());
  EXPECT_TRUE(create_scene(*admin, "by-admin").ok());
  pb::PartInfo info;
  const std::string box = testing::box_obj(0, 0, 0, 10, 10, 10);
  EXPECT_EQ(testing::upload_part(*reader, box, "obj", &info).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_TRUE(testing::upload_part(*writer, box, "obj", &info).ok());
  {
    grpc::ClientContext ctx;
    pb::GetPartInfoRequest request;
    request.set_part_id(info.part_id());
    pb::PartInfo got;
    EXPECT_TRUE(reader->GetPartInfo(&ctx, request, &got).ok());
  }
  {
    // A drag stream is writing too.
    grpc::ClientContext ctx;
    auto stream = reader->DragObject(&ctx);
    pb::MoveObjectRequest move;
    move.set_scene_id("by-writer");
    stream->Write(move);
    stream->WritesDone();
    pb::MoveResult result;
    while (stream->Read(&result)) {
    }
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }
  EXPECT_EQ(put_machine_model(*writer).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  const grpc::Status by_admin = put_machine_model(*admin);  // allowed: refused only for its (empty) model
  EXPECT_NE(by_admin.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(by_admin.error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

// One connection carries the calls of several tokens (a proxy, or channels sharing a connection,
// gRPC's default): each call's own token decides, never the first one seen on the connection.
TEST(AccessControlE2E, EachCallsTokenDecidesOnASharedConnection) {
  const std::string dir = testing::temp_dir("access-shared-connection");
  Daemon daemon(dir + "/data", {"--token-file", token_file(dir)}, with_token(kAdminToken));
  auto channel = grpc::CreateChannel(daemon.address(), grpc::experimental::LocalCredentials(LOCAL_TCP));
  auto stub = pb::Gatekeeper::NewStub(channel);
  auto create_as = [&](const char* token) {
    grpc::ClientContext ctx;
    ctx.set_credentials(grpc::AccessTokenCredentials(token));
    pb::CreateSceneRequest request;
    request.set_name("shared");
    pb::SceneInfo out;
    return stub->CreateScene(&ctx, request, &out);
  };
  for (int round = 0; round < 2; ++round) {
    EXPECT_TRUE(create_as(kWriteToken).ok());
    EXPECT_EQ(create_as(kReadToken).error_code(), grpc::StatusCode::PERMISSION_DENIED);  // not escalated by the writer before
    EXPECT_TRUE(create_as(kAdminToken).ok());                                            // not held back by the reader before
  }
}

TEST(AccessControlE2E, ATokenFileOthersCanReadIsRefused) {
  const std::string dir = testing::temp_dir("access-token-mode");
  std::string log;
  EXPECT_EQ(refused_start(dir, "--listen 127.0.0.1:0 --token-file " + token_file(dir, 0644), &log), 2) << log;
  EXPECT_NE(log.find("token_file"), std::string::npos) << log;
  write_file(dir + "/short", "read abc\n", 0600);
  EXPECT_EQ(refused_start(dir, "--listen 127.0.0.1:0 --token-file " + dir + "/short", &log), 2) << log;
}

// A CA, a server certificate for localhost / 127.0.0.1, and a client certificate, by openssl.
struct Certificates {
  std::string dir;
  std::string ca, server_cert, server_key, client_cert, client_key, other_ca;
};

Certificates make_certificates(const std::string& dir) {
  Certificates c{dir, dir + "/ca.pem", dir + "/server.pem", dir + "/server.key", dir + "/client.pem", dir + "/client.key",
                 dir + "/other-ca.pem"};
  const std::string script =
      "set -e; cd " + dir + "; exec >openssl.log 2>&1\n"
      "openssl req -x509 -newkey rsa:2048 -nodes -keyout ca.key -out ca.pem -days 2 -subj /CN=test-ca\n"
      "openssl req -x509 -newkey rsa:2048 -nodes -keyout other-ca.key -out other-ca.pem -days 2 -subj /CN=other-ca\n"
      "openssl req -newkey rsa:2048 -nodes -keyout server.key -out server.csr -subj /CN=localhost\n"
      "printf 'subjectAltName=DNS:localhost,IP:127.0.0.1\\n' > server.ext\n"
      "openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out server.pem -days 2 -extfile server.ext\n"
      "openssl req -newkey rsa:2048 -nodes -keyout client.key -out client.csr -subj /CN=planner\n"
      "openssl x509 -req -in client.csr -CA ca.pem -CAkey ca.key -CAcreateserial -out client.pem -days 2\n"
      "mkdir -p cadb; : > cadb/index.txt; echo 01 > cadb/serial\n"
      "printf '[ca]\\ndefault_ca=d\\n[d]\\ndir=./cadb\\ndatabase=$dir/index.txt\\nserial=$dir/serial\\nnew_certs_dir=$dir\\n"
      "certificate=./ca.pem\\nprivate_key=./ca.key\\ndefault_md=sha256\\npolicy=p\\n[p]\\ncommonName=supplied\\n' > ca.cnf\n"
      "openssl ca -batch -config ca.cnf -in server.csr -out server-expired.pem -startdate 20200101000000Z "
      "-enddate 20200102000000Z -extfile server.ext\n"
      "chmod 600 server.key client.key\n";
  write_file(dir + "/make-certificates.sh", script, 0700);
  EXPECT_EQ(std::system(("bash " + dir + "/make-certificates.sh").c_str()), 0) << "openssl failed; see " << dir << "/openssl.log";
  return c;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::shared_ptr<grpc::ChannelCredentials> tls(const Certificates& c, bool with_client_cert, bool trust_other_ca = false) {
  grpc::SslCredentialsOptions o;
  o.pem_root_certs = read_text(trust_other_ca ? c.other_ca : c.ca);
  if (with_client_cert) {
    o.pem_cert_chain = read_text(c.client_cert);
    o.pem_private_key = read_text(c.client_key);
  }
  return grpc::SslCredentials(o);
}

grpc::Status info_over(const std::string& address, const std::shared_ptr<grpc::ChannelCredentials>& creds) {
  grpc::ChannelArguments args;
  args.SetSslTargetNameOverride("localhost");
  return server_info(grpc::CreateCustomChannel(address, creds, args));
}

TEST(AccessControlE2E, TlsAndMutualTlsWithRealCertificates) {
  const std::string dir = testing::temp_dir("access-tls");
  const Certificates c = make_certificates(dir);
  grpc::ChannelArguments args;
  args.SetSslTargetNameOverride("localhost");
  {
    // TLS alone on loopback; a client that does not trust the CA cannot connect, and a plain
    // client is not served. Beyond loopback TLS alone is refused (anybody could call).
    std::string log;
    EXPECT_EQ(refused_start(dir, "--listen 0.0.0.0:0 --tls-cert " + c.server_cert + " --tls-key " + c.server_key, &log), 2) << log;
    EXPECT_NE(log.find("--tls-client-ca"), std::string::npos) << log;
    Daemon daemon(dir + "/tls", {"--tls-cert", c.server_cert, "--tls-key", c.server_key}, tls(c, false), args);
    EXPECT_TRUE(server_info(daemon.channel()).ok());
    EXPECT_FALSE(info_over(daemon.address(), tls(c, false, true)).ok());
    EXPECT_FALSE(server_info(grpc::CreateChannel(daemon.address(), grpc::InsecureChannelCredentials())).ok());
  }
  {
    // Mutual TLS on every address: without a client certificate signed by the client CA there is no call.
    Daemon daemon(dir + "/mtls",
                  {"--listen", "0.0.0.0:0", "--tls-cert", c.server_cert, "--tls-key", c.server_key, "--tls-client-ca", c.ca,
                   "--token-file", token_file(dir)},
                  grpc::CompositeChannelCredentials(tls(c, true), grpc::AccessTokenCredentials(kAdminToken)), args);
    EXPECT_TRUE(server_info(daemon.channel()).ok());
    EXPECT_FALSE(info_over(daemon.address(), grpc::CompositeChannelCredentials(tls(c, false), grpc::AccessTokenCredentials(kAdminToken))).ok());
    // A certificate but no token: the token still decides.
    EXPECT_EQ(info_over(daemon.address(), tls(c, true)).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }
  // An expired server certificate is refused at startup (clients would refuse it later).
  std::string log;
  EXPECT_EQ(refused_start(dir, "--listen 127.0.0.1:0 --tls-cert " + dir + "/server-expired.pem --tls-key " + c.server_key, &log), 2)
      << log;
  EXPECT_NE(log.find("expired"), std::string::npos) << log;
  // A key file others can read is refused.
  ::chmod(c.server_key.c_str(), 0644);
  EXPECT_EQ(refused_start(dir, "--listen 127.0.0.1:0 --tls-cert " + c.server_cert + " --tls-key " + c.server_key, &log), 2) << log;
}

TEST(AccessControlE2E, TheDataDirectoryAndItsFilesArePrivate) {
  const std::string dir = testing::temp_dir("access-private");
  const std::string data = dir + "/data";
  std::filesystem::create_directories(data + "/left-behind");
  write_file(data + "/left-behind/notes.txt", "an earlier run's file\n", 0666);
  ::chmod((data + "/left-behind").c_str(), 0755);
  ::chmod(data.c_str(), 0755);  // an existing, open directory and what it holds are closed too
  Daemon daemon(data, {});
  auto stub = daemon.stub();
  pb::PartInfo info;
  ASSERT_TRUE(testing::upload_part(*stub, testing::box_obj(0, 0, 0, 10, 10, 10), "obj", &info).ok());
  ASSERT_TRUE(create_scene(*stub, "private").ok());
  struct stat st{};
  ASSERT_EQ(::stat(data.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(data)) {
    ASSERT_EQ(::stat(entry.path().c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 077, 0u) << entry.path() << " is open to group or others";
    ++files;
  }
  EXPECT_GT(files, 2);
}

}  // namespace
}  // namespace gk
