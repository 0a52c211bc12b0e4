#include "server/process_memory.h"

#include <sys/resource.h>

#include <fstream>
#include <sstream>
#include <string>

namespace gk::server {

ProcessMemory read_process_memory() {
  ProcessMemory m;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    std::istringstream fields(line);
    std::string key;
    std::uint64_t kib = 0;
    if (!(fields >> key >> kib)) continue;
    if (key == "VmRSS:") m.resident_bytes = kib * 1024, m.read = true;
    else if (key == "VmHWM:") m.peak_resident_bytes = kib * 1024;
    else if (key == "VmSize:") m.virtual_bytes = kib * 1024;
  }
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) {
    const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
    m.cpu_seconds = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  }
  return m;
}

}  // namespace gk::server
