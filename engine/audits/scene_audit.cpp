#include "engine/audits/scene_audit.h"

#include "engine/audits/tile_scheduler.h"

#include "kernel/broadphase/broad_phase.h"
#include "kernel/measure/contact_regions.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/measure/penetration_depth.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <tuple>
#include <thread>

namespace gk::engine {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Depth on request uses a coarser lattice than ClearanceQuery: an audit has many pairs.
constexpr int kAuditDepthDirections = 42;
constexpr int kAuditVolumeRaysPerAxis = 128;
constexpr std::size_t kMaxTiles = 1u << 20;

bool matches(const std::string& pattern, const std::string& value) { return pattern == "*" || pattern == value; }

// Runs body(i) for i in [0, n) on `threads` threads pulling indices in order.
template <typename Body>
void parallel_for(std::size_t n, int threads, Body&& body) {
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < n; i = next++) body(i);
  };
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < std::min<std::size_t>(static_cast<std::size_t>(threads), n); ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

// The narrow phase of one pair; false when the pair is neither in contact nor too close.
bool audit_pair(const AuditObject& oa, const MeshBvh& ma, const AuditObject& ob, const MeshBvh& mb, const AuditOptions& options,
                PairClash& out) {
  VerdictOptions vo;
  vo.max_contacts = options.max_contacts_per_pair;
  // Farther than the clearance (plus the window the triangles of CAD parts cannot resolve): not a
  // clash, no need to measure.
  const double reach = options.clearance_mm + oa.surface_deviation_mm + ob.surface_deviation_mm;
  vo.distance_upper_bound_mm = reach;
  auto v = assess(ma, oa.pose, mb, ob.pose, vo);
  if (!v.ok()) {
    out.verdict = Verdict::kInconclusive;  // a gate treats it as a clash
    out.inconclusive_reason = InconclusiveReason::kPairFailed;
    out.error = v.error().to_string();
    return true;
  }
  const VerdictResult& r = v.value();
  if (r.verdict == Verdict::kClear && r.distance_mm >= reach) return false;
  out.verdict = r.verdict;
  out.inconclusive_reason = r.inconclusive_reason;
  out.distance_mm = r.distance_mm;
  out.point_a = r.point_a;
  out.point_b = r.point_b;
  out.clearance_violation = r.verdict == Verdict::kClear;
  if (!r.contacts.empty()) {
    std::vector<ProximityPair> pairs;
    for (const Contact& c : r.contacts) pairs.push_back({c.triangle_a, c.triangle_b, 0.0, c.point, c.point});
    out.contacts = static_cast<unsigned>(r.contacts.size());
    out.contacts_truncated = r.contacts_truncated;
    out.regions = contact_places(pairs, options.region_merge_mm);
  } else {
    auto near = pairs_within(ma, oa.pose, mb, ob.pose, options.clearance_mm, options.max_contacts_per_pair);
    if (near.ok()) {
      out.contacts = static_cast<unsigned>(near.value().pairs.size());
      out.contacts_truncated = near.value().truncated;
      out.regions = contact_places(near.value().pairs, options.region_merge_mm);
    }
  }
  if (options.compute_depth && r.verdict == Verdict::kCollision) {
    auto depth = penetration_vector(ma, oa.pose, mb, ob.pose, kAuditDepthDirections, tolerances::kAuditDepthResolutionMm);
    if (depth.ok()) {
      out.depth_mm = depth.value().depth_mm;
      out.depth_direction = Direction::of(depth.value().direction);
    }
  }
  if (options.compute_volume && r.verdict == Verdict::kCollision && ma.mesh().is_closed_oriented() &&
      mb.mesh().is_closed_oriented()) {
    auto volume = interference_volume(ma, oa.pose, mb, ob.pose, kAuditVolumeRaysPerAxis);
    if (volume.ok()) {
      // A CAD part's triangles are not its surface: the bound covers the band between them.
      const Aabb ba = transformed_box(ma.root_bounds(), oa.pose), bb = transformed_box(mb.root_bounds(), ob.pose);
      const Aabb region{ba.min.cwiseMax(bb.min), ba.max.cwiseMin(bb.max)};
      out.volume_mm3 = volume.value().volume_mm3;
      out.volume_error_bound_mm3 = volume.value().error_bound_mm3 +
                                   tessellation_band_volume(ma.mesh(), oa.pose, oa.surface_deviation_mm, region) +
                                   tessellation_band_volume(mb.mesh(), ob.pose, ob.surface_deviation_mm, region);
    }
  }
  return true;
}

