// The factory audit end to end on a generated scene: mesh loading and BVH builds (once per unique
// mesh), then the tiled, parallel audit, with the time of every stage and the peak RSS.
//   build/tests/benchmarks/audit_benchmark [objects] [triangles] [threads] [tile_mm] [distinct]
//   e.g. audit_benchmark 10000 100000000 2 50000      (catalogue meshes shared, as in a real twin)
//        audit_benchmark 2000 10000000 2 50000 1      (every machine its own mesh and BVH)
//        audit_benchmark 2000 10000000 2 50000 1 DIR  (BVHs from the disk cache in DIR; run twice)
//        audit_benchmark 10000 100000000 2 50000 2 --packed DIR --budget-gb 3
//            (DISTINCT 2: every copy randomly deformed, its own content; out of core: the first run
//             builds every object's mesh and tree into DIR and releases it, the audit reads them
//             tile by tile within the budget; a second run reads the scene's index from DIR and
//             audits from the packs without building anything; --cold drops the packs from the
//             page cache first, so they are read from the disk)
#include "kernel/broadphase/broad_phase.h"
#include "engine/audits/scene_audit.h"
#include "tests/support/factory_scene.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

double peak_rss_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB on Linux
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args;
  std::string packed_dir;
  double budget_gb = 0.0;
  bool cold = false;  // --cold: the packs are dropped from the page cache first, so they are read from the disk
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--packed" && i + 1 < argc) {
      packed_dir = argv[++i];
    } else if (a == "--cold") {
      cold = true;
    } else if (a == "--budget-gb" && i + 1 < argc) {
      budget_gb = std::atof(argv[++i]);
    } else {
      args.push_back(a);
    }
  }
  auto arg = [&](std::size_t k) { return k < args.size() ? args[k].c_str() : nullptr; };
  gk::testing::FactorySceneOptions scene_options;
  scene_options.objects = arg(0) ? std::strtoul(arg(0), nullptr, 10) : 10000;
  scene_options.triangles = arg(1) ? std::strtoull(arg(1), nullptr, 10) : 100000000ULL;
  const int threads = arg(2) ? std::atoi(arg(2)) : 2;
  const double tile = arg(3) ? std::atof(arg(3)) : 50000.0;
  const int distinct = arg(4) ? std::atoi(arg(4)) : 0;
  scene_options.distinct_meshes = distinct != 0;
  scene_options.deformed = distinct == 2;
  if (arg(5)) scene_options.bvh_cache_dir = arg(5);
  scene_options.pack_dir = packed_dir;
  const auto t0 = std::chrono::steady_clock::now();
  gk::testing::FactoryScene scene;
  const char* scene_source = "generated and built";
  if (!packed_dir.empty()) {
    auto indexed = gk::testing::read_factory_scene_index(packed_dir);
    if (indexed.ok()) {
      scene = std::move(indexed).value();
      scene_source = "index read (meshes and trees stay in the packs)";
    }
  }
  if (scene.objects.empty()) scene = gk::testing::generate_factory_scene(scene_options);
  if (cold) {
    ::sync();
    for (const gk::engine::AuditObject& o : scene.objects) {
      if (!o.packed) continue;
      const int fd = ::open(o.packed->path.c_str(), O_RDONLY);
      if (fd < 0) continue;
      ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
      ::close(fd);
    }
  }
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  gk::engine::AuditOptions options;
  options.memory_budget_bytes = static_cast<std::uint64_t>(budget_gb * 1e9);
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
  for (const gk::engine::AuditObject& o : scene.objects) boxes.push_back(gk::transformed_box(gk::engine::local_bounds(o), o.pose));
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
  std::printf("scene: %s\n", scene_source);
  if (!packed_dir.empty())
    std::printf("out of core%s: budget %.2f GB | read %.3f GB of packs in %llu meshes | most held at once %.3f GB | tiles over budget %zu\n",
                cold ? " (packs dropped from the page cache first)" : "", budget_gb, static_cast<double>(r.bytes_read) / 1e9, static_cast<unsigned long long>(r.meshes_read),
                static_cast<double>(r.peak_held_bytes) / 1e9, r.tiles_over_budget);
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
