// ClearanceQuery's expensive extras, measured apart from the mesh answer:
//  - the B-Rep refinement of two CAD parts near contact (the face pairs in the deflection window,
//    each through BRepExtrema), against BRepExtrema on the whole shapes;
//  - the penetration depth vector of interpenetrating large meshes.
//   build/tests/benchmarks/clearance_benchmark [--benchmark_filter=...]
#include "engine/verdicts/pair_verdict.h"
#include "kernel/measure/contact_regions.h"
#include "kernel/measure/exact_interference_volume.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/measure/penetration_depth.h"
#include "mesh_io/mesh_file_reader.h"
#include "occt_adapters/exact_measures.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/benchmarks/latency_counters.h"
#include "tests/support/random_meshes.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <vector>

namespace {

using gk::RigidTransform;
using gk::Vec3;
using Clock = std::chrono::steady_clock;

template <typename T>
T must(gk::Result<T> r) {
  if (!r.ok()) {
    std::fprintf(stderr, "%s\n", r.error().to_string().c_str());
    std::exit(2);
  }
  return std::move(r).value();
}

void report(benchmark::State& state, const std::vector<double>& us) { gk::bench::report_latencies(state, us); }

double since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

// Two CAD parts tessellated as the service does (0.05 mm), and poses of B 0.05-3 mm from A.
struct CadPair {
  gk::occt::Shape a, b;
  std::vector<int> face_of_a, face_of_b;  // each triangle's B-Rep face
  std::shared_ptr<gk::MeshBvh> bvh_a, bvh_b;
  std::vector<RigidTransform> poses;
};

const CadPair& cad_pair() {
  static const CadPair pair = [] {
    CadPair p{};
    p.a = must(gk::occt::read_shape_file(gk::testing::shared_data("step/occt/Pump_TopCover.brep")));
    p.b = must(gk::occt::read_shape_file(gk::testing::shared_data("step/occt/Pump_Nut.brep")));
    gk::occt::MeshedShape mesh_a = must(gk::occt::mesh_shape(p.a, 0.05));
    gk::occt::MeshedShape mesh_b = must(gk::occt::mesh_shape(p.b, 0.05));
    p.face_of_a = mesh_a.face_of_triangle;
    p.face_of_b = mesh_b.face_of_triangle;
    p.bvh_a = must(gk::MeshBvh::build(gk::testing::share(std::move(mesh_a.mesh))));
    p.bvh_b = must(gk::MeshBvh::build(gk::testing::share(std::move(mesh_b.mesh))));
    gk::testing::Rng rng(31);
    std::uniform_real_distribution<double> gap(0.05, 3.0);
    const Vec3 ca = p.bvh_a->root_bounds().center(), cb = p.bvh_b->root_bounds().center();
    const double reach = p.bvh_a->root_bounds().diagonal().norm() + p.bvh_b->root_bounds().diagonal().norm();
    while (p.poses.size() < 30) {
      RigidTransform pose = gk::testing::random_pose(rng, 0.0);
      pose.translation = ca + Vec3::Random().normalized() * reach - pose.rotation * cb;
      const auto d = must(gk::distance(*p.bvh_a, {}, *p.bvh_b, pose));
      pose.translation -= (d.distance_mm - gap(rng)) * (d.point_b - d.point_a).normalized();
      if (must(gk::distance(*p.bvh_a, {}, *p.bvh_b, pose)).distance_mm > 0.02) p.poses.push_back(pose);
    }
    return p;
  }();
  return pair;
}

// The mesh answer of ClearanceQuery: verdict, pairs within a 1 mm gap, regions.
void BM_Cad_MeshAnswer(benchmark::State& state) {
  const CadPair& p = cad_pair();
  std::vector<double> us;
  for (auto _ : state)
    for (const RigidTransform& pose : p.poses) {
      const auto t0 = Clock::now();
      const auto v = must(gk::assess(*p.bvh_a, {}, *p.bvh_b, pose));
      const auto near = must(gk::pairs_within(*p.bvh_a, {}, *p.bvh_b, pose, 1.0, 100000));
      benchmark::DoNotOptimize(gk::group_into_regions(near.pairs, 10.0).size() + v.contacts.size());
      us.push_back(since(t0));
    }
  report(state, us);
}

// The refinement the service adds for CAD parts: the face pairs within the deflection window,
// each measured exactly. The distance sum is compared with BRepExtrema on whole shapes below.
void BM_Cad_BrepRefinement(benchmark::State& state) {
  const CadPair& p = cad_pair();
  std::vector<double> us;
  double sum = 0.0, face_pairs = 0.0;
  for (auto _ : state) {
    sum = face_pairs = 0.0;
    for (const RigidTransform& pose : p.poses) {
      const auto t0 = Clock::now();
      const double d = must(gk::distance(*p.bvh_a, {}, *p.bvh_b, pose)).distance_mm;
      const auto candidates = must(gk::pairs_within(*p.bvh_a, {}, *p.bvh_b, pose, d + 0.1, 20000));
      std::set<std::pair<int, int>> faces;
      for (const auto& c : candidates.pairs)
        faces.insert({p.face_of_a[c.triangle_a], p.face_of_b[c.triangle_b]});
      sum += must(gk::occt::closest_face_pair(p.a, {}, p.b, pose, {faces.begin(), faces.end()})).distance.distance_mm;
      face_pairs += static_cast<double>(faces.size());
      us.push_back(since(t0));
    }
  }
  report(state, us);
  state.counters["distance_sum_mm"] = sum;
  state.counters["face_pairs_per_query"] = face_pairs / static_cast<double>(p.poses.size());
}

// The verdict of two CAD parts closer than their tessellation can tell (signed gaps uniform in
// [-0.05, 0.05] mm, set on the meshes): the engine decides on the exact faces (engine/pair_verdict).
// Range 1: B is a mesh part (the nut's tessellation, no B-Rep): the CAD part's exact faces against
// its triangles, crossing told from touching by the Boolean common of the solid and the triangles.
void BM_Cad_ExactFaceDecision(benchmark::State& state) {
  const CadPair& p = cad_pair();
  gk::engine::PartGeometry a, b;
  a.bvh = p.bvh_a;
  a.mesh = gk::testing::share(p.bvh_a->mesh());
  a.shape = p.a;
  a.face_of_triangle = p.face_of_a;
  a.deflection_mm = 0.05;
  b.bvh = p.bvh_b;
  b.mesh = gk::testing::share(p.bvh_b->mesh());
  b.shape = p.b;
  b.face_of_triangle = p.face_of_b;
  b.deflection_mm = 0.05;
  if (state.range(0) == 1) {
    b.shape = {};
    b.face_of_triangle.clear();
    b.deflection_mm = 0.0;
  }
  gk::testing::Rng rng(32);
  std::uniform_real_distribution<double> gap(-0.05, 0.05);
  std::vector<RigidTransform> poses;
  for (RigidTransform pose : p.poses) {
    const auto d = must(gk::distance(*p.bvh_a, {}, *p.bvh_b, pose));
    pose.translation -= (d.distance_mm - gap(rng)) * (d.point_b - d.point_a).normalized();
    poses.push_back(pose);
  }
  std::vector<double> us;
  int clear = 0, touching = 0, collision = 0, inconclusive = 0, on_brep = 0;
  for (auto _ : state)
    for (const RigidTransform& pose : poses) {
      const auto t0 = Clock::now();
      const gk::engine::PairVerdict v = must(gk::engine::decide_pair({&a, {}}, {&b, pose}));
      us.push_back(since(t0));
      on_brep += v.decided_on_brep ? 1 : 0;
      switch (v.result.verdict) {
        case gk::Verdict::kClear: ++clear; break;
        case gk::Verdict::kTouching: ++touching; break;
        case gk::Verdict::kCollision: ++collision; break;
        case gk::Verdict::kInconclusive: ++inconclusive; break;
      }
    }
  report(state, us);
  state.counters["clear"] = clear;
  state.counters["touching"] = touching;
  state.counters["collision"] = collision;
  state.counters["inconclusive"] = inconclusive;
  state.counters["on_brep"] = on_brep;
}

// The slow peer: BRepExtrema_DistShapeShape on the whole placed shapes.
void BM_Cad_BrepExtremaWhole(benchmark::State& state) {
  const CadPair& p = cad_pair();
  std::vector<double> us;
  double sum = 0.0;
  for (auto _ : state) {
    sum = 0.0;
    for (const RigidTransform& pose : p.poses) {
      const auto t0 = Clock::now();
      sum += must(gk::occt::exact_distance(p.a, must(gk::occt::place(p.b, pose)))).distance_mm;
      us.push_back(since(t0));
    }
  }
  report(state, us);
  state.counters["distance_sum_mm"] = sum;
}

// Two large meshes (TR12J 67k, fandisk 32k scaled to about 500 mm) and poses of B overlapping A
// by a depth drawn from [lo, hi] mm.
struct LargePair {
  std::shared_ptr<gk::MeshBvh> a, b;
};

// A shared mesh scaled about its box's centre to a box diagonal of `diagonal_mm`.
std::shared_ptr<gk::MeshBvh> scaled_mesh(const std::string& relative, double diagonal_mm) {
  gk::TriangleMesh m = must(gk::mesh_io::read_mesh_file(gk::testing::shared_data(relative)));
  const double factor = diagonal_mm / m.bounds().diagonal().norm();
  std::vector<Vec3> v = m.vertices();
  for (Vec3& q : v) q *= factor;
  (void)m.set_vertices(std::move(v));
  return must(gk::MeshBvh::build(gk::testing::share(std::move(m))));
}

// Two large closed meshes for volumes: the refined elephant scan (89k) and fandisk (32k), both
// scaled to about 500 mm.
const LargePair& closed_pair() {
  static const LargePair pair{scaled_mesh("meshes/cgal/refined_elephant.off", 500.0),
                              scaled_mesh("meshes/cgal/fandisk_large.off", 500.0)};
  return pair;
}

const LargePair& large_pair() {
  static const LargePair pair = [] {
    LargePair p;
    p.a = must(gk::MeshBvh::build(gk::testing::share(
        must(gk::mesh_io::read_mesh_file(gk::testing::shared_data("meshes/occt/TR12J_OCC64K.stl"))))));
    // fandisk is about 5 mm across as stored: scaled by 100, as in kernel_benchmark, to be a part.
    gk::TriangleMesh m = must(gk::mesh_io::read_mesh_file(gk::testing::shared_data("meshes/cgal/fandisk_large.off")));
    std::vector<Vec3> v = m.vertices();
    for (Vec3& q : v) q *= 100.0;
    (void)m.set_vertices(std::move(v));
    p.b = must(gk::MeshBvh::build(gk::testing::share(std::move(m))));
    return p;
  }();
  return pair;
}

std::vector<RigidTransform> overlapping_poses(const LargePair& p, std::uint64_t seed, double lo, double hi, std::size_t count) {
  gk::testing::Rng rng(seed);
  std::uniform_real_distribution<double> overlap(lo, hi);
  std::vector<RigidTransform> poses;
  const Vec3 ca = p.a->root_bounds().center(), cb = p.b->root_bounds().center();
  const double reach = p.a->root_bounds().diagonal().norm() + p.b->root_bounds().diagonal().norm();
  while (poses.size() < count) {
    RigidTransform pose = gk::testing::random_pose(rng, 0.0);
    pose.translation = ca + Vec3::Random().normalized() * reach - pose.rotation * cb;
    const auto d = must(gk::distance(*p.a, {}, *p.b, pose));
    pose.translation -= (d.distance_mm + overlap(rng)) * (d.point_b - d.point_a).normalized();
    poses.push_back(pose);
  }
  return poses;
}

// The depth vector of the large pair overlapping by 0.5-3 mm.
void BM_Large_DepthVector(benchmark::State& state) {
  const auto& a = large_pair().a;
  const auto& b = large_pair().b;
  const std::vector<RigidTransform> poses = overlapping_poses(large_pair(), 99, 0.5, 3.0, 8);
  std::vector<double> us;
  double sum = 0.0;
  for (auto _ : state) {
    sum = 0.0;
    for (const RigidTransform& pose : poses) {
      const auto t0 = Clock::now();
      sum += must(gk::penetration_vector(*a, {}, *b, pose, 162, 1e-4)).depth_mm;
      us.push_back(since(t0));
    }
  }
  report(state, us);
  state.counters["depth_sum_mm"] = sum;
}

// Shared volume: the ray cast on the tessellations at several grid sizes against OCCT's Boolean
// common of the B-Rep solids (the reference), on Pump_Nut against a copy shifted 2 mm and turned
// 10 degrees. Counters: the relative error and the time of each.
void BM_Volume_RayCastVsBoolean(benchmark::State& state) {
  static const gk::occt::Shape nut = must(gk::occt::read_shape_file(gk::testing::shared_data("step/occt/Pump_Nut.brep")));
  static const auto mesh = must(gk::MeshBvh::build(gk::testing::share(must(gk::occt::mesh_shape(nut, 0.01)).mesh)));
  const RigidTransform pose = RigidTransform::from_axis_angle(Vec3(0.3, 0.2, 1.0).normalized(), 10.0 * 3.14159265358979323846 / 180.0,
                                                              Vec3(2.0, 0.5, 0.0));
  const int cells = static_cast<int>(state.range(0));
  double reference = 0.0, boolean_ms = 0.0, volume = 0.0, ray_ms = 0.0, bound = 0.0, cell = 0.0, exact = 0.0;
  for (auto _ : state) {
    auto t0 = Clock::now();
    reference = must(gk::occt::interference_volume(nut, must(gk::occt::place(nut, pose))));
    boolean_ms = since(t0) / 1000.0;
    t0 = Clock::now();
    const gk::VolumeEstimate v = must(gk::interference_volume(*mesh, {}, *mesh, pose, cells));
    ray_ms = since(t0) / 1000.0;
    volume = v.volume_mm3;
    bound = v.error_bound_mm3;
    cell = v.cell_mm;
    exact = v.method == gk::VolumeMethod::kExactCorefinement ? 1.0 : 0.0;
  }
  state.counters["boolean_mm3"] = reference;
  state.counters["boolean_ms"] = boolean_ms;
  state.counters["mesh_mm3"] = volume;
  state.counters["mesh_ms"] = ray_ms;
  state.counters["mesh_error_pct"] = 100.0 * (volume - reference) / reference;
  state.counters["mesh_bound_pct"] = 100.0 * bound / reference;
  state.counters["mesh_cell_mm"] = cell;
  state.counters["exact_fallback"] = exact;
}

// The shared volume of the closed pair as ClearanceQuery computes it (the ray cast, replaced by the
// exact corefinement where its bound exceeds 1 %), overlapping by 0.5-3 mm (range 0) or by
// 0.001-0.01 mm (range 1). Counters: how often the exact method ran, and its own time.
void BM_Large_Volume(benchmark::State& state) {
  const LargePair& p = closed_pair();
  const bool thin = state.range(0) == 1;
  const std::vector<RigidTransform> poses = overlapping_poses(p, thin ? 101 : 100, thin ? 0.001 : 0.5, thin ? 0.01 : 3.0, 8);
  std::vector<double> us, exact_us;
  int exact = 0;
  double worst_relative_bound = 0.0;
  for (auto _ : state)
    for (const RigidTransform& pose : poses) {
      auto t0 = Clock::now();
      const gk::VolumeEstimate v = must(gk::interference_volume(*p.a, {}, *p.b, pose, 256));
      us.push_back(since(t0));
      if (v.method == gk::VolumeMethod::kExactCorefinement) ++exact;
      if (v.volume_mm3 > 0.0) worst_relative_bound = std::max(worst_relative_bound, v.error_bound_mm3 / v.volume_mm3);
      t0 = Clock::now();
      benchmark::DoNotOptimize(must(gk::exact_interference_volume(p.a->mesh(), {}, p.b->mesh(), pose)).volume_mm3);
      exact_us.push_back(since(t0));
    }
  report(state, us);
  std::sort(exact_us.begin(), exact_us.end());
  state.counters["exact_runs"] = exact;
  state.counters["exact_alone_p50_ms"] = exact_us[exact_us.size() / 2] / 1000.0;
  state.counters["exact_alone_max_ms"] = exact_us.back() / 1000.0;
  state.counters["worst_bound_pct"] = 100.0 * worst_relative_bound;
}

}  // namespace

BENCHMARK(BM_Large_Volume)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Volume_RayCastVsBoolean)->Arg(64)->Arg(128)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Cad_MeshAnswer)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Cad_BrepRefinement)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Cad_ExactFaceDecision)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Cad_BrepExtremaWhole)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Large_DepthVector)->Unit(benchmark::kMillisecond)->Iterations(1);

BENCHMARK_MAIN();
