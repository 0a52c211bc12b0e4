// gatekeeper-loadgen: drives ValidateStep on a gatekeeperd with N concurrent callers for a fixed
// count or duration, and prints the latency histogram and the count of every status code.
//
//   gatekeeper-loadgen --address 127.0.0.1:50051 --concurrency 8 --seconds 10 [--distinct 1000] [--json]
//
// --distinct cycles the requests through that many different bends (flange height and angle), so
// that 1 measures the memo path and a large number the full pipeline.
#include "clients/channel_options.h"
#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <CLI/CLI.hpp>
#include <grpcpp/grpcpp.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

namespace pb = ::gatekeeper::v1;
using Clock = std::chrono::steady_clock;

namespace {

pb::ValidateStepRequest request_number(long i) {
  pb::ValidateStepRequest r;
  r.mutable_part()->set_width_mm(1000.0);
  r.mutable_part()->set_depth_mm(800.0);
  r.mutable_part()->set_thickness_mm(1.5);
  r.mutable_step()->set_kind(pb::BEND_UP);
  // Flanges of 20-270 mm (some hit the upper beam) at 30-135 degrees.
  r.mutable_step()->mutable_bend_point()->set_y_mm(800.0 - (20.0 + static_cast<double>(i % 251)));
  r.mutable_step()->mutable_bend_direction()->set_x_mm(1.0);
  r.mutable_step()->set_target_angle_deg(30.0 + static_cast<double>((i / 251) % 106));
  r.set_skip_corrections(true);
  r.mutable_state()->set_clamp_z_mm(1.5);
  r.mutable_state()->set_manipulator_y_mm(-400.0);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  gk::clients::ChannelOptions connection;
  int concurrency = 1;
  double seconds = 5.0;
  long count = 0;
  long distinct = 1;
  bool json = false;
  CLI::App app{"gatekeeper-loadgen: ValidateStep load with latency histogram and status counts"};
  connection.add_to(app);
  app.add_option("--concurrency", concurrency)->check(CLI::Range(1, 1024));
  app.add_option("--seconds", seconds, "run this long (ignored with --count)")->check(CLI::Range(0.1, 3600.0));
  app.add_option("--count", count, "total calls instead of a duration")->check(CLI::Range(0L, 100000000L));
  app.add_option("--distinct", distinct, "different requests cycled through")->check(CLI::Range(1L, 100000000L));
  app.add_flag("--json", json, "print the summary as JSON");
  CLI11_PARSE(app, argc, argv);

  // One channel per 8 callers: one HTTP/2 connection serialises its streams' framing.
  const int channels = std::max(1, concurrency / 8);
  std::vector<std::unique_ptr<pb::Gatekeeper::Stub>> stubs;
  for (int c = 0; c < channels; ++c) {
    grpc::ChannelArguments args;
    args.SetInt("grpc.channel_id", c);  // distinct channels, not a shared subchannel
    std::shared_ptr<grpc::Channel> channel;
    try {
      channel = connection.open(args);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    }
    if (!channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10))) {
      std::fprintf(stderr, "cannot connect to %s\n", connection.address.c_str());
      return 2;
    }
    stubs.push_back(pb::Gatekeeper::NewStub(channel));
  }
  std::atomic<long> issued{0};
  std::mutex merge;
  std::vector<double> latencies_us;
  std::map<std::string, long> by_status;
  const auto start = Clock::now();
  const auto stop_at = start + std::chrono::duration<double>(seconds);
  std::vector<std::thread> workers;
  for (int w = 0; w < concurrency; ++w) {
    workers.emplace_back([&, w] {
      std::vector<double> mine;
      std::map<std::string, long> statuses;
      pb::Gatekeeper::Stub& stub = *stubs[w % channels];
      for (;;) {
        const long i = issued.fetch_add(1);
        if (count > 0 ? i >= count : Clock::now() >= stop_at) break;
        const pb::ValidateStepRequest req = request_number(i % distinct);
        pb::ValidateStepResponse resp;
        grpc::ClientContext ctx;
        ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
        const auto t0 = Clock::now();
        const grpc::Status s = stub.ValidateStep(&ctx, req, &resp);
        mine.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        ++statuses[s.ok() ? "OK" : std::to_string(static_cast<int>(s.error_code()))];
      }
      std::lock_guard<std::mutex> lock(merge);
      latencies_us.insert(latencies_us.end(), mine.begin(), mine.end());
      for (const auto& [k, v] : statuses) by_status[k] += v;
    });
  }
  for (auto& t : workers) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  std::sort(latencies_us.begin(), latencies_us.end());
  auto pct = [&](double q) {
    return latencies_us.empty() ? 0.0 : latencies_us[std::min(latencies_us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(latencies_us.size())))];
  };
  nlohmann::json out = {{"address", connection.address},
                        {"concurrency", concurrency},
                        {"distinct_requests", distinct},
                        {"calls", latencies_us.size()},
                        {"seconds", elapsed},
                        {"calls_per_second", static_cast<double>(latencies_us.size()) / elapsed},
                        {"p50_us", pct(0.50)},
                        {"p90_us", pct(0.90)},
                        {"p99_us", pct(0.99)},
                        {"max_us", latencies_us.empty() ? 0.0 : latencies_us.back()},
                        {"status_counts", by_status}};
  // Latency histogram: counts per power-of-two bucket of microseconds.
  std::map<long, long> histogram;
  for (double us : latencies_us) {
    long bucket = 1;
    while (static_cast<double>(bucket) < us) bucket *= 2;
    ++histogram[bucket];
  }
  for (const auto& [bucket, n] : histogram) out["histogram_us_le"][std::to_string(bucket)] = n;
  if (json) {
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    std::printf("%ld calls in %.2f s with %d callers: %.0f calls/s; p50 %.0f us, p90 %.0f us, p99 %.0f us, max %.0f us\n",
                static_cast<long>(latencies_us.size()), elapsed, concurrency, out["calls_per_second"].get<double>(),
                pct(0.5), pct(0.9), pct(0.99), out["max_us"].get<double>());
    for (const auto& [k, v] : by_status) std::printf("  status %s: %ld\n", k.c_str(), v);
    for (const auto& [bucket, n] : histogram) std::printf("  <= %6ld us: %ld\n", bucket, n);
  }
  return by_status.size() == 1 && by_status.count("OK") ? 0 : 1;
}
