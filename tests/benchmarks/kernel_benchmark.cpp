// Kernel benchmarks against FCL 0.7 (OBBRSS) in the same process, on the same meshes and poses.
//   build/tests/benchmarks/kernel_benchmark [--benchmark_filter=...]
// Every query is timed on its own; the counters give mean, median and p99 per query in
// microseconds, and a hash of the answers shows both runs computed the same thing.
#include "kernel/measure/contact_regions.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/benchmarks/latency_counters.h"
#include "tests/support/near_contact_poses.h"
#include "tests/support/fcl_peer.h"
#include "tests/support/random_meshes.h"

#include <benchmark/benchmark.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using gk::RigidTransform;
using gk::Vec3;
using Clock = std::chrono::steady_clock;
using gk::testing::FclModel;
using gk::testing::to_fcl;

struct Subject {
  std::shared_ptr<gk::MeshBvh> ours;
  std::shared_ptr<FclModel> fcl;
};

// Meshes are loaded once; `scale` turns metre-unit robot meshes into millimetres.
const Subject& subject(const std::string& relative, double scale = 1.0) {
  static std::map<std::string, Subject> cache;
  auto it = cache.find(relative);
  if (it != cache.end()) return it->second;
  auto mesh = gk::mesh_io::read_mesh_file(gk::testing::shared_data(relative));
  if (!mesh.ok()) {
    std::fprintf(stderr, "%s\n", mesh.error().to_string().c_str());
    std::exit(2);
  }
  gk::TriangleMesh m = std::move(mesh).value();
  if (scale != 1.0) {
    std::vector<Vec3> v = m.vertices();
    for (Vec3& p : v) p *= scale;
    (void)m.set_vertices(std::move(v));
  }
  Subject s;
  s.ours = gk::MeshBvh::build(gk::testing::share(m)).value();
  s.fcl = gk::testing::make_fcl_model(m);
  return cache.emplace(relative, s).first->second;
}

// FCL's env/rob procedure: random translations in +-3000 mm, random rotations (fixed seed).
const std::vector<RigidTransform>& env_rob_poses() {
  static const std::vector<RigidTransform> poses = [] {
    gk::testing::Rng rng(20240601);
    std::vector<RigidTransform> p;
    for (int i = 0; i < 10000; ++i) p.push_back(gk::testing::random_pose(rng, 3000.0));
    return p;
  }();
  return poses;
}

struct Timings {
  std::vector<double> us;
  void add(Clock::time_point t0) { us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count()); }
  void report(benchmark::State& state, double checksum) {
    gk::bench::report_latencies(state, us);
    state.counters["checksum"] = checksum;
  }
};

// --- the four queries, each returning what goes into the checksum ----------------------------

using Query = double (*)(const Subject& a, const RigidTransform& pose_a, const Subject& b, const RigidTransform& pose_b);

double collide_ours(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  gk::CollisionRequest req;
  req.all_contacts = true;
  return static_cast<double>(gk::collide(*a.ours, pa, *b.ours, pb, req).value().contacts.size());
}

double collide_fcl(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  const fcl::CollisionRequestd req(1000000, true);
  fcl::CollisionResultd res;
  fcl::collide(a.fcl.get(), to_fcl(pa), b.fcl.get(), to_fcl(pb), req, res);
  return static_cast<double>(res.numContacts());
}

double distance_ours(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  return gk::distance(*a.ours, pa, *b.ours, pb).value().distance_mm;
}

double distance_fcl(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  const fcl::DistanceRequestd req(true);
  fcl::DistanceResultd res;
  fcl::distance(a.fcl.get(), to_fcl(pa), b.fcl.get(), to_fcl(pb), req, res);
  return std::max(res.min_distance, 0.0);
}

// Times every query on its own. The poses move A (env/rob: env moves, rob stays) or B.
void measure(benchmark::State& state, const Subject& a, const Subject& b, const std::vector<RigidTransform>& poses,
             bool poses_move_a, Query query) {
  Timings t;
  double checksum = 0;
  for (auto _ : state) {
    checksum = 0;
    for (const RigidTransform& pose : poses) {
      const auto t0 = Clock::now();
      checksum += poses_move_a ? query(a, pose, b, RigidTransform{}) : query(a, RigidTransform{}, b, pose);
      t.add(t0);
    }
  }
  t.report(state, checksum);
}

void env_rob(benchmark::State& state, Query query) {
  measure(state, subject("meshes/fcl/env.obj"), subject("meshes/fcl/rob.obj"), env_rob_poses(), true, query);
}

// --- large real meshes near contact ------------------------------------------------------------

struct LargePair {
  const char* a;
  double scale_a;
  const char* b;
  double scale_b;
};

const LargePair kLargePairs[] = {
    {"meshes/occt/TR12J_OCC64K.stl", 1.0, "meshes/robots/kuka_kr10r1420/visual/base_link.stl", 1000.0},
    {"meshes/cgal/fandisk_large.off", 100.0, "meshes/occt/TR12J_OCC64K.stl", 1.0},
};

