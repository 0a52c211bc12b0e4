// The interference audit of a whole scene (seed 000, scenario 3): every pair of objects checked,
// tiled and in parallel, with progress and cancellation.
//
//  1. Tiles: the scene's floor plan (x, y) is cut into square tiles; an object belongs to every
//     tile its box meets (a "ghost" in all but one). Each tile runs its own broad phase, and a pair
//     is kept only by the tile holding the low corner of the two boxes' intersection, so a pair
//     crossing tile borders is audited once and no global pair set is needed.
//  2. Two levels of parallelism: tiles are spread over the threads; then the candidate pairs are
//     pulled by the threads one at a time, tile by tile (the costliest tiles first, and in a tile
//     the costliest pairs first, so no thread is left with a giant pair at the end). A tile whose
//     pairs are all done is reported (on_tile_done): a checkpoint a resumed audit skips.
//  3. Per pair: the exact verdict (kernel/query/contact_verdict), contact locations grouped into clash
//     regions, clearance violations for a gap, and the penetration depth on request.
// Results are in pair order whatever the tiling or thread count, so runs are reproducible.
#pragma once

#include "kernel/core/direction.h"
#include "engine/parts/packed_mesh_file.h"
#include "engine/verdicts/contact_place.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <optional>
#include <vector>

namespace gk::engine {

// One object: a shared (instanced) mesh at a pose. Identical meshes share one MeshBvh.
struct AuditObject {
  std::string name;
  std::string category;  // e.g. "column", "robot", "pipe"
  std::string group;     // an assembly; rules can allow contacts inside one
  std::shared_ptr<const MeshBvh> mesh;
  RigidTransform pose;
  // How far the object's true surface may lie from its triangles [mm]: a CAD part's tessellation
  // deflection, 0 for a mesh. A pair is reported up to the clearance plus both deviations, for the
  // layer above to decide on the exact geometry (the triangles cannot tell within that window).
  double surface_deviation_mm = 0.0;
  // Or, without `mesh`, the mesh on disk, read when a tile needs it and released after (out of core; audits only).
  std::optional<PackedMeshFile> packed = std::nullopt;
};

// Every object has a mesh (in memory, or on disk where `packed_allowed`), a finite rigid pose and
// a surface deviation in [0, 1000] mm; an error names objects[i] and the field otherwise (the
// audit's and the layout session's check).
Result<bool> check_objects(const std::vector<AuditObject>& objects, bool packed_allowed);

// The object's mesh bounds in its own frame and its triangle count, whether in memory or on disk.
Aabb local_bounds(const AuditObject& object);
std::size_t triangle_count(const AuditObject& object);

// An intended contact (seed 004 §6: parts bolted together, pins in holes): matching pairs are left
// out of the narrow phase and counted as excluded.
struct ContactRule {
  std::string name;
  std::string category_a, category_b;  // "*" matches any; the order of the pair does not matter
  bool same_group_only = false;        // only when both objects belong to the same (non-empty) group
};

struct PairClash {
  std::uint32_t a = 0, b = 0;  // object indices, a < b
  Verdict verdict = Verdict::kClear;
  InconclusiveReason inconclusive_reason = InconclusiveReason::kNone;
  double distance_mm = 0.0;    // 0 when in contact
  bool clearance_violation = false;  // apart, but closer than the gap
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();
  std::vector<ContactPlace> regions;  // contact locations grouped
  unsigned contacts = 0;
  bool contacts_truncated = false;
  double depth_mm = -1.0;      // on request, for collisions: certified upper bound (kernel/measure/penetration_depth)
  std::optional<Direction> depth_direction;  // with depth_mm
  double volume_mm3 = -1.0;    // on request, for collisions of closed meshes: ray-cast shared volume
  double volume_error_bound_mm3 = -1.0;  // |volume_mm3 - true volume| <= this
  std::string error;           // the pair could not be decided (then verdict INCONCLUSIVE)
};

struct AuditProgress {
  std::size_t tiles_total = 0, tiles_done = 0;
  std::size_t pairs_total = 0, pairs_done = 0;
  std::size_t clashes = 0;
  double elapsed_s = 0.0, eta_s = 0.0;
};

struct AuditOptions {
  double clearance_mm = 0.0;   // pairs closer than this are violations
  double tile_mm = 0.0;        // 0: one tile
  int threads = 1;
  bool compute_depth = false;
  bool compute_volume = false;
  double region_merge_mm = 100.0;
  std::size_t max_contacts_per_pair = 2000;
  std::vector<ContactRule> rules;
  // Only pairs with at least one of these objects (an incremental re-audit); empty: all pairs.
  std::vector<std::uint32_t> only_objects;
  const std::atomic<bool>* cancel = nullptr;
  std::function<void(const AuditProgress&)> on_progress;  // called from worker threads, serialised
  std::function<void(const PairClash&)> on_clash;          // each clash as found (any order), serialised
  double progress_interval_s = 0.2;
  // Checkpoints. A tile is numbered by its place in the floor plan, the same in every run of the
  // same objects with the same tile_mm and clearance. When every pair a tile owns is done, its
  // clashes (in (a, b) order; none for a clear tile) are handed over, serialised with the other
  // calls; not for a tile cut short by cancellation, and not for tiles without pairs.
  std::function<void(std::size_t tile, const std::vector<PairClash>& clashes)> on_tile_done;
  // Tiles a checkpoint holds: their pairs are not computed again and their clashes are not in the
  // result (the caller adds the checkpoint's); they count as done.
  std::vector<std::size_t> skip_tiles;
  // Out of core: the most bytes of meshes read from disk (objects given `packed`) held at once; 0:
  // no limit. With packed objects, tiles are worked on in floor-plan order (engine/audits/tile_scheduler).
  std::uint64_t memory_budget_bytes = 0;
  // Stop after the broad phase: the result has the tiles, the candidate pairs and each tile's
  // cost, and no clash (how a distributed audit plans which process takes which tiles).
  bool broad_phase_only = false;
};

struct AuditTimes {
  double boxes_s = 0.0, broad_s = 0.0, narrow_s = 0.0, total_s = 0.0;
};

struct AuditResult {
  std::vector<PairClash> clashes;        // ordered by (a, b)
  std::size_t objects = 0, triangles = 0;  // triangles counted per instance
  std::size_t tiles = 0, candidate_pairs = 0, excluded_by_rules = 0, pairs_done = 0;
  std::size_t ghost_entries = 0;         // object-in-tile entries beyond the first
  // Per tile, the estimated cost of its pairs (the sum over its pairs of both meshes' triangle
  // counts; 0: no pair to audit), skipped tiles included.
  std::vector<double> tile_costs;
  std::vector<std::size_t> tile_pairs;   // per tile, its pairs for the narrow phase (skipped tiles included)
  bool cancelled = false;                // then clashes cover the pairs_done pairs finished
  AuditTimes times;
  // Out of core: the bytes of packs read and how many (objects sharing a pack share its reading),
  // the most held at once (estimated in-memory bytes), meshes let go to fit the budget, and the
  // tiles admitted beyond the budget because alone they do not fit it.
  std::uint64_t bytes_read = 0, meshes_read = 0, peak_held_bytes = 0;
  std::uint64_t meshes_let_go = 0;       // let go to fit the budget, then read again
  std::size_t tiles_over_budget = 0;
};

Result<AuditResult> audit_scene(const std::vector<AuditObject>& objects, const AuditOptions& options);

// The canonical order of an audit's clashes, (a, b): what every report and merge is sorted by.
void sort_in_pair_order(std::vector<PairClash>& clashes);

// Incremental re-audit: the previous result with every pair involving a changed object recomputed
// (the changed objects' new poses are in `objects`). Equals a full audit of `objects`.
Result<AuditResult> reaudit_scene(const std::vector<AuditObject>& objects, const AuditResult& previous,
                                  const std::vector<std::uint32_t>& changed, const AuditOptions& options);

// Which rule (index) excludes the pair, or -1.
int matching_rule(const std::vector<ContactRule>& rules, const AuditObject& a, const AuditObject& b);

}  // namespace gk::engine
