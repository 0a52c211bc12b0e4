// Hands an audit's narrow-phase pairs to worker threads tile by tile, keeping in memory the meshes
// of the tiles being worked on and, budget permitting, those later tiles will need (seed 000 §5.3:
// tiles out of core).
//
// A tile is admitted when the meshes it still lacks fit in the memory budget beside those held.
// If they do not, held meshes that no running tile uses are let go first, those needed farthest
// ahead first (they are read again when their tile comes); if they still do not fit, the tile
// waits for running tiles to finish, or is admitted alone when none runs (counted as over
// budget), so an audit always progresses. Its missing meshes are read by the admitting thread,
// then its pairs are handed out; meanwhile an idle thread admits the next tile, so reading
// overlaps computing. When a tile's last pair is done, every mesh no later tile needs is
// released. Objects that share a mesh (the same pack) share its one reading; without budget
// pressure each mesh is read once per audit however many tiles it spans. Meshes given in memory
// are held throughout and not counted against the budget.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/status.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace gk::engine {

class TileScheduler {
 public:
  struct Tile {
    std::size_t id = 0;                // the tile's number in the floor plan
    std::vector<std::size_t> pairs;    // work indices, in the order they are handed out
  };
  // Reads mesh m (only called for meshes not given in memory).
  using Loader = std::function<Result<std::shared_ptr<const MeshBvh>>(std::uint32_t mesh)>;

  struct Setup {
    std::vector<Tile> tiles;                                   // in the order they are admitted
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>* work = nullptr;  // the pairs of objects (a, b)
    std::vector<std::uint32_t> mesh_of;                        // per object, its mesh; empty: mesh i is object i's
    std::vector<std::shared_ptr<const MeshBvh>> in_memory;     // per mesh; null: read with the loader
    std::vector<std::uint64_t> bytes;                          // per mesh: its size in memory once read
    std::vector<std::uint64_t> file_bytes;                     // per mesh: the bytes its reading reads
    std::uint64_t budget_bytes = 0;                            // 0: no limit
    Loader loader;
  };

  struct Assignment {
    std::size_t work_index = 0;
    std::shared_ptr<const MeshBvh> a, b;  // null when the mesh could not be read (then error says why)
    std::string error;
  };

  struct Stats {
    std::uint64_t bytes_read = 0, meshes_read = 0, peak_held_bytes = 0;  // bytes_read: of files
    std::uint64_t meshes_let_go = 0;      // held meshes let go to fit the budget (read again later)
    std::size_t tiles_over_budget = 0;
  };

  explicit TileScheduler(Setup setup);

  // The next pair with both meshes held, or nothing when every pair is handed out (or `cancel`).
  std::optional<Assignment> next(const std::atomic<bool>* cancel);
  // The pair is done; the tile's number when it was that tile's last pair.
  std::optional<std::size_t> finish(std::size_t work_index);
  Stats stats() const;

 private:
  enum class Held : std::uint8_t { kAbsent, kReading, kHeld, kFailed };
  std::uint32_t mesh_of(std::uint32_t object) const { return setup_.mesh_of.empty() ? object : setup_.mesh_of[object]; }
  // Admits tiles_[next_tile_] (the lock held on entry and on return; released while reading).
  void admit(std::unique_lock<std::mutex>& lock);
  // Lets go of held meshes no running tile uses (not those of tile k), farthest next use first,
  // until `excess` bytes are freed or none is left.
  void let_go(std::uint64_t excess, std::size_t k);

  Setup setup_;
  std::vector<std::vector<std::uint32_t>> tile_meshes_;   // per admitted-order tile: the meshes its pairs use
  std::vector<std::vector<std::size_t>> mesh_tiles_;      // per mesh: the admitted-order tiles using it, ascending
  std::vector<std::size_t> tile_of_work_;                 // work index -> admitted-order tile
  std::vector<std::size_t> pairs_left_;                   // per admitted-order tile
  std::vector<std::size_t> uses_left_;                    // per mesh: tiles not yet finished that use it
  std::vector<std::size_t> open_uses_;                    // per mesh: admitted, unfinished tiles that use it
  std::vector<Held> held_;
  std::vector<std::shared_ptr<const MeshBvh>> meshes_;
  std::vector<std::string> errors_;
  std::vector<std::size_t> ready_;                        // work indices of admitted tiles, handed out from the front
  std::size_t ready_at_ = 0;
  std::size_t next_tile_ = 0, tiles_reading_ = 0, tiles_open_ = 0;
  std::uint64_t held_bytes_ = 0;
  Stats stats_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
};

}  // namespace gk::engine
