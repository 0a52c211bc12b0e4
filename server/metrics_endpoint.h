// GET /metrics over plain HTTP/1.x on a loopback address of its own (never the gRPC port, never
// beyond loopback: the numbers say what the daemon is doing; a scraper on the same host or a
// sidecar reads them).
//
// A small poll loop on one thread rather than an HTTP library: cpp-httplib 0.11 (Debian's) let one
// local connection grow the daemon's memory without bound (no limit on the number of headers:
// 41 -> 728 MiB), let four slow clients block every scrape (its timeout is per read, not per
// request), held shutdown for as long as a client trickled, and queued connections without limit
// (a thousand idle ones took the file descriptors gRPC needs to accept). Here every connection has
// 8 KiB for its request head and 2 s from accept to its last byte, at most 32 are open at once,
// each answer closes its connection, and stopping closes everything at once.
#pragma once

#include "kernel/core/status.h"

#include <atomic>
#include <functional>
#include <string>
#include <thread>

namespace gk::server {

class MetricsEndpoint {
 public:
  // render() is called for each scrape, on the endpoint's thread.
  explicit MetricsEndpoint(std::function<std::string()> render);
  ~MetricsEndpoint();  // stops serving: open connections are closed, the thread joined
  MetricsEndpoint(const MetricsEndpoint&) = delete;
  MetricsEndpoint& operator=(const MetricsEndpoint&) = delete;

  // Listens on "host:port" (port 0: any free port) of a loopback host and serves until destroyed;
  // returns the bound port, or an error naming the field "metrics_listen".
  Result<int> start(const std::string& listen);

  static constexpr std::size_t kMaxRequestHeadBytes = 8192;
  static constexpr int kMaxConnections = 32;
  static constexpr int kConnectionMillis = 2000;  // from accept to the answer's last byte

 private:
  void serve();

  std::function<std::string()> render_;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};  // a pipe: a byte in it ends serve()
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace gk::server
