// The kernel against FCL 0.7 (OBBRSS) on a varied set of pairs from ../shared/data, in one run
// and one process, on identical arrays and poses: every pair at random poses and near contact
// (gap uniform in [-1, 3] mm), collide with all contacts and distance with witnesses, and the
// distance on the non-colliding poses on a line of its own. Prints the whole table (mean and
// median per query, ours / FCL / ratio FCL÷ours), each mesh's build rate and memory per
// triangle, and a hash of our answers that must not change across optimisations.
//   build/tests/benchmarks/kernel_fcl_table [poses per kind, default 200] [triangles per leaf, default the kernel's]
//                                            [only this pair, 1-7, for profiling]
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/near_contact_poses.h"
#include "tests/support/fcl_peer.h"
#include "tests/support/random_meshes.h"

#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>
#include <fcl/narrowphase/detail/traversal/distance/mesh_distance_traversal_node.h>
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace {

using gk::RigidTransform;
using gk::Vec3;
using Clock = std::chrono::steady_clock;
using gk::testing::FclModel;
using gk::testing::to_fcl;

struct Subject {
  std::string name;
  std::shared_ptr<const gk::TriangleMesh> mesh;
  std::shared_ptr<gk::MeshBvh> ours;
  std::shared_ptr<FclModel> fcl;
  double build_ms = 0.0, fcl_build_ms = 0.0, slabs_ms = 0.0;
  double bytes_per_triangle = 0.0;  // heap the mesh with its tree keeps (glibc's count of bytes in use)
  double slab_bytes_per_triangle = 0.0;  // what the node slabs add once a distance query fits them
};

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// A mesh from the shared data, scaled so that its box diagonal is diagonal_mm and centred on the
// origin (the same arrays go to both libraries).
Subject load(const std::string& relative, double diagonal_mm, int leaf_size) {
  const std::size_t heap0 = mallinfo2().uordblks;  // the mesh and its tree: what stays allocated after both
  auto read = gk::mesh_io::read_mesh_file(gk::testing::shared_data(relative));
  if (!read.ok()) {
    std::fprintf(stderr, "%s: %s\n", relative.c_str(), read.error().to_string().c_str());
    std::exit(2);
  }
  gk::TriangleMesh m = std::move(read).value();
  const gk::Aabb box = m.bounds();
  const double scale = diagonal_mm / box.diagonal().norm();
  std::vector<Vec3> v = m.vertices();
  for (Vec3& p : v) p = (p - box.center()) * scale;
  (void)m.set_vertices(std::move(v));
  Subject s;
  s.name = relative.substr(relative.rfind('/') + 1);
  s.mesh = gk::testing::share(std::move(m));
  const auto t0 = Clock::now();
  gk::BvhBuildOptions options;
  options.leaf_size = leaf_size;
  s.ours = gk::MeshBvh::build(s.mesh, options).value();
  s.build_ms = ms_since(t0);
  const std::size_t heap1 = mallinfo2().uordblks;
  s.bytes_per_triangle = static_cast<double>(heap1 - heap0) / static_cast<double>(s.mesh->triangle_count());
  const auto ts = Clock::now();
  (void)s.ours->node_slabs();
  s.slabs_ms = ms_since(ts);
  s.slab_bytes_per_triangle = static_cast<double>(mallinfo2().uordblks - heap1) / static_cast<double>(s.mesh->triangle_count());
  const auto t1 = Clock::now();
  s.fcl = gk::testing::make_fcl_model(*s.mesh);
  s.fcl_build_ms = ms_since(t1);
  return s;
}

struct Answer {
  double value = 0.0;  // contacts, or distance
  bool collides = false;
  long long node_pairs = 0, triangle_pairs = 0, triangle_node_tests = 0;  // our work (not counted for FCL)
};

Answer collide_ours(const Subject& a, const Subject& b, const RigidTransform& pb) {
  gk::CollisionRequest req;
  req.all_contacts = true;
  const auto r = gk::collide(*a.ours, RigidTransform{}, *b.ours, pb, req).value();
  return {static_cast<double>(r.contacts.size()), !r.contacts.empty()};
}
Answer collide_fcl(const Subject& a, const Subject& b, const RigidTransform& pb) {
  const fcl::CollisionRequestd req(100000000, false);
  fcl::CollisionResultd res;
  fcl::collide(a.fcl.get(), fcl::Transform3d::Identity(), b.fcl.get(), to_fcl(pb), req, res);
  return {static_cast<double>(res.numContacts()), res.numContacts() > 0};
}
Answer distance_ours(const Subject& a, const Subject& b, const RigidTransform& pb) {
  const auto r = gk::distance(*a.ours, RigidTransform{}, *b.ours, pb).value();
  return {r.distance_mm, r.distance_mm <= 0.0, r.stats.node_pairs_tested, r.stats.triangle_pairs_tested, r.stats.triangle_node_tests};
}
Answer distance_fcl(const Subject& a, const Subject& b, const RigidTransform& pb) {
  const fcl::DistanceRequestd req(true);
  fcl::DistanceResultd res;
  fcl::distance(a.fcl.get(), fcl::Transform3d::Identity(), b.fcl.get(), to_fcl(pb), req, res);
  return {std::max(res.min_distance, 0.0), res.min_distance <= 0.0};
}

// FCL's work on the same distance query (BV pairs and triangle pairs tested), in a pass of its own
// so that counting does not weigh on the timed one.
std::pair<long long, long long> distance_fcl_work(const Subject& a, const Subject& b, const RigidTransform& pb) {
  const fcl::DistanceRequestd req(true);
  fcl::DistanceResultd res;
  fcl::detail::MeshDistanceTraversalNodeOBBRSS<double> node;
  fcl::detail::initialize(node, *a.fcl, fcl::Transform3d::Identity(), *b.fcl, to_fcl(pb), req, res);
  node.enable_statistics = true;
  fcl::detail::distance(&node);
  return {node.num_bv_tests, node.num_leaf_tests};
}

// Microseconds one call of f takes. A call that takes less than 2 us (most random poses miss at
// the roots) is timed again as 64 calls in a row, divided by 64: a single reading of the clock
// there is mostly the clock. The same rule for both libraries.
template <typename F>
double timed_us(F&& f) {
  auto t0 = Clock::now();
  f();
  const double once = ms_since(t0) * 1e3;
  if (once >= 2.0) return once;
  constexpr int kRepeats = 64;
  t0 = Clock::now();
  for (int i = 0; i < kRepeats; ++i) f();
  return ms_since(t0) * 1e3 / kRepeats;
}

struct Stats {
  double mean = 0.0, median = 0.0;
};
Stats stats_of(std::vector<double> us) {
  if (us.empty()) return {};
  std::sort(us.begin(), us.end());
  return {std::accumulate(us.begin(), us.end(), 0.0) / static_cast<double>(us.size()), us[us.size() / 2]};
}

// FNV-1a over the answers' bytes: a change of any answer changes it.
struct AnswerHash {
  std::uint64_t h = 14695981039346656037ull;
  void add(double v) {
    unsigned char bytes[8];
    std::memcpy(bytes, &v, 8);
    for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  }
};

struct PairSpec {
  const char* a;
  double diagonal_a;
  const char* b;
  double diagonal_b;
  const char* kind;
};

}  // namespace

