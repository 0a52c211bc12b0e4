// GET /metrics over plain HTTP on a loopback address of its own (never the gRPC port, never
// beyond loopback: the numbers say what the daemon is doing, and a scraper on the same host or a
// sidecar reads them). Served by cpp-httplib on its own four threads; a slow or hostile client is
// cut off by short timeouts (1 s to send a request, 2 s to read or write it), one request per
// connection, and a 4 KiB request body limit.
#pragma once

#include "kernel/core/status.h"

#include <functional>
#include <memory>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace gk::server {

class MetricsEndpoint {
 public:
  // render() is called for each scrape, on the endpoint's threads.
  explicit MetricsEndpoint(std::function<std::string()> render);
  ~MetricsEndpoint();  // stops serving
  MetricsEndpoint(const MetricsEndpoint&) = delete;
  MetricsEndpoint& operator=(const MetricsEndpoint&) = delete;

  // Listens on "host:port" (port 0: any free port) of a loopback host and serves until destroyed;
  // returns the bound port, or an error naming the field "metrics_listen".
  Result<int> start(const std::string& listen);

 private:
  std::function<std::string()> render_;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
};

}  // namespace gk::server
