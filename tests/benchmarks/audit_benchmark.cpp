// The factory audit end to end on a generated scene: mesh loading and BVH builds (once per unique
// mesh), then the tiled, parallel audit, with the time of every stage and the peak RSS.
//   build/tests/benchmarks/audit_benchmark [objects] [triangles] [threads] [tile_mm] [distinct]
//   e.g. audit_benchmark 10000 100000000 2 50000      (catalogue meshes shared, as in a real twin)
//        audit_benchmark 2000 10000000 2 50000 1      (every machine its own mesh and BVH)
//        audit_benchmark 2000 10000000 2 50000 1 DIR  (BVHs from the disk cache in DIR; run twice)
#include "kernel/broadphase/broad_phase.h"
#include "engine/audits/scene_audit.h"
#include "tests/support/factory_scene.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <vector>

namespace {

double peak_rss_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB on Linux
}

}  // namespace

int main(int argc, char** argv) {
  gk::testing::FactorySceneOptions scene_options;
  scene_options.objects = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 10000;
  scene_options.triangles = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 100000000ULL;
  const int threads = argc > 3 ? std::atoi(argv[3]) : 2;
  const double tile = argc > 4 ? std::atof(argv[4]) : 50000.0;
  scene_options.distinct_meshes = argc > 5 && std::atoi(argv[5]) != 0;
  if (argc > 6) scene_options.bvh_cache_dir = argv[6];
  const auto t0 = std::chrono::steady_clock::now();
  const gk::testing::FactoryScene scene = gk::testing::generate_factory_scene(scene_options);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  gk::engine::AuditOptions options;
  options.clearance_mm = 10.0;
  options.threads = threads;
  options.tile_mm = tile;
  options.rules = scene.rules;
  const auto audit = gk::engine::audit_scene(scene.objects, options);
  if (!audit.ok()) {
    std::fprintf(stderr, "%s\n", audit.error().to_string().c_str());
    return 1;
  }
  const gk::engine::AuditResult& r = audit.value();
  // The two broad phases on the whole scene's boxes (the audit runs sweep-and-prune per tile).
  std::vector<gk::Aabb> boxes;
  for (const gk::engine::AuditObject& o : scene.objects) boxes.push_back(gk::transformed_box(o.mesh->root_bounds(), o.pose));
  auto t_sap = std::chrono::steady_clock::now();
  const auto sap = gk::sweep_and_prune(boxes, options.clearance_mm);
  const double sap_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_sap).count();
  gk::HashGridStats grid_stats;
  auto t_grid = std::chrono::steady_clock::now();
  const auto grid = gk::hash_grid_pairs(boxes, options.clearance_mm, &grid_stats);
  const double grid_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_grid).count();
  std::map<gk::Verdict, int> verdicts;
  int violations = 0;
  for (const gk::engine::PairClash& c : r.clashes) {
    ++verdicts[c.verdict];
    violations += c.clearance_violation ? 1 : 0;
  }
  std::printf("objects %zu  triangles %zu (per instance)  unique meshes %zu  threads %d  tile %.0f mm\n", r.objects,
              r.triangles, scene.unique_meshes, threads, tile);
  std::printf("load + BVH build %.2f s | boxes %.3f s | broad %.3f s (%zu tiles, %zu ghost entries) | narrow %.2f s | audit %.2f s | end to end %.2f s\n",
              build_s, r.times.boxes_s, r.times.broad_s, r.tiles, r.ghost_entries, r.times.narrow_s, r.times.total_s,
              build_s + r.times.total_s);
  std::printf("candidate pairs %zu, excluded by rules %zu, narrow-phase pairs %zu | clashes %zu (collision %d, touching %d, "
              "inconclusive %d, clearance violations %d) | peak RSS %.2f GB\n",
              r.candidate_pairs, r.excluded_by_rules, r.pairs_done, r.clashes.size(), verdicts[gk::Verdict::kCollision],
              verdicts[gk::Verdict::kTouching], verdicts[gk::Verdict::kInconclusive], violations, peak_rss_gb());
  std::printf("broad phase on all %zu boxes: sweep and prune %.2f ms, hash grid %.2f ms (cell %.0f mm, %zu oversized), "
              "%zu pairs, same: %s\n",
              boxes.size(), sap_ms, grid_ms, grid_stats.cell_mm, grid_stats.oversized, sap.size(), sap == grid ? "yes" : "NO");
  return sap == grid ? 0 : 1;
}