int main(int argc, char** argv) {
  const int per_kind = argc > 1 ? std::max(10, std::atoi(argv[1])) : 200;
  const int leaf_size = argc > 2 ? std::max(1, std::atoi(argv[2])) : gk::BvhBuildOptions{}.leaf_size;
  const int only_pair = argc > 3 ? std::atoi(argv[3]) : 0;
  // Scans, CAD tessellations, robot links, a thin part and very unequal sizes; sizes in mm.
  const PairSpec specs[] = {
      {"meshes/fcl/env.obj", 6000.0, "meshes/fcl/rob.obj", 600.0, "classic (FCL's env/rob)"},
      {"meshes/cgal/camel.off", 1000.0, "meshes/cgal/bull.off", 1000.0, "scan vs scan"},
      {"meshes/cgal/man.off", 1800.0, "meshes/cgal/knot1.off", 600.0, "scan vs scan"},
      {"meshes/cgal/turbine.off", 800.0, "meshes/cgal/fandisk_large.off", 300.0, "CAD tessellations"},
      {"meshes/occt/motor.stl", 500.0, "meshes/occt/video_part.stl", 300.0, "CAD tessellations"},
      {"meshes/robots/kuka_kr10r1420/visual/link_2.stl", 700.0, "meshes/robots/kuka_kr10r1420/visual/link_3.stl", 400.0,
       "robot links"},
      {"meshes/occt/TR12J_OCC64K.stl", 1500.0, "meshes/robots/ur5/collision/wrist3.stl", 60.0, "very unequal sizes"},
  };
  std::map<std::string, Subject> subjects;
  auto subject = [&](const char* path, double diagonal) -> const Subject& {
    const std::string key = std::string(path) + "@" + std::to_string(diagonal);
    auto it = subjects.find(key);
    if (it == subjects.end()) it = subjects.emplace(key, load(path, diagonal, leaf_size)).first;
    return it->second;
  };
  std::printf("# kernel vs FCL 0.7 OBBRSS, %d poses per kind, %d triangles per leaf; times in microseconds per query\n",
              per_kind, leaf_size);
  std::printf("%-44s %-8s %-10s %9s %9s %9s %9s %7s %7s %6s\n", "pair", "poses", "query", "ours_mean", "ours_med", "fcl_mean",
              "fcl_med", "x_mean", "x_med", "agree");
  AnswerHash hash;
  double worst_ratio = 1e300;
  std::string worst_line;
  for (std::size_t p = 0; p < std::size(specs); ++p) {
    if (only_pair > 0 && static_cast<int>(p) + 1 != only_pair) continue;
    const PairSpec& spec = specs[p];
    const Subject& a = subject(spec.a, spec.diagonal_a);
    const Subject& b = subject(spec.b, spec.diagonal_b);
    // Random poses: B anywhere within A's box grown by B's size (many hit, many miss); near
    // contact: tests/support's gap in [-1, 3] mm.
    std::vector<RigidTransform> random_poses;
    gk::testing::Rng rng(4242 + p);
    const double reach = 0.5 * (spec.diagonal_a + spec.diagonal_b) / std::sqrt(3.0);
    for (int i = 0; i < per_kind; ++i) random_poses.push_back(gk::testing::random_pose(rng, reach));
    const std::vector<RigidTransform> near = gk::testing::near_contact_poses(*a.ours, *b.ours, 900u + static_cast<unsigned>(p), per_kind);
    const std::string label = a.name + " / " + b.name;
    for (const auto& [pose_kind, poses] : {std::pair<const char*, const std::vector<RigidTransform>*>{"random", &random_poses},
                                          {"near", &near}}) {
      std::vector<double> c_ours, c_fcl, d_ours, d_fcl, dfree_ours, dfree_fcl;
      int agree_c = 0, agree_d = 0;
      double d_node_pairs = 0.0, d_triangle_pairs = 0.0, d_triangle_nodes = 0.0, fcl_bv_pairs = 0.0, fcl_triangle_pairs = 0.0;
      for (const RigidTransform& pose : *poses) {
        Answer co, cf, dq, df;
        c_ours.push_back(timed_us([&] { co = collide_ours(a, b, pose); }));
        c_fcl.push_back(timed_us([&] { cf = collide_fcl(a, b, pose); }));
        const double du = timed_us([&] { dq = distance_ours(a, b, pose); });
        d_ours.push_back(du);
        d_node_pairs += static_cast<double>(dq.node_pairs);
        d_triangle_pairs += static_cast<double>(dq.triangle_pairs);
        d_triangle_nodes += static_cast<double>(dq.triangle_node_tests);
        const double dfu = timed_us([&] { df = distance_fcl(a, b, pose); });
        d_fcl.push_back(dfu);
        const auto [bv_pairs, leaf_pairs] = distance_fcl_work(a, b, pose);
        fcl_bv_pairs += static_cast<double>(bv_pairs);
        fcl_triangle_pairs += static_cast<double>(leaf_pairs);
        if (!co.collides) {
          dfree_ours.push_back(du);
          dfree_fcl.push_back(dfu);
        }
        // Contacts are counted on exact predicates; distances are hashed to the nanometre (a tree
        // of another shape may reach the same minimum through another triangle pair, one
        // rounding apart).
        hash.add(co.value);
        hash.add(static_cast<double>(std::llround(dq.value * 1e6)));
        agree_c += co.collides == cf.collides ? 1 : 0;
        // FCL reports 0 or a negative distance in contact; apart, both are the same distance.
        agree_d += (co.collides ? df.value <= 1e-6 : std::abs(dq.value - df.value) <= 1e-6 * std::max(1.0, dq.value)) ? 1 : 0;
      }
      const auto line = [&](const char* query, const std::vector<double>& ours, const std::vector<double>& theirs, int agree,
                            std::size_t n) {
        if (ours.empty()) return;
        const Stats o = stats_of(ours), f = stats_of(theirs);
        const double x_mean = f.mean / o.mean, x_med = f.median / o.median;
        std::printf("%-44s %-8s %-10s %9.2f %9.2f %9.2f %9.2f %7.2f %7.2f %3d/%zu\n", label.c_str(), pose_kind, query, o.mean,
                    o.median, f.mean, f.median, x_mean, x_med, agree, n);
        const double worse = std::min(x_mean, x_med);
        if (worse < worst_ratio) {
          worst_ratio = worse;
          worst_line = label + " " + pose_kind + " " + query;
        }
      };
      line("collide", c_ours, c_fcl, agree_c, poses->size());
      line("distance", d_ours, d_fcl, agree_d, poses->size());
      line("dist_free", dfree_ours, dfree_fcl, static_cast<int>(dfree_ours.size()), dfree_ours.size());
      const double n = static_cast<double>(poses->size());
      std::printf("%-44s %-8s %-10s node pairs %.0f, triangle pairs %.0f (triangle-to-leaf bounds %.0f) per distance query (ours); FCL %.0f "
                  "and %.0f\n",
                  label.c_str(), pose_kind, "work", d_node_pairs / n, d_triangle_pairs / n, d_triangle_nodes / n, fcl_bv_pairs / n,
                  fcl_triangle_pairs / n);
    }
  }
  // Slabs are fitted on a mesh's first distance query (not by collision tests): their time and
  // bytes on columns of their own, and the rate and bytes with them.
  std::printf("\n%-36s %10s %10s %12s %12s %10s %9s %10s %14s %12s\n", "mesh", "triangles", "build_ms", "M_tri/s", "fcl_build_ms",
              "B/triangle", "slabs_ms", "slabs_B/tri", "M_tri/s_slabs", "B/tri_slabs");
  for (const auto& [key, s] : subjects) {
    const double n = static_cast<double>(s.mesh->triangle_count());
    std::printf("%-36s %10zu %10.1f %12.2f %12.1f %10.0f %9.1f %10.0f %14.2f %12.0f\n", s.name.c_str(), s.mesh->triangle_count(),
                s.build_ms, n / (s.build_ms * 1e3), s.fcl_build_ms, s.bytes_per_triangle, s.slabs_ms, s.slab_bytes_per_triangle,
                n / ((s.build_ms + s.slabs_ms) * 1e3), s.bytes_per_triangle + s.slab_bytes_per_triangle);
  }
  std::printf("\nworst ratio (min of mean, median): %.2f on %s\nanswer hash %016llx\n", worst_ratio, worst_line.c_str(),
              static_cast<unsigned long long>(hash.h));
  return 0;
}
