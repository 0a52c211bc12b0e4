// gatekeeper-mesh-check: loads two mesh files, places the second one, and prints the kernel's
// verdict, minimum distance with witnesses, contacts, and how long each query took.
//
//   gatekeeper-mesh-check A.stl B.obj [--move X Y Z] [--rotate-deg AX AY AZ ANGLE] [--gap MM]
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::shared_ptr<gk::MeshBvh> load(const char* path) {
  const auto t0 = Clock::now();
  auto mesh = gk::mesh_io::read_mesh_file(path);
  if (!mesh.ok()) {
    std::fprintf(stderr, "error: %s\n", mesh.error().to_string().c_str());
    std::exit(2);
  }
  const double read_ms = ms_since(t0);
  auto shared = std::make_shared<const gk::TriangleMesh>(std::move(mesh).value());
  const auto t1 = Clock::now();
  auto bvh = gk::MeshBvh::build(shared);
  if (!bvh.ok()) {
    std::fprintf(stderr, "error: %s\n", bvh.error().to_string().c_str());
    std::exit(2);
  }
  const gk::Aabb box = shared->bounds();
  std::printf("%s: %zu triangles, %zu vertices, closed=%s, zero-area=%zu, read %.1f ms, BVH %.2f ms (%d nodes)\n",
              path, shared->triangle_count(), shared->vertices().size(), shared->is_closed_oriented() ? "yes" : "no",
              shared->report().zero_area_triangles.size(), read_ms, ms_since(t1), bvh.value()->node_count());
  std::printf("  bounds [%.3f %.3f %.3f] .. [%.3f %.3f %.3f] mm\n", box.min.x(), box.min.y(), box.min.z(),
              box.max.x(), box.max.y(), box.max.z());
  return bvh.value();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s A B [--move X Y Z] [--rotate-deg AX AY AZ ANGLE] [--gap MM]\n", argv[0]);
    return 2;
  }
  gk::RigidTransform pose_b;
  double gap_mm = 1.0;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--move" && i + 3 < argc) {
      pose_b.translation = gk::Vec3(std::atof(argv[i + 1]), std::atof(argv[i + 2]), std::atof(argv[i + 3]));
      i += 3;
    } else if (arg == "--rotate-deg" && i + 4 < argc) {
      const gk::Vec3 axis(std::atof(argv[i + 1]), std::atof(argv[i + 2]), std::atof(argv[i + 3]));
      pose_b.rotation = gk::RigidTransform::from_axis_angle(axis, std::atof(argv[i + 4]) * 3.14159265358979323846 / 180.0).rotation;
      i += 4;
    } else if (arg == "--gap" && i + 1 < argc) {
      gap_mm = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "unknown or incomplete option: %s\n", arg.c_str());
      return 2;
    }
  }
  const auto a = load(argv[1]);
  const auto b = load(argv[2]);
  const gk::RigidTransform pose_a;

  auto t0 = Clock::now();
  auto verdict = gk::assess(*a, pose_a, *b, pose_b);
  const double verdict_ms = ms_since(t0);
  if (!verdict.ok()) {
    std::fprintf(stderr, "error: %s\n", verdict.error().to_string().c_str());
    return 2;
  }
  const gk::VerdictResult& v = verdict.value();
  std::printf("verdict: %s (%s) in %.3f ms; %lld node pairs, %lld triangle pairs tested\n", gk::to_string(v.verdict),
              v.reason.c_str(), verdict_ms, v.stats.node_pairs_tested, v.stats.triangle_pairs_tested);
  std::printf("  distance %.6f mm between [%.4f %.4f %.4f] and [%.4f %.4f %.4f]\n", v.distance_mm, v.point_a.x(),
              v.point_a.y(), v.point_a.z(), v.point_b.x(), v.point_b.y(), v.point_b.z());
  for (std::size_t i = 0; i < v.contacts.size() && i < 5; ++i) {
    const gk::Contact& c = v.contacts[i];
    std::printf("  contact A#%u x B#%u at [%.4f %.4f %.4f]%s\n", c.triangle_a, c.triangle_b, c.point.x(), c.point.y(),
                c.point.z(), c.coplanar ? " (coplanar)" : "");
  }
  if (v.contacts.size() > 5) std::printf("  ... %zu contacts in all\n", v.contacts.size());

  t0 = Clock::now();
  auto near = gk::pairs_within(*a, pose_a, *b, pose_b, gap_mm);
  if (near.ok())
    std::printf("triangle pairs closer than %.3f mm: %zu (%.3f ms)\n", gap_mm, near.value().pairs.size(), ms_since(t0));
  return v.verdict == gk::Verdict::kClear ? 0 : 1;
}
