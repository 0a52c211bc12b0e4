// Mesh uploads (STL binary and ASCII, OBJ, OFF, PLY, glTF, GLB): any bytes give a mesh or an error,
// never a crash, a hang or a read outside the bytes. The first byte picks the format.
#include "mesh_io/mesh_file_reader.h"
#include "tests/fuzz/fuzz_input.h"

namespace {
const char* const kFormats[] = {"stl", "obj", "off", "ply", "gltf", "glb"};
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto in = gk::fuzz::select(data, size, sizeof kFormats / sizeof kFormats[0]);
  auto mesh = gk::mesh_io::read_mesh_bytes(in.payload, kFormats[in.variant]);
  if (mesh.ok() && mesh.value().triangle_count() == 0) __builtin_trap();  // a mesh is never empty
  return 0;
}
