#include "server/metrics_endpoint.h"

#include "server/access_control.h"

#include <httplib.h>

namespace gk::server {

MetricsEndpoint::MetricsEndpoint(std::function<std::string()> render)
    : render_(std::move(render)), http_(std::make_unique<httplib::Server>()) {}

MetricsEndpoint::~MetricsEndpoint() {
  http_->stop();
  if (thread_.joinable()) thread_.join();
}

Result<int> MetricsEndpoint::start(const std::string& listen) {
  const std::size_t colon = listen.rfind(':');
  if (colon == std::string::npos || colon + 1 == listen.size())
    return invalid_argument("metrics_listen", "\"" + listen + "\" is not host:port");
  if (!is_loopback_listen_address(listen))
    return invalid_argument("metrics_listen", listen + " is beyond loopback: metrics are served on loopback only");
  std::string host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  int port = -1;
  try {
    std::size_t used = 0;
    port = std::stoi(listen.substr(colon + 1), &used);
    if (used != listen.size() - colon - 1) port = -1;
  } catch (const std::exception&) {
    port = -1;
  }
  if (port < 0 || port > 65535) return invalid_argument("metrics_listen", "the port of \"" + listen + "\" is not 0..65535");

  http_->new_task_queue = [] { return new httplib::ThreadPool(4); };
  http_->set_keep_alive_timeout(1);  // a connection that sends nothing holds a thread this long
  http_->set_read_timeout(2, 0);
  http_->set_write_timeout(2, 0);
  http_->set_keep_alive_max_count(1);
  http_->set_payload_max_length(4096);
  http_->Get("/metrics", [this](const httplib::Request&, httplib::Response& response) {
    response.set_content(render_(), "text/plain; version=0.0.4; charset=utf-8");
  });
  const int bound = port == 0 ? http_->bind_to_any_port(host) : (http_->bind_to_port(host, port) ? port : -1);
  if (bound <= 0) return invalid_argument("metrics_listen", "cannot listen on " + listen);
  thread_ = std::thread([this] { http_->listen_after_bind(); });
  return bound;
}

}  // namespace gk::server
