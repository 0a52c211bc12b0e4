// OCCT's CAD readers crash on some malformed files (a 342-byte STEP file dereferences a null
// pointer inside StepGeom_CartesianPoint, found by tests/fuzz/shape_file_fuzzer), and no exception
// handler catches a segmentation fault. So every CAD file is first read and tessellated in a child
// process (the daemon itself, run with --check-cad): a crash, a hang or a memory blow-up there
// refuses the file and leaves the daemon serving. Only a file the child read cleanly is then read
// in the daemon: the same deterministic code on the same bytes.
#pragma once

#include "kernel/core/status.h"

#include <chrono>
#include <cstdint>
#include <string>

namespace gk::engine {

struct CadSandbox {
  std::string executable;                 // empty: no child, the file is read in this process
  std::chrono::seconds timeout{120};      // wall time of one check
  std::uint64_t memory_bytes = 8ull << 30;  // address space of the child
};

// Process-wide: main sets it once before serving (the readers are called from static functions).
void set_cad_sandbox(const CadSandbox& sandbox);
const CadSandbox& cad_sandbox();

// Reads and tessellates the file in a child; ok when the child did so cleanly. A clean refusal
// (the reader's own error) comes back with the reader's message; a crash, a timeout or memory
// exhaustion as INVALID_ARGUMENT on "data" saying so.
Result<bool> check_cad_in_child(const std::string& path, const std::string& format, double deflection_mm);

// The child's side: `gatekeeperd --check-cad PATH FORMAT DEFLECTION_MM MEMORY_BYTES`. Returns the
// process exit status (0: read cleanly; 3: refused, the reason on stderr).
int run_cad_check(int argc, char** argv);

}  // namespace gk::engine
