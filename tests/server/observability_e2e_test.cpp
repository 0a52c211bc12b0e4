// What an operator reads, on the real daemon: GET /metrics in Prometheus text (checked by the
// prometheus_client package's own parser, and its numbers against the calls this test made),
// and the JSON log, one object per line (read back with nlohmann::json), with a call line per
// answer carrying the request id the client sent and the deciding stage the answer reported.
#include "tests/server/daemon_fixture.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

int read_port(const std::string& file) {
  for (int i = 0; i < 200; ++i) {
    std::ifstream in(file);
    int port = 0;
    if (in >> port && port > 0) return port;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  return 0;
}

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  timeval timeout{10, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  return fd;
}

// Sends `request` as it is and reads the answer to its end (the server closes the connection).
std::string http_exchange(int port, const std::string& request) {
  const int fd = connect_to(port);
  if (fd < 0) return "";
  (void)::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
  std::string answer;
  char buffer[65536];
  for (ssize_t n; (n = ::recv(fd, buffer, sizeof buffer, 0)) > 0;) answer.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  return answer;
}

int status_of(const std::string& answer) { return answer.size() > 12 ? std::atoi(answer.c_str() + 9) : 0; }

// GET /metrics: the body, with the status and content type checked.
std::string scrape(int port) {
  const std::string answer = http_exchange(port, "GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(status_of(answer), 200) << answer.substr(0, 200);
  EXPECT_NE(answer.find("Content-Type: text/plain; version=0.0.4"), std::string::npos);
  const std::size_t body = answer.find("\r\n\r\n");
  return body == std::string::npos ? "" : answer.substr(body + 4);
}

// The value of one sample line "name{labels} value" (labels as written), or -1 when absent.
double sample(const std::string& text, const std::string& series) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(series + " ", 0) == 0) return std::stod(line.substr(series.size() + 1));
  }
  return -1.0;
}

// Runs Debian's prometheus_client text parser over the exposition: its exit status and what it says.
std::pair<int, std::string> parse_with_prometheus_client(const std::string& text, const std::string& dir) {
  const std::string in = dir + "/metrics.txt", out = dir + "/parsed.txt";
  std::ofstream(in) << text;
  const std::string command =
      "/usr/bin/python3 -c 'import sys\n"
      "from prometheus_client.parser import text_string_to_metric_families\n"
      "n = 0\n"
      "for family in text_string_to_metric_families(open(sys.argv[1]).read()):\n"
      "    for s in family.samples: n += 1\n"
      "print(n)' " + in + " > " + out + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream parsed(out);
  std::stringstream said;
  said << parsed.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, said.str()};
}

std::vector<nlohmann::json> read_json_lines(const std::string& path, std::vector<std::string>* bad) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    try {
      out.push_back(nlohmann::json::parse(line));
    } catch (const nlohmann::json::exception&) {
      bad->push_back(line);
    }
  }
  return out;
}

pb::ValidateStepResponse validate(pb::Gatekeeper::Stub& stub, const pb::ValidateStepRequest& request, const std::string& request_id,
                                  std::string* echoed) {
  grpc::ClientContext ctx;
  if (!request_id.empty()) ctx.AddMetadata("x-request-id", request_id);
  pb::ValidateStepResponse response;
  const grpc::Status status = stub.ValidateStep(&ctx, request, &response);
  EXPECT_TRUE(status.ok()) << status.error_message();
  const auto& metadata = ctx.GetServerInitialMetadata();
  const auto it = metadata.find("x-request-id");
  *echoed = it == metadata.end() ? "" : std::string(it->second.data(), it->second.size());
  return response;
}

