// This process's memory and CPU time as Linux reports them in /proc/self (for /metrics).
#pragma once

#include <cstdint>

namespace gk::server {

struct ProcessMemory {
  std::uint64_t resident_bytes = 0;       // VmRSS
  std::uint64_t peak_resident_bytes = 0;  // VmHWM
  std::uint64_t virtual_bytes = 0;        // VmSize
  double cpu_seconds = 0.0;               // user + system
  bool read = false;                      // false: /proc/self could not be read (the fields are 0)
};

ProcessMemory read_process_memory();

}  // namespace gk::server