std::optional<Error> validate(const std::vector<AuditObject>& objects, const AuditOptions& options) {
  if (!std::isfinite(options.clearance_mm) || options.clearance_mm < 0.0)
    return invalid_argument("clearance_mm", "must be a finite, non-negative distance");
  if (!std::isfinite(options.tile_mm) || options.tile_mm < 0.0) return invalid_argument("tile_mm", "must be finite and >= 0");
  if (options.threads < 1 || options.threads > 256) return invalid_argument("threads", "must be in [1, 256]");
  if (auto bad = check_objects(objects, true); !bad.ok()) return bad.error();
  for (std::uint32_t id : options.only_objects)
    if (id >= objects.size()) return invalid_argument("only_objects", "no object " + std::to_string(id));
  return std::nullopt;
}

}  // namespace

Result<bool> check_objects(const std::vector<AuditObject>& objects, bool packed_allowed) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string field = "objects[" + std::to_string(i) + "]";
    if (!objects[i].mesh && !(packed_allowed && objects[i].packed)) return invalid_argument(field + ".mesh", "is missing");
    if (objects[i].mesh && objects[i].packed) return invalid_argument(field + ".packed", "is given beside a mesh in memory");
    if (objects[i].packed && (objects[i].packed->triangles == 0 || objects[i].packed->bounds.empty()))
      return invalid_argument(field + ".packed", "describes no triangles");
    if (!objects[i].pose.is_finite() || !objects[i].pose.is_rigid()) return invalid_argument(field + ".pose", "must be a finite rigid transform");
    if (!(objects[i].surface_deviation_mm >= 0.0 && objects[i].surface_deviation_mm <= 1000.0))
      return invalid_argument(field + ".surface_deviation_mm", "must be in [0, 1000] mm");
  }
  return true;
}

Aabb local_bounds(const AuditObject& object) { return object.mesh ? object.mesh->root_bounds() : object.packed->bounds; }

std::size_t triangle_count(const AuditObject& object) {
  return object.mesh ? object.mesh->mesh().triangle_count() : object.packed->triangles;
}

int matching_rule(const std::vector<ContactRule>& rules, const AuditObject& a, const AuditObject& b) {
  for (std::size_t i = 0; i < rules.size(); ++i) {
    const ContactRule& r = rules[i];
    const bool cats = (matches(r.category_a, a.category) && matches(r.category_b, b.category)) ||
                      (matches(r.category_a, b.category) && matches(r.category_b, a.category));
    if (!cats) continue;
    if (r.same_group_only && (a.group.empty() || a.group != b.group)) continue;
    return static_cast<int>(i);
  }
  return -1;
}