TEST(ObservabilityE2E, MetricsCountWhatWasCalledAndParseAsPrometheusText) {
  const std::string dir = testing::temp_dir("metrics");
  Daemon daemon(dir + "/data", {"--metrics-listen", "127.0.0.1:0", "--metrics-port-file", dir + "/metrics-port"});
  const int port = read_port(dir + "/metrics-port");
  ASSERT_GT(port, 0);
  auto stub = daemon.stub();

  // The same question three times (one validation, two cache answers), and a different one.
  std::string echoed;
  for (int i = 0; i < 3; ++i) validate(*stub, testing::bend_request(150.0, 90.0), "", &echoed);
  validate(*stub, testing::bend_request(250.0, 90.0), "", &echoed);
  for (int i = 0; i < 2; ++i) {  // two NOT_FOUND
    grpc::ClientContext ctx;
    pb::GetSceneRequest get;
    get.set_scene_id("no-such-scene");
    pb::SceneInfo info;
    EXPECT_EQ(stub->GetScene(&ctx, get, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  }

  {  // a stream refused: counted too
    grpc::ClientContext ctx;
    pb::WatchAuditRequest watch;
    watch.set_job_id("audit-unknown");
    auto reader = stub->WatchAudit(&ctx, watch);
    pb::AuditProgress progress;
    while (reader->Read(&progress)) {
    }
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::NOT_FOUND);
  }

  const std::string text = scrape(port);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_calls_total{method=\"ValidateStep\"}"), 4.0) << text;
  EXPECT_EQ(sample(text, "gatekeeper_rpc_errors_total{method=\"WatchAudit\"}"), 1.0);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_errors_total{method=\"ValidateStep\"}"), 0.0);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_calls_total{method=\"GetScene\"}"), 2.0);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_errors_total{method=\"GetScene\"}"), 2.0);
  EXPECT_EQ(sample(text, "gatekeeper_step_cache_hits_total"), 2.0);
  EXPECT_EQ(sample(text, "gatekeeper_step_cache_misses_total"), 2.0);
  EXPECT_EQ(sample(text, "gatekeeper_step_cache_entries"), 2.0);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_latency_seconds_bucket{method=\"ValidateStep\",le=\"+Inf\"}"), 4.0);
  EXPECT_EQ(sample(text, "gatekeeper_rpc_latency_seconds_count{method=\"ValidateStep\"}"), 4.0);
  EXPECT_GT(sample(text, "gatekeeper_rpc_latency_seconds_sum{method=\"ValidateStep\"}"), 0.0);
  EXPECT_EQ(sample(text, "gatekeeper_queue_depth{pool=\"validation\"}"), 0.0);
  EXPECT_EQ(sample(text, "gatekeeper_queue_capacity{pool=\"validation\"}"), 64.0);
  EXPECT_GT(sample(text, "process_resident_memory_bytes"), 1e6);
  // Buckets are cumulative: never decreasing with le.
  double previous = 0.0;
  std::istringstream lines(text);
  std::string line;
  int buckets = 0;
  while (std::getline(lines, line)) {
    if (line.rfind("gatekeeper_rpc_latency_seconds_bucket{method=\"ValidateStep\"", 0) != 0) continue;
    const double v = std::stod(line.substr(line.rfind(' ') + 1));
    EXPECT_GE(v, previous) << line;
    previous = v;
    ++buckets;
  }
  EXPECT_EQ(buckets, 26);

  const auto [status, said] = parse_with_prometheus_client(text, dir);
  EXPECT_EQ(status, 0) << said;
  EXPECT_GT(std::atoi(said.c_str()), 100) << said;
}

TEST(ObservabilityE2E, MetricsEndpointRefusesWhatIsNotAScrapeAndOutlivesIdleConnections) {
  const std::string dir = testing::temp_dir("metrics-hostile");
  Daemon daemon(dir + "/data", {"--metrics-listen", "127.0.0.1:0", "--metrics-port-file", dir + "/metrics-port"});
  const int port = read_port(dir + "/metrics-port");
  ASSERT_GT(port, 0);
  EXPECT_EQ(status_of(http_exchange(port, "GET /../../etc/passwd HTTP/1.1\r\n\r\n")), 404);
  EXPECT_EQ(status_of(http_exchange(port, "POST /metrics HTTP/1.1\r\nContent-Length: 5\r\n\r\nhello")), 405);
  EXPECT_EQ(status_of(http_exchange(port, "garbage\r\n\r\n")), 400);
  // A request head without an end (headers streamed on): refused at 8 KiB, not kept growing.
  {
    std::string flood = "GET /metrics HTTP/1.1\r\n";
    while (flood.size() < 1000000) flood += "X-Filler: " + std::string(100, 'x') + "\r\n";
    EXPECT_EQ(status_of(http_exchange(port, flood)), 431);
  }
  // Connections that send nothing, or trickle, hold a slot at most 2 s from their accept.
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) {
    const int fd = connect_to(port);
    ASSERT_GE(fd, 0);
    (void)::send(fd, "G", 1, MSG_NOSIGNAL);
    idle.push_back(fd);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::string text = scrape(port);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(text.find("gatekeeper_rpc_calls_total"), std::string::npos);
  EXPECT_LT(seconds, 5.0);  // the 32 slots free 2 s after their accept; the scrape is then answered
  for (int fd : idle) ::close(fd);
  // The gRPC side is unaffected.
  std::string echoed;
  auto stub = daemon.stub();
  validate(*stub, testing::bend_request(150.0, 90.0), "", &echoed);
  // A client trickling a request when the daemon is told to stop does not hold the stop.
  const int trickling = connect_to(port);
  ASSERT_GE(trickling, 0);
  (void)::send(trickling, "GET /met", 8, MSG_NOSIGNAL);
  const auto stop0 = std::chrono::steady_clock::now();
  EXPECT_EQ(daemon.stop(SIGTERM), 0);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - stop0).count(), 4.0);  // --drain-seconds 1
  ::close(trickling);
}

