// CAD uploads (STEP, BREP, IGES) as the daemon takes them: read by OCCT, then tessellated. Any
// bytes give a shape or an error, never a crash. The first byte picks the format.
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/fuzz/fuzz_input.h"

namespace {
const char* const kFormats[] = {"step", "brep", "iges"};
constexpr double kDeflectionMm = 0.5;  // coarse: the reader and the mesher's robustness are fuzzed, not accuracy
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto in = gk::fuzz::select(data, size, sizeof kFormats / sizeof kFormats[0]);
  auto shape = gk::occt::read_shape_bytes(in.payload, kFormats[in.variant]);
  if (shape.ok()) (void)gk::occt::mesh_shape(shape.value(), kDeflectionMm);
  return 0;
}