// Poses of B near A, gap uniform in [-1, 3] mm (tests/support), prepared outside the timing.
const std::vector<RigidTransform>& near_contact_poses(int pair_index) {
  static std::map<int, std::vector<RigidTransform>> cache;
  auto it = cache.find(pair_index);
  if (it != cache.end()) return it->second;
  const LargePair& p = kLargePairs[pair_index];
  const Subject& a = subject(p.a, p.scale_a);
  const Subject& b = subject(p.b, p.scale_b);
  return cache.emplace(pair_index, gk::testing::near_contact_poses(*a.ours, *b.ours, static_cast<unsigned>(1000 + pair_index), 100))
      .first->second;
}

void large(benchmark::State& state, Query query) {
  const int i = static_cast<int>(state.range(0));
  measure(state, subject(kLargePairs[i].a, kLargePairs[i].scale_a), subject(kLargePairs[i].b, kLargePairs[i].scale_b),
          near_contact_poses(i), false, query);
}

// A full clearance answer: the verdict (contacts, or distance with witnesses, containment), every
// triangle pair within a 1 mm safety gap, and those pairs grouped into contact regions.
double clearance_ours(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  const auto v = gk::assess(*a.ours, pa, *b.ours, pb).value();
  const auto near = gk::pairs_within(*a.ours, pa, *b.ours, pb, 1.0, 100000).value();
  const auto regions = gk::group_into_regions(near.pairs, 10.0);
  return v.distance_mm + static_cast<double>(regions.size());
}

// FCL's nearest equivalent: every contact, then the distance with witnesses (FCL has no "pairs
// within a gap" query and no regions).
double clearance_fcl(const Subject& a, const RigidTransform& pa, const Subject& b, const RigidTransform& pb) {
  return collide_fcl(a, pa, b, pb) + distance_fcl(a, pa, b, pb);
}

void BM_EnvRob_Collide_Ours(benchmark::State& s) { env_rob(s, collide_ours); }
void BM_EnvRob_Collide_Fcl(benchmark::State& s) { env_rob(s, collide_fcl); }
void BM_EnvRob_Distance_Ours(benchmark::State& s) { env_rob(s, distance_ours); }
void BM_EnvRob_Distance_Fcl(benchmark::State& s) { env_rob(s, distance_fcl); }
void BM_Large_Collide_Ours(benchmark::State& s) { large(s, collide_ours); }
void BM_Large_Collide_Fcl(benchmark::State& s) { large(s, collide_fcl); }
void BM_Large_Distance_Ours(benchmark::State& s) { large(s, distance_ours); }
void BM_Large_Distance_Fcl(benchmark::State& s) { large(s, distance_fcl); }
void BM_Large_Clearance_Ours(benchmark::State& s) { large(s, clearance_ours); }
void BM_Large_Clearance_Fcl(benchmark::State& s) { large(s, clearance_fcl); }

// --- build and refit ----------------------------------------------------------------------------

void BM_Build_Ours(benchmark::State& state) {
  auto mesh = gk::mesh_io::read_mesh_file(gk::testing::shared_data("meshes/occt/TR12J_OCC64K.stl")).value();
  auto shared = gk::testing::share(mesh);
  for (auto _ : state) benchmark::DoNotOptimize(gk::MeshBvh::build(shared));
  state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
  state.counters["ms_per_100k_triangles"] = benchmark::Counter(
      static_cast<double>(mesh.triangle_count()) / 1e5, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_Build_Fcl(benchmark::State& state) {
  auto mesh = gk::mesh_io::read_mesh_file(gk::testing::shared_data("meshes/occt/TR12J_OCC64K.stl")).value();
  for (auto _ : state) benchmark::DoNotOptimize(gk::testing::make_fcl_model(mesh));
  state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
}

void BM_Refit_Ours(benchmark::State& state) {
  auto mesh = gk::mesh_io::read_mesh_file(gk::testing::shared_data("meshes/occt/TR12J_OCC64K.stl")).value();
  auto bvh = gk::MeshBvh::build(gk::testing::share(mesh)).value();
  std::vector<Vec3> moved = mesh.vertices();
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i].z() += 0.001 * static_cast<double>(i % 7);
  gk::TriangleMesh deformed = mesh;
  (void)deformed.set_vertices(moved);
  auto shared = gk::testing::share(deformed);
  for (auto _ : state) bvh->refit(shared);
  state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
}

}  // namespace

BENCHMARK(BM_EnvRob_Collide_Ours)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_EnvRob_Collide_Fcl)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_EnvRob_Distance_Ours)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_EnvRob_Distance_Fcl)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Collide_Ours)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Collide_Fcl)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Distance_Ours)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Distance_Fcl)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Clearance_Ours)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Large_Clearance_Fcl)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Build_Ours)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_Build_Fcl)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_Refit_Ours)->Unit(benchmark::kMillisecond)->Iterations(20);

BENCHMARK_MAIN();