Result<AuditResult> audit_scene(const std::vector<AuditObject>& objects, const AuditOptions& options) {
  if (auto bad = validate(objects, options)) return *bad;
  const auto t0 = Clock::now();
  AuditResult result;
  result.objects = objects.size();
  std::vector<Aabb> boxes(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    boxes[i] = transformed_box(local_bounds(objects[i]), objects[i].pose);
    result.triangles += triangle_count(objects[i]);
  }
  result.times.boxes_s = seconds_since(t0);

  // ---- broad phase, per tile ----
  const auto t_broad = Clock::now();
  std::vector<IndexPair> candidates;
  std::vector<std::size_t> owner;  // the tile owning each candidate (0 for a re-audit)
  std::mutex report_mutex;
  AuditProgress progress;
  auto last_report = Clock::now();
  auto report = [&](bool force) {
    if (!options.on_progress) return;
    std::lock_guard<std::mutex> lock(report_mutex);
    if (!force && seconds_since(last_report) < options.progress_interval_s) return;
    last_report = Clock::now();
    progress.elapsed_s = seconds_since(t0);
    progress.eta_s = progress.pairs_done > 0 && progress.pairs_total > progress.pairs_done
                         ? progress.elapsed_s / static_cast<double>(progress.pairs_done) *
                               static_cast<double>(progress.pairs_total - progress.pairs_done)
                         : 0.0;
    options.on_progress(progress);
  };
  // Boxes closer than the clearance, or than the contact tolerance (assess calls such a pair
  // TOUCHING), meet; the slack keeps rounding in the box transforms from dropping an exact touch.
  double magnitude = 1.0, deviation = 0.0;
  for (const Aabb& b : boxes) magnitude = std::max({magnitude, b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()});
  for (const AuditObject& o : objects) deviation = std::max(deviation, o.surface_deviation_mm);
  const double margin = std::max(options.clearance_mm + 2.0 * deviation, tolerances::kContactMm) +
                        4.0 * tolerances::kBoxSlackRelative * magnitude;
  bool broad_phase_cancelled = false;
  std::vector<char> wanted(objects.size(), options.only_objects.empty() ? 1 : 0);
  for (std::uint32_t id : options.only_objects) wanted[id] = 1;
  if (!options.only_objects.empty()) {
    // Re-audit: the changed objects against everything.
    for (std::uint32_t id : options.only_objects)
      for (std::uint32_t other : boxes_meeting(boxes, boxes[id], margin))
        if (other != id && (!wanted[other] || other > id)) candidates.emplace_back(std::min(id, other), std::max(id, other));
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    owner.assign(candidates.size(), 0);
    result.tiles = 1;
  } else {
    Aabb scene;
    for (const Aabb& b : boxes) scene.extend(b);
    std::size_t nx = 1, ny = 1;
    if (options.tile_mm > 0.0 && !scene.empty()) {
      // Counted in double first: a tiny tile (1e-17 mm) would overflow any integer.
      const double tx = std::ceil(scene.diagonal().x() / options.tile_mm) + 1.0;
      const double ty = std::ceil(scene.diagonal().y() / options.tile_mm) + 1.0;
      if (!(tx * ty <= static_cast<double>(kMaxTiles))) return invalid_argument("tile_mm", "gives more than 2^20 tiles for this scene");
      nx = static_cast<std::size_t>(tx);
      ny = static_cast<std::size_t>(ty);
    }
    const double tile = options.tile_mm > 0.0 ? options.tile_mm : 1.0;
    auto tile_x = [&](double x) {
      if (nx == 1) return std::size_t{0};
      return std::min(nx - 1, static_cast<std::size_t>(std::max(0.0, std::floor((x - scene.min.x()) / tile))));
    };
    auto tile_y = [&](double y) {
      if (ny == 1) return std::size_t{0};
      return std::min(ny - 1, static_cast<std::size_t>(std::max(0.0, std::floor((y - scene.min.y()) / tile))));
    };
    std::vector<std::vector<std::uint32_t>> members(nx * ny);
    for (std::uint32_t i = 0; i < objects.size(); ++i) {
      if (options.cancel && options.cancel->load()) break;  // the broad phase below sees it too
      const Aabb g = boxes[i].expanded(0.5 * margin);
      for (std::size_t x = tile_x(g.min.x()); x <= tile_x(g.max.x()); ++x)
        for (std::size_t y = tile_y(g.min.y()); y <= tile_y(g.max.y()); ++y) members[x * ny + y].push_back(i);
    }
    std::size_t entries = 0;
    for (const auto& m : members) entries += m.size();
    result.ghost_entries = entries - objects.size();
    result.tiles = nx * ny;
    progress.tiles_total = nx * ny;
    std::vector<std::vector<IndexPair>> per_tile(nx * ny);
    parallel_for(nx * ny, options.threads, [&](std::size_t t) {
      // Cancelled between tiles: a million small tiles of a crowded scene take many seconds.
      if (options.cancel && options.cancel->load()) return;
      const std::vector<std::uint32_t>& ids = members[t];
      std::vector<Aabb> local;
      local.reserve(ids.size());
      for (std::uint32_t id : ids) local.push_back(boxes[id]);
      for (const auto& [la, lb] : sweep_and_prune(local, margin)) {
        const std::uint32_t a = ids[la], b = ids[lb];
        // The tile holding the low corner of the grown boxes' intersection owns the pair.
        const Vec3 low = boxes[a].expanded(0.5 * margin).min.cwiseMax(boxes[b].expanded(0.5 * margin).min);
        if (tile_x(low.x()) * ny + tile_y(low.y()) != t) continue;
        per_tile[t].emplace_back(std::min(a, b), std::max(a, b));
      }
      std::lock_guard<std::mutex> lock(report_mutex);
      ++progress.tiles_done;
    });
    // Cancelled during the broad phase, the candidates are incomplete: never a report of "no clash".
    broad_phase_cancelled = options.cancel && options.cancel->load();
    // Tile by tile, each tile's pairs in (a, b) order.
    for (std::size_t t = 0; t < per_tile.size(); ++t) {
      std::sort(per_tile[t].begin(), per_tile[t].end());
      candidates.insert(candidates.end(), per_tile[t].begin(), per_tile[t].end());
      owner.insert(owner.end(), per_tile[t].size(), t);
    }
  }
  // Intended contacts never reach the narrow phase; nor do the pairs of tiles a checkpoint holds.
  std::vector<char> skipped(result.tiles, 0);
  for (std::size_t t : options.skip_tiles)
    if (t < skipped.size()) skipped[t] = 1;
  // A pair's estimated cost: both meshes' triangles. Each tile's sum, skipped tiles included, so
  // that every process of a distributed audit plans the same.
  auto pair_cost = [&](const IndexPair& p) {
    return static_cast<double>(triangle_count(objects[p.first]) + triangle_count(objects[p.second]));
  };
  std::vector<double>& tile_cost = result.tile_costs;
  tile_cost.assign(result.tiles, 0.0);
  result.tile_pairs.assign(result.tiles, 0);
  std::vector<IndexPair> work;
  std::vector<std::size_t> work_tile;
  std::size_t done_before = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const IndexPair& p = candidates[i];
    if (matching_rule(options.rules, objects[p.first], objects[p.second]) >= 0) {
      ++result.excluded_by_rules;
      continue;
    }
    tile_cost[owner[i]] += pair_cost(p);
    ++result.tile_pairs[owner[i]];
    if (skipped[owner[i]]) {
      ++done_before;
    } else {
      work.push_back(p);
      work_tile.push_back(owner[i]);
    }
  }
  result.candidate_pairs = candidates.size();
  result.times.broad_s = seconds_since(t_broad);

  // ---- narrow phase: tile by tile, the costliest tiles and pairs first ----
  const auto t_narrow = Clock::now();
  auto cost = [&](std::size_t i) { return pair_cost(work[i]); };
  if (options.broad_phase_only) {
    result.times.total_s = seconds_since(t0);
    return result;
  }
  // Tiles in memory: the costliest first. Out of core: in floor-plan order, so that a tile's
  // neighbours, which share its ghosts, follow it while those meshes are held.
  bool out_of_core = false;
  for (const AuditObject& o : objects) out_of_core = out_of_core || o.packed.has_value();
  std::vector<TileScheduler::Tile> tiles(result.tiles);
  for (std::size_t t = 0; t < tiles.size(); ++t) tiles[t].id = t;
  for (std::size_t i = 0; i < work.size(); ++i) tiles[work_tile[i]].pairs.push_back(i);  // in (a, b) order
  // Each tile's work indices in (a, b) order, for handing over its clashes when it is done.
  std::vector<std::vector<std::size_t>> tile_work;
  if (options.on_tile_done)
    for (const TileScheduler::Tile& t : tiles) tile_work.push_back(t.pairs);
  for (TileScheduler::Tile& t : tiles)
    std::stable_sort(t.pairs.begin(), t.pairs.end(), [&](std::size_t l, std::size_t r) { return cost(l) > cost(r); });
  if (!out_of_core)
    std::stable_sort(tiles.begin(), tiles.end(), [&](const TileScheduler::Tile& l, const TileScheduler::Tile& r) {
      return tile_cost[l.id] > tile_cost[r.id];
    });
  TileScheduler::Setup setup;
  setup.tiles = std::move(tiles);
  setup.work = &work;
  setup.budget_bytes = options.memory_budget_bytes;
  // One mesh per distinct MeshBvh in memory or pack file on disk: objects sharing one share its reading.
  std::map<const MeshBvh*, std::uint32_t> mesh_in_memory;
  std::map<std::string, std::uint32_t> mesh_on_disk;
  std::vector<std::uint32_t> first_object;  // per mesh, an object holding it
  for (std::uint32_t i = 0; i < objects.size(); ++i) {
    const AuditObject& o = objects[i];
    const auto next = static_cast<std::uint32_t>(first_object.size());
    const std::uint32_t m = o.mesh ? mesh_in_memory.emplace(o.mesh.get(), next).first->second
                                   : mesh_on_disk.emplace(o.packed->path, next).first->second;
    setup.mesh_of.push_back(m);
    if (m != next) continue;
    first_object.push_back(i);
    setup.in_memory.push_back(o.mesh);
    // Held in memory: the pack's arrays (the tree reads the mesh's own corners); read through a
    // mapping of the file. Counted with a margin for the allocations' rounding, and the node slabs
    // a distance query fits (kernel/bvh/node_slabs.h).
    setup.bytes.push_back(o.packed ? o.packed->bytes + o.packed->bytes / 8 + MeshBvh::slab_bytes_at_most(o.packed->triangles) : 0);
    setup.file_bytes.push_back(o.packed ? o.packed->bytes : 0);
  }
  setup.loader = [&objects, &first_object](std::uint32_t m) { return read_packed_mesh(*objects[first_object[m]].packed); };
  TileScheduler scheduler(std::move(setup));
  std::vector<PairClash> slots(work.size());
  std::vector<char> state(work.size(), 0);  // 0 not done, 1 done no clash, 2 clash
  progress.pairs_total = work.size() + done_before;
  progress.pairs_done = done_before;
  report(true);
  std::atomic<std::size_t> done{done_before}, clashes{0};
  auto worker = [&] {
    while (auto assigned = scheduler.next(options.cancel)) {
      const std::size_t i = assigned->work_index;
      PairClash& c = slots[i];
      c.a = work[i].first;
      c.b = work[i].second;
      bool clash = true;
      if (!assigned->error.empty()) {  // a mesh could not be read: the pair is undecided, a clash
        c.verdict = Verdict::kInconclusive;
        c.inconclusive_reason = InconclusiveReason::kPairFailed;
        c.error = assigned->error;
      } else {
        clash = audit_pair(objects[c.a], *assigned->a, objects[c.b], *assigned->b, options, c);
      }
      // The pair's hold on its meshes ends before the tile may be finished, so that what the
      // scheduler lets go is freed at once (its budget counts what it holds).
      assigned->a.reset();
      assigned->b.reset();
      state[i] = clash ? 2 : 1;
      ++done;
      if (clash) ++clashes;
      if (clash && options.on_clash) {
        std::lock_guard<std::mutex> lock(report_mutex);
        options.on_clash(c);
      }
      if (const auto t = scheduler.finish(i); t && options.on_tile_done) {
        std::vector<PairClash> found;
        for (std::size_t j : tile_work[*t])
          if (state[j] == 2) found.push_back(slots[j]);
        std::lock_guard<std::mutex> lock(report_mutex);
        options.on_tile_done(*t, found);
      }
      if (options.on_progress) {
        {
          std::lock_guard<std::mutex> lock(report_mutex);
          progress.pairs_done = done;
          progress.clashes = clashes;
        }
        report(false);
      }
    }
  };
  {
    std::vector<std::thread> pool;
    for (int t = 1; t < options.threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
  }
  const TileScheduler::Stats io = scheduler.stats();
  result.bytes_read = io.bytes_read;
  result.meshes_read = io.meshes_read;
  result.peak_held_bytes = io.peak_held_bytes;
  result.tiles_over_budget = io.tiles_over_budget;
  result.meshes_let_go = io.meshes_let_go;
  for (std::size_t i = 0; i < work.size(); ++i)
    if (state[i] == 2) result.clashes.push_back(std::move(slots[i]));
  sort_in_pair_order(result.clashes);  // tile order is not (a, b) order when the tiles are several
  result.pairs_done = done;
  result.cancelled = broad_phase_cancelled || done < work.size() + done_before;
  result.times.narrow_s = seconds_since(t_narrow);
  result.times.total_s = seconds_since(t0);
  progress.pairs_done = done;
  progress.clashes = clashes;
  report(true);
  return result;
}

