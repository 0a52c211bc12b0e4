// gatekeeper-audit: an audit of one scene spread over the processes of an MPI job.
//
//   mpiexec -n N gatekeeper-audit --data-dir DIR --scene SCENE --work-dir SHARED --out report.json
//           [--memory-budget-gb G]   (out of core: meshes read from packs tile by tile)
//
// Every process opens the daemon's data directory for reading (scenes, parts, the BVH cache: on
// storage all of them see), runs the same broad phase and so the same plan of tiles
// (engine/audits/tile_plan: costliest tile to the least loaded process), and audits its own
// tiles. Each finished tile is written to the shared work directory (written whole, synced,
// renamed), which is also the checkpoint: run the same command again after a failure (a killed
// process ends the whole MPI job) and only the tiles without a file are computed. Process 0 then
// merges every tile's clashes in the canonical (object, object) order of the single-process audit
// and writes the report. Clashes are the kernel's answers on the triangles: a pair with a CAD part
// within its tessellation's deflection is reported (conservatively), not decided again on the
// exact faces as the daemon's audit does.
#include "engine/audits/audit_request.h"
#include "engine/audits/scene_audit.h"
#include "engine/audits/tile_plan.h"
#include "engine/parts/part_registry.h"
#include "engine/parts/part_store.h"
#include "engine/scenes/placed_scene.h"
#include "engine/scenes/scene_store.h"
#include "kernel/core/content_hash.h"
#include "server/distributed_audit/audit_work_dir.h"

#include <CLI/CLI.hpp>
#include <mpi.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace gk;
using server::read_whole;
using server::tile_path;
using server::write_whole;

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kClear: return "CLEAR";
    case Verdict::kTouching: return "TOUCHING";
    case Verdict::kCollision: return "COLLISION";
    case Verdict::kInconclusive: return "INCONCLUSIVE";
  }
  return "?";
}

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

