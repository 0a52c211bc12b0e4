#include "engine/parts/cad_sandbox.h"

#include "engine/parts/part_registry.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace gk::engine {
namespace {

CadSandbox& configured() {
  static CadSandbox sandbox;
  return sandbox;
}

// Sanitizer builds reserve terabytes of address space for their shadow memory at start: an
// address-space limit would stop the child before it reads anything. They run without one.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kAddressSpaceLimit = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
constexpr bool kAddressSpaceLimit = false;
#else
constexpr bool kAddressSpaceLimit = true;
#endif
#else
constexpr bool kAddressSpaceLimit = true;
#endif

constexpr int kReadCleanly = 0;
constexpr int kRefused = 3;
constexpr std::size_t kMaxMessageBytes = 4096;

}  // namespace

void set_cad_sandbox(const CadSandbox& sandbox) { configured() = sandbox; }
const CadSandbox& cad_sandbox() { return configured(); }

Result<bool> check_cad_in_child(const std::string& path, const std::string& format, double deflection_mm) {
  const CadSandbox& sandbox = configured();
  if (sandbox.executable.empty()) return true;
  int channel[2];
  if (::pipe2(channel, O_CLOEXEC) != 0) return Error{ErrorCode::kInternal, "", "cad check: pipe: " + std::string(std::strerror(errno))};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);  // OCCT's chatter
  posix_spawn_file_actions_adddup2(&actions, channel[1], 2);
  const std::string deflection = std::to_string(deflection_mm), memory = std::to_string(sandbox.memory_bytes);
  std::vector<char*> args = {const_cast<char*>(sandbox.executable.c_str()), const_cast<char*>("--check-cad"),
                             const_cast<char*>(path.c_str()), const_cast<char*>(format.c_str()),
                             const_cast<char*>(deflection.c_str()), const_cast<char*>(memory.c_str()), nullptr};
  pid_t child = -1;
  const int spawned = ::posix_spawn(&child, sandbox.executable.c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(channel[1]);
  if (spawned != 0) {
    ::close(channel[0]);
    return Error{ErrorCode::kInternal, "", "cad check: cannot start " + sandbox.executable + ": " + std::strerror(spawned)};
  }
  // Collect what the child says (its refusal) until it ends or the time is up.
  std::string message;
  const auto deadline = std::chrono::steady_clock::now() + sandbox.timeout;
  bool open = true, timed_out = false;
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(child, SIGKILL);
      ::waitpid(child, &status, 0);
      timed_out = true;
      break;
    }
    if (open) {
      pollfd p{channel[0], POLLIN, 0};
      if (::poll(&p, 1, 20) > 0) {
        char buffer[512];
        const ssize_t n = ::read(channel[0], buffer, sizeof buffer);
        if (n <= 0) open = false;
        else if (message.size() < kMaxMessageBytes) message.append(buffer, static_cast<std::size_t>(n));
      }
    } else {
      ::usleep(5000);
    }
    if (done == child) {
      // Exited; drain what is left of the message, then stop.
      char buffer[512];
      ssize_t n;
      while ((n = ::read(channel[0], buffer, sizeof buffer)) > 0 && message.size() < kMaxMessageBytes)
        message.append(buffer, static_cast<std::size_t>(n));
      break;
    }
  }
  ::close(channel[0]);
  // A child killed or crashed never removed the link with the format's extension it made for the
  // reader (engine/parts/part_registry): removed here, or refused uploads would pile up in tmp/.
  if (std::filesystem::path(path).extension() != "." + format) {
    std::error_code ec;
    std::filesystem::remove(path + "." + format, ec);
  }
  if (timed_out)
    return invalid_argument("data", "reading the CAD file took longer than " + std::to_string(sandbox.timeout.count()) +
                                        " s: refused");
  if (WIFSIGNALED(status))
    return invalid_argument("data", "the CAD reader crashed on this file (signal " + std::to_string(WTERMSIG(status)) +
                                        "): refused; the daemon is unaffected");
  if (WIFEXITED(status) && WEXITSTATUS(status) == kReadCleanly) return true;
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  if (WIFEXITED(status) && WEXITSTATUS(status) == kRefused) return invalid_argument("data", message);
  return invalid_argument("data", "the CAD reader failed on this file (exit status " +
                                      std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + "): refused" +
                                      (message.empty() ? "" : ": " + message));
}

int run_cad_check(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: %s --check-cad PATH FORMAT DEFLECTION_MM MEMORY_BYTES\n", argv[0]);
    return 2;
  }
  const double deflection = std::strtod(argv[4], nullptr);
  const unsigned long long memory = std::strtoull(argv[5], nullptr, 10);
  if (kAddressSpaceLimit && memory > 0) {
    const rlimit limit{memory, memory};
    ::setrlimit(RLIMIT_AS, &limit);
  }
  try {
    auto mesh = PartRegistry::read_in_process(argv[2], argv[3], deflection);
    if (!mesh.ok()) {
      std::fprintf(stderr, "%s\n", mesh.error().message.c_str());
      return kRefused;
    }
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "reading the CAD file needs more than %llu bytes of memory: refused\n", memory);
    return kRefused;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "the CAD reader failed: %s\n", e.what());
    return kRefused;
  }
  return kReadCleanly;
}

}  // namespace gk::engine
