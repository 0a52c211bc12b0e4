// Uses the installed kernel, engine and client library: two boxes 5 mm apart through the kernel,
// an id through the engine's input checks, a sha256 through the client library. Exit 0 when each
// answers what it must.
#include "clients/gatekeeper_client/upload.h"
#include "engine/input_checks.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"

#include <cmath>
#include <cstdio>
#include <memory>

namespace {

std::shared_ptr<const gk::TriangleMesh> box(double size) {
  std::vector<gk::Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back((i & 1) * size, ((i >> 1) & 1) * size, ((i >> 2) & 1) * size);
  const std::vector<gk::TriangleMesh::Face> f = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return std::make_shared<const gk::TriangleMesh>(gk::TriangleMesh::create(v, f).value());
}

}  // namespace

int main() {
  auto mesh = box(100.0);
  auto bvh = gk::MeshBvh::build(mesh).value();
  const auto d = gk::distance(*bvh, gk::RigidTransform(), *bvh, gk::RigidTransform::from_translation(gk::Vec3(105.0, 0, 0)));
  const bool distance_ok = d.ok() && std::abs(d.value().distance_mm - 5.0) < 1e-12;
  const bool id_checked = gk::engine::check_id("robot-1", "id").ok() && !gk::engine::check_id("no spaces", "id").ok();
  const bool sha_ok = gk::client::sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
  std::printf("kernel distance %s, engine id check %s, client sha256 %s\n", distance_ok ? "ok" : "WRONG", id_checked ? "ok" : "WRONG",
              sha_ok ? "ok" : "WRONG");
  return distance_ok && id_checked && sha_ok ? 0 : 1;
}