int fail(int rank, const std::string& message) {
  std::fprintf(stderr, "gatekeeper-audit (process %d): %s\n", rank, message.c_str());
  MPI_Abort(MPI_COMM_WORLD, 2);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  CLI::App app("gatekeeper-audit: one scene's audit over the processes of an MPI job");
  std::string data_dir, scene_id, work_dir, out_path;
  engine::AuditOptions asked;
  int threads = 1;
  double memory_budget_gb = 0.0;
  app.add_option("--data-dir", data_dir, "the daemon's data directory (read only)")->required();
  std::string job_path;
  auto* scene_option = app.add_option("--scene", scene_id, "the scene to audit (as it is in the data directory now)");
  auto* job_option = app.add_option("--job", job_path,
                                    "instead of --scene: a job file (a scene snapshot and all options) written by the daemon "
                                    "handing this audit over; its options replace the ones given here");
  scene_option->excludes(job_option);
  app.add_option("--work-dir", work_dir, "a directory every process can write: finished tiles (the checkpoint)")->required();
  app.add_option("--out", out_path, "the report (JSON), written by process 0")->required();
  app.add_option("--clearance-mm", asked.clearance_mm, "pairs closer than this are clearance violations");
  app.add_option("--tile-mm", asked.tile_mm, "floor-plan tile side (0: 50,000 mm)");
  app.add_option("--threads", threads, "threads per process");
  app.add_flag("--compute-depth", asked.compute_depth, "a penetration depth per colliding pair");
  app.add_flag("--compute-volume", asked.compute_volume, "the shared volume per colliding pair of closed meshes");
  app.add_option("--memory-budget-gb", memory_budget_gb,
                 "out of core: each part is written once as a pack beside the BVH cache, and each process holds at most "
                 "this many GB of meshes at once, reading them tile by tile (0: every part in memory)")
      ->check(CLI::Range(0.0, 1.0e6));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (rank == 0) app.exit(e);
    MPI_Finalize();
    return e.get_exit_code() == 0 ? 0 : 2;
  }
  asked.threads = threads;
  if (scene_id.empty() && job_path.empty()) return fail(rank, "--scene or --job is required");
  Result<engine::SceneRecord> scene = Error{};
  if (!job_path.empty()) {
    auto job = server::read_job_file(job_path);
    if (!job.ok()) return fail(rank, job.error().to_string());
    scene = job.value().scene;
    asked = job.value().options;
    scene_id = job.value().scene.id;
  }
  auto options = engine::checked_audit_options(asked, 1);
  if (!options.ok()) return fail(rank, options.error().to_string());
  if (!fs::is_regular_file(data_dir + "/gatekeeper.sqlite")) return fail(rank, "--data-dir: no daemon data directory at " + data_dir);
  if (job_path.empty()) {
    auto scenes = engine::SceneStore::open_read_only(data_dir);
    if (!scenes.ok()) return fail(rank, scenes.error().to_string());
    scene = scenes.value()->get(scene_id);
    if (!scene.ok()) return fail(rank, scene.error().to_string());
  }

  // The work directory belongs to this audit: its fingerprint is written by the first run (each
  // process writes the same bytes, renamed into place) and must match on every later one.
  std::error_code ec;
  fs::create_directories(work_dir, ec);
  if (ec) return fail(rank, "--work-dir: cannot create " + work_dir + ": " + ec.message());
  const std::string print = server::audit_fingerprint(scene.value(), options.value());
  const std::string print_path = work_dir + "/audit.fingerprint";
  if (!fs::exists(print_path) && !write_whole(print_path, print + "\n")) return fail(rank, "--work-dir: cannot write " + print_path);
  if (read_whole(print_path) != print + "\n")
    return fail(rank, "--work-dir: " + work_dir + " holds the tiles of another audit (another scene snapshot or other options); use a fresh directory");
  // For whoever watches the job (a test kills one process by it).
  std::ofstream(work_dir + "/process-" + std::to_string(rank) + ".pid") << ::getpid() << "\n";
  auto store = engine::PartStore::open_read_only(data_dir);
  if (!store.ok()) return fail(rank, store.error().to_string());
  const auto t_load = std::chrono::steady_clock::now();
  Result<engine::PlacedScene> placed = Error{};
  if (memory_budget_gb > 0.0) {
    // The registry exists only while the packs are written: its parts are gone before the audit.
    const auto budget = static_cast<std::size_t>(memory_budget_gb * 1e9);
    engine::PartRegistry parts(*store.value(), data_dir + "/bvh-cache", budget);
    placed = engine::place_scene_packed(scene.value(), parts, data_dir + "/bvh-cache/packs");
  } else {
    engine::PartRegistry parts(*store.value(), data_dir + "/bvh-cache");
    placed = engine::place_scene(scene.value(), parts);
  }
  if (!placed.ok()) return fail(rank, placed.error().to_string());
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_load).count();
  const std::vector<engine::AuditObject>& objects = placed.value().objects;

  // The same plan on every process.
  engine::AuditOptions plan_options = options.value();
  plan_options.broad_phase_only = true;
  auto planned = engine::audit_scene(objects, plan_options);
  if (!planned.ok()) return fail(rank, planned.error().to_string());
  const std::vector<double>& costs = planned.value().tile_costs;
  const std::vector<std::vector<std::size_t>> plan = engine::plan_tiles(costs, size);
  std::vector<char> mine(costs.size(), 0);
  for (std::size_t t : plan[static_cast<std::size_t>(rank)]) mine[t] = 1;

  engine::AuditOptions run = options.value();
  run.memory_budget_bytes = static_cast<std::uint64_t>(memory_budget_gb * 1e9);
  std::size_t resumed = 0;
  for (std::size_t t = 0; t < costs.size(); ++t) {
    const bool done = fs::exists(tile_path(work_dir, t));
    if (!mine[t] || done) run.skip_tiles.push_back(t);
    if (mine[t] && done) ++resumed;
  }
  std::string write_error;
  std::size_t written = 0;
  run.on_tile_done = [&](std::size_t tile, const std::vector<engine::PairClash>& clashes) {
    if (!write_whole(tile_path(work_dir, tile), server::tile_file_bytes(print, tile, clashes)))
      write_error = "cannot write " + tile_path(work_dir, tile);
    else ++written;
  };
  const auto t_run = std::chrono::steady_clock::now();
  auto result = engine::audit_scene(objects, run);
  if (!result.ok()) return fail(rank, result.error().to_string());
  if (!write_error.empty()) return fail(rank, write_error);
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_run).count();
  double my_cost = 0.0;
  for (std::size_t t : plan[static_cast<std::size_t>(rank)]) my_cost += costs[t];
  std::ofstream(work_dir + "/process-" + std::to_string(rank) + ".json")
      << nlohmann::json{{"process", rank}, {"tiles", plan[static_cast<std::size_t>(rank)].size()}, {"tiles_computed", written},
                        {"tiles_resumed", resumed}, {"estimated_cost", my_cost}, {"load_s", load_s}, {"audit_s", run_s},
                        {"packs_read", result.value().meshes_read}, {"pack_bytes_read", result.value().bytes_read},
                        {"most_held_bytes", result.value().peak_held_bytes}}
             .dump()
      << "\n";

  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0) {
    std::vector<engine::PairClash> clashes;
    std::vector<std::size_t> missing;
    for (std::size_t t = 0; t < costs.size(); ++t) {
      if (!(costs[t] > 0.0)) continue;
      if (!fs::exists(tile_path(work_dir, t))) {
        missing.push_back(t);
        continue;
      }
      auto tile = server::read_tile_file(tile_path(work_dir, t), print, t);
      if (!tile.ok()) return fail(rank, tile_path(work_dir, t) + ": " + tile.error().message + " (delete the file and run again)");
      for (const engine::PairClash& c : tile.value())
        if (c.b >= objects.size()) return fail(rank, tile_path(work_dir, t) + ": names an object this scene does not have (delete the file and run again)");
      clashes.insert(clashes.end(), tile.value().begin(), tile.value().end());
    }
    if (!missing.empty()) return fail(rank, std::to_string(missing.size()) + " tiles have no result: run the same command again");
    engine::sort_in_pair_order(clashes);
    const auto& records = placed.value().records;
    nlohmann::json report;
    report["scene_id"] = scene_id;
    report["processes"] = size;
    report["objects"] = planned.value().objects;
    report["triangles"] = planned.value().triangles;
    report["tiles"] = planned.value().tiles;
    report["candidate_pairs"] = planned.value().candidate_pairs;
    report["excluded_by_rules"] = planned.value().excluded_by_rules;
    nlohmann::json list = nlohmann::json::array();
    for (const engine::PairClash& c : clashes) {
      nlohmann::json j{{"object_a", records[c.a]->id},
                       {"object_b", records[c.b]->id},
                       {"name_a", records[c.a]->name},
                       {"name_b", records[c.b]->name},
                       {"verdict", verdict_name(c.verdict)},
                       {"distance_mm", c.distance_mm},
                       {"clearance_violation", c.clearance_violation},
                       {"point_a", vec(c.point_a)},
                       {"point_b", vec(c.point_b)},
                       {"contacts", c.contacts},
                       {"regions", c.regions.size()},
                       {"depth_mm", c.depth_mm},
                       {"volume_mm3", c.volume_mm3},
                       {"volume_error_bound_mm3", c.volume_error_bound_mm3}};
      if (c.depth_direction) j["depth_direction"] = vec(c.depth_direction->vector());
      if (!c.error.empty()) j["error"] = c.error;
      list.push_back(std::move(j));
    }
    report["clashes"] = std::move(list);
    nlohmann::json per_process = nlohmann::json::array();
    for (int r = 0; r < size; ++r) {
      const std::string text = read_whole(work_dir + "/process-" + std::to_string(r) + ".json");
      per_process.push_back(nlohmann::json::parse(text, nullptr, false));
    }
    report["per_process"] = std::move(per_process);
    if (!write_whole(out_path, report.dump(1) + "\n")) return fail(rank, "cannot write " + out_path);
    std::printf("gatekeeper-audit: %zu clashes among %llu objects, %zu tiles over %d processes -> %s\n", clashes.size(),
                static_cast<unsigned long long>(planned.value().objects), planned.value().tiles, size, out_path.c_str());
  }
  MPI_Finalize();
  return 0;
}
