// The BVH disk cache is read back by a restarted daemon or an audit: a damaged or foreign file
// must be refused (and rebuilt over), never trusted. The input is the file's bytes, for a fixed
// mesh of a few triangles; a tree that is accepted must answer a query without faults.
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"

#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

namespace {

std::shared_ptr<const gk::TriangleMesh> fixed_mesh() {
  std::vector<gk::Vec3> v = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {10, 10, 10}};
  std::vector<gk::TriangleMesh::Face> f = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {1, 4, 2}, {2, 4, 3}, {3, 4, 1}};
  return std::make_shared<const gk::TriangleMesh>(gk::TriangleMesh::create(std::move(v), std::move(f)).value());
}

}  // namespace

// scripts/fuzz.sh seeds the corpus with the fixed mesh's real cache file: GK_FUZZ_SEED_OUT names
// where to write it.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* out = std::getenv("GK_FUZZ_SEED_OUT")) {
    const std::string bytes = gk::MeshBvh::build(fixed_mesh()).value()->serialize();
    std::ofstream(out, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto mesh = fixed_mesh();
  static const auto reference = gk::MeshBvh::build(mesh).value();
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  auto tree = gk::MeshBvh::deserialize(mesh, bytes);
  if (!tree.ok()) return 0;
  // An accepted tree must give the exact answer of a freshly built one.
  const gk::RigidTransform apart = gk::RigidTransform::from_translation(gk::Vec3(30, 1, 2));
  auto d = gk::distance(*tree.value(), gk::RigidTransform{}, *reference, apart);
  auto e = gk::distance(*reference, gk::RigidTransform{}, *reference, apart);
  if (d.ok() != e.ok() || (d.ok() && d.value().distance_mm != e.value().distance_mm)) __builtin_trap();
  return 0;
}