void sort_in_pair_order(std::vector<PairClash>& clashes) {
  std::sort(clashes.begin(), clashes.end(), [](const PairClash& l, const PairClash& r) { return std::tie(l.a, l.b) < std::tie(r.a, r.b); });
}

Result<AuditResult> reaudit_scene(const std::vector<AuditObject>& objects, const AuditResult& previous,
                                  const std::vector<std::uint32_t>& changed, const AuditOptions& options) {
  if (changed.empty()) return previous;
  AuditOptions only = options;
  only.only_objects = changed;
  auto fresh = audit_scene(objects, only);
  if (!fresh.ok()) return fresh.error();
  for (const PairClash& c : previous.clashes)
    if (c.a >= objects.size() || c.b >= objects.size())
      return invalid_argument("previous", "a clash names object " + std::to_string(std::max(c.a, c.b)) + ", beyond the objects given");
  for (std::uint32_t id : changed)
    if (id >= objects.size()) return invalid_argument("changed", "no object " + std::to_string(id));
  std::vector<char> is_changed(objects.size(), 0);
  for (std::uint32_t id : changed) is_changed[id] = 1;
  AuditResult out = fresh.value();
  for (const PairClash& c : previous.clashes)
    if (!is_changed[c.a] && !is_changed[c.b]) out.clashes.push_back(c);
  sort_in_pair_order(out.clashes);
  return out;
}

}  // namespace gk::engine