TEST(ObservabilityE2E, MetricsBeyondLoopbackAreRefusedAtStart) {
  const std::string dir = testing::temp_dir("metrics-public");
  const std::string command = std::string(GATEKEEPERD_PATH) + " --data-dir " + dir + "/data --listen 127.0.0.1:0 " +
                              "--metrics-listen 0.0.0.0:0 > " + dir + "/out.txt 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(testing::read_file(dir + "/out.txt").find("metrics_listen"), std::string::npos);
}

TEST(ObservabilityE2E, JsonLogHasOneObjectPerLineAndACallLineWithRequestIdAndDecidingStage) {
  const std::string dir = testing::temp_dir("json-log");
  const std::string log = dir + "/daemon.log";
  std::map<std::string, std::string> stage_of;  // request id -> deciding stage answered
  std::string hostile_echo;
  {
    Daemon daemon(dir + "/data", {"--log-format", "json", "--log-file", log, "--log-level", "info"});
    auto stub = daemon.stub();
    const std::vector<std::pair<std::string, pb::ValidateStepRequest>> asked = {
        {"plan-7.step-1", testing::bend_request(150.0, 90.0)},
        {"plan-7.step-1-again", testing::bend_request(150.0, 90.0)},  // from the cache
        {"plan-7.step-2", testing::bend_request(250.0, 90.0)},         // the beam: a collision
    };
    for (const auto& [id, request] : asked) {
      std::string echoed;
      const pb::ValidateStepResponse r = validate(*stub, request, id, &echoed);
      EXPECT_EQ(echoed, id);
      stage_of[id] = pb::DecidingStage_Name(r.deciding_stage());
    }
    EXPECT_EQ(stage_of["plan-7.step-1-again"], "DECIDING_STAGE_CACHE");
    // A request id that must not reach the log as given: replaced, and echoed as replaced.
    validate(*stub, testing::bend_request(150.0, 90.0), std::string(200, 'a') + "\"}{", &hostile_echo);
    EXPECT_EQ(hostile_echo.rfind("gk-", 0), 0u) << hostile_echo;
    // An error's text (with quotes and a newline from the caller's id) stays inside its string.
    grpc::ClientContext ctx;
    pb::GetSceneRequest get;
    get.set_scene_id("bad\"id\n{\"level\":\"fake\"}");
    pb::SceneInfo info;
    EXPECT_FALSE(stub->GetScene(&ctx, get, &info).ok());
  }  // the daemon stops: its log is complete

  std::vector<std::string> bad;
  const std::vector<nlohmann::json> lines = read_json_lines(log, &bad);
  EXPECT_TRUE(bad.empty()) << bad.size() << " lines are not JSON, the first: " << (bad.empty() ? "" : bad.front());
  ASSERT_GT(lines.size(), 5u);
  int calls = 0;
  bool saw_hostile = false, saw_failed = false;
  for (const nlohmann::json& line : lines) {
    EXPECT_TRUE(line.contains("time") && line.contains("level") && line.contains("logger")) << line.dump();
    if (line.value("logger", "") != "calls") continue;
    ++calls;
    const std::string id = line.value("request_id", "");
    if (line.value("method", "") == "ValidateStep" && stage_of.count(id)) {
      EXPECT_EQ(line.value("status", ""), "OK");
      EXPECT_EQ(line.value("deciding_stage", ""), stage_of[id]) << line.dump();
      EXPECT_TRUE(line["micros"].is_number());
      stage_of.erase(id);
    }
    if (id == hostile_echo) saw_hostile = true;
    if (line.value("method", "") == "ValidateStep") {
      EXPECT_EQ(line.value("level", ""), "info");
    }
    if (line.value("method", "") == "GetScene") {
      saw_failed = true;
      EXPECT_EQ(line.value("level", ""), "info");  // the client's mistake, not the daemon's
      EXPECT_NE(line.value("status", ""), "OK");
      EXPECT_TRUE(line.contains("error"));
    }
  }
  EXPECT_TRUE(stage_of.empty()) << stage_of.size() << " answers have no call line";
  EXPECT_TRUE(saw_hostile);
  EXPECT_TRUE(saw_failed);
  EXPECT_EQ(calls, 5);
}

}  // namespace
}  // namespace gk
