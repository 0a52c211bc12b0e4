#include "server/metrics_endpoint.h"

#include "server/access_control.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <vector>

namespace gk::server {
namespace {

using Clock = std::chrono::steady_clock;

struct Connection {
  int fd = -1;
  Clock::time_point deadline;
  std::string in;         // the request head as it arrives
  std::string out;        // the whole answer, once the head is complete
  std::size_t sent = 0;
};

std::string response(int status, const char* reason, const std::string& type, const std::string& body) {
  return "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\nContent-Type: " + type +
         "\r\nContent-Length: " + std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body;
}

// The answer to a complete request head: its first line only matters.
std::string answer(const std::string& head, const std::function<std::string()>& render) {
  const std::size_t eol = head.find_first_of("\r\n");
  const std::string line = head.substr(0, eol);
  const std::size_t sp1 = line.find(' ');
  const std::size_t sp2 = sp1 == std::string::npos ? std::string::npos : line.find(' ', sp1 + 1);
  if (sp1 == std::string::npos || sp2 == std::string::npos || line.compare(sp2 + 1, 5, "HTTP/") != 0)
    return response(400, "Bad Request", "text/plain", "bad request line\n");
  const std::string method = line.substr(0, sp1), target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  const std::string path = target.substr(0, target.find('?'));
  if (path != "/metrics") return response(404, "Not Found", "text/plain", "only /metrics is served\n");
  if (method != "GET") return response(405, "Method Not Allowed", "text/plain", "GET only\n");
  return response(200, "OK", "text/plain; version=0.0.4; charset=utf-8", render());
}

// Strictly "host:port" with a port of 0..65535 written in digits only.
bool split_listen(const std::string& listen, std::string& host, int& port) {
  const std::size_t colon = listen.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size() || listen.size() - colon - 1 > 5) return false;
  port = 0;
  for (std::size_t i = colon + 1; i < listen.size(); ++i) {
    if (listen[i] < '0' || listen[i] > '9') return false;
    port = port * 10 + (listen[i] - '0');
  }
  if (port > 65535) return false;
  host = listen.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  return !host.empty();
}

}  // namespace

MetricsEndpoint::MetricsEndpoint(std::function<std::string()> render) : render_(std::move(render)) {}

MetricsEndpoint::~MetricsEndpoint() {
  stopping_ = true;
  if (wake_[1] >= 0) {
    const char byte = 0;
    (void)!::write(wake_[1], &byte, 1);
  }
  if (thread_.joinable()) thread_.join();
  for (int fd : {listen_fd_, wake_[0], wake_[1]})
    if (fd >= 0) ::close(fd);
}

Result<int> MetricsEndpoint::start(const std::string& listen) {
  std::string host;
  int port = 0;
  if (!split_listen(listen, host, port))
    return invalid_argument("metrics_listen", "\"" + listen + "\" is not host:port with a port of 0..65535");
  if (!is_loopback_listen_address(listen))
    return invalid_argument("metrics_listen", listen + " is beyond loopback: metrics are served on loopback only");
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0 || found == nullptr)
    return invalid_argument("metrics_listen", "cannot resolve " + host);
  int bound_port = -1;
  for (addrinfo* a = found; a != nullptr && bound_port < 0; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_storage local{};
    socklen_t length = sizeof local;
    if (::bind(fd, a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd, 16) == 0 &&
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &length) == 0) {
      listen_fd_ = fd;
      bound_port = local.ss_family == AF_INET6 ? ntohs(reinterpret_cast<sockaddr_in6*>(&local)->sin6_port)
                                               : ntohs(reinterpret_cast<sockaddr_in*>(&local)->sin_port);
    } else {
      ::close(fd);
    }
  }
  ::freeaddrinfo(found);
  if (bound_port < 0) return invalid_argument("metrics_listen", "cannot listen on " + listen + ": " + std::strerror(errno));
  if (::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) return Error{ErrorCode::kInternal, "metrics_listen", "no pipe"};
  thread_ = std::thread([this] { serve(); });
  return bound_port;
}

void MetricsEndpoint::serve() {
  std::vector<Connection> open;
  std::vector<pollfd> polled;
  while (!stopping_) {
    polled.clear();
    polled.push_back({wake_[0], POLLIN, 0});
    // Beyond the limit, new connections wait in the listen backlog until one closes.
    if (static_cast<int>(open.size()) < kMaxConnections) polled.push_back({listen_fd_, POLLIN, 0});
    const std::size_t first_connection = polled.size();
    for (const Connection& c : open) polled.push_back({c.fd, static_cast<short>(c.out.empty() ? POLLIN : POLLOUT), 0});
    ::poll(polled.data(), polled.size(), 100);
    if (stopping_) break;
    const auto now = Clock::now();
    const bool listening = first_connection == 2;
    if (listening && (polled[1].revents & POLLIN)) {
      for (;;) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) break;
        open.push_back({fd, now + std::chrono::milliseconds(kConnectionMillis), {}, {}, 0});
        if (static_cast<int>(open.size()) >= kMaxConnections) break;
      }
    }
    for (std::size_t i = 0; i < open.size(); ++i) {
      Connection& c = open[i];
      const std::size_t at = first_connection + i;
      const short events = at < polled.size() && polled[at].fd == c.fd ? polled[at].revents : 0;
      bool done = now >= c.deadline || (events & (POLLERR | POLLNVAL)) != 0;
      if (!done && c.out.empty() && (events & (POLLIN | POLLHUP))) {
        char buffer[4096];
        const ssize_t n = ::recv(c.fd, buffer, sizeof buffer, 0);
        if (n <= 0) {
          done = n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK);
        } else {
          c.in.append(buffer, static_cast<std::size_t>(n));
          const std::size_t end = c.in.find("\r\n\r\n") != std::string::npos ? c.in.find("\r\n\r\n") : c.in.find("\n\n");
          if (end != std::string::npos) c.out = answer(c.in.substr(0, end), render_);
          else if (c.in.size() > kMaxRequestHeadBytes)
            c.out = response(431, "Request Header Fields Too Large", "text/plain", "request head over 8 KiB\n");
          if (!c.out.empty()) c.in.clear();
        }
      }
      if (!done && !c.out.empty() && (events & POLLOUT)) {
        const ssize_t n = ::send(c.fd, c.out.data() + c.sent, c.out.size() - c.sent, MSG_NOSIGNAL);
        if (n > 0) c.sent += static_cast<std::size_t>(n);
        else if (errno != EAGAIN && errno != EWOULDBLOCK) done = true;
        if (c.sent == c.out.size()) done = true;
      }
      if (done) {
        ::close(c.fd);
        c.fd = -1;
      }
    }
    open.erase(std::remove_if(open.begin(), open.end(), [](const Connection& c) { return c.fd < 0; }), open.end());
  }
  for (const Connection& c : open) ::close(c.fd);
}

}  // namespace gk::server
