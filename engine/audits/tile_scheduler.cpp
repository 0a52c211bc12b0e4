#include "engine/audits/tile_scheduler.h"

#include <algorithm>

namespace gk::engine {

TileScheduler::TileScheduler(Setup setup) : setup_(std::move(setup)) {
  const std::size_t n_meshes = setup_.in_memory.size();
  setup_.tiles.erase(std::remove_if(setup_.tiles.begin(), setup_.tiles.end(), [](const Tile& t) { return t.pairs.empty(); }),
                     setup_.tiles.end());
  tile_meshes_.resize(setup_.tiles.size());
  mesh_tiles_.resize(n_meshes);
  tile_of_work_.assign(setup_.work ? setup_.work->size() : 0, 0);
  pairs_left_.resize(setup_.tiles.size());
  uses_left_.assign(n_meshes, 0);
  open_uses_.assign(n_meshes, 0);
  held_.assign(n_meshes, Held::kAbsent);
  meshes_.resize(n_meshes);
  errors_.resize(n_meshes);
  setup_.bytes.resize(n_meshes, 0);
  setup_.file_bytes.resize(n_meshes, 0);
  std::vector<std::size_t> seen_in(n_meshes, static_cast<std::size_t>(-1));
  for (std::size_t k = 0; k < setup_.tiles.size(); ++k) {
    pairs_left_[k] = setup_.tiles[k].pairs.size();
    for (std::size_t i : setup_.tiles[k].pairs) {
      tile_of_work_[i] = k;
      for (std::uint32_t o : {(*setup_.work)[i].first, (*setup_.work)[i].second}) {
        const std::uint32_t m = mesh_of(o);
        if (seen_in[m] == k) continue;
        seen_in[m] = k;
        tile_meshes_[k].push_back(m);
        mesh_tiles_[m].push_back(k);
        ++uses_left_[m];
      }
    }
  }
  for (std::size_t m = 0; m < n_meshes; ++m)
    if (setup_.in_memory[m]) {
      meshes_[m] = setup_.in_memory[m];
      held_[m] = Held::kHeld;
    }
}

std::optional<TileScheduler::Assignment> TileScheduler::next(const std::atomic<bool>* cancel) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    if (cancel && cancel->load()) return std::nullopt;
    if (ready_at_ < ready_.size()) {
      Assignment s;
      s.work_index = ready_[ready_at_++];
      const std::uint32_t a = mesh_of((*setup_.work)[s.work_index].first), b = mesh_of((*setup_.work)[s.work_index].second);
      s.a = meshes_[a];
      s.b = meshes_[b];
      s.error = held_[a] == Held::kFailed ? errors_[a] : held_[b] == Held::kFailed ? errors_[b] : std::string();
      return s;
    }
    if (next_tile_ < setup_.tiles.size()) {
      auto need = [&] {
        std::uint64_t bytes = 0;
        for (std::uint32_t m : tile_meshes_[next_tile_])
          if (held_[m] == Held::kAbsent) bytes += setup_.bytes[m];
        return bytes;
      };
      const std::uint64_t budget = setup_.budget_bytes;
      if (budget != 0 && held_bytes_ + need() > budget) let_go(held_bytes_ + need() - budget, next_tile_);
      const bool fits = budget == 0 || held_bytes_ + need() <= budget;
      if (fits || tiles_open_ == 0) {
        if (!fits) ++stats_.tiles_over_budget;
        admit(lock);
        continue;
      }
    } else if (tiles_reading_ == 0) {
      return std::nullopt;  // every pair is handed out; the other threads finish theirs
    }
    changed_.wait(lock);
  }
}

void TileScheduler::let_go(std::uint64_t excess, std::size_t k) {
  std::vector<char> in_tile(meshes_.size(), 0);
  for (std::uint32_t m : tile_meshes_[k]) in_tile[m] = 1;
  // Candidates: held, read from disk, used by no running tile, not by the tile to admit.
  std::vector<std::pair<std::size_t, std::uint32_t>> candidates;  // (next use, mesh)
  for (std::uint32_t m = 0; m < meshes_.size(); ++m) {
    if (held_[m] != Held::kHeld || setup_.in_memory[m] || open_uses_[m] != 0 || in_tile[m]) continue;
    const auto& uses = mesh_tiles_[m];
    const auto at = std::lower_bound(uses.begin(), uses.end(), next_tile_);
    candidates.emplace_back(at == uses.end() ? static_cast<std::size_t>(-1) : *at, m);
  }
  std::sort(candidates.begin(), candidates.end(), std::greater<>());
  std::uint64_t freed = 0;
  for (const auto& [when, m] : candidates) {
    if (freed >= excess) break;
    meshes_[m].reset();
    held_[m] = Held::kAbsent;
    held_bytes_ -= setup_.bytes[m];
    freed += setup_.bytes[m];
    ++stats_.meshes_let_go;
  }
}

void TileScheduler::admit(std::unique_lock<std::mutex>& lock) {
  const std::size_t k = next_tile_++;
  ++tiles_open_;
  ++tiles_reading_;
  std::vector<std::uint32_t> mine;
  for (std::uint32_t m : tile_meshes_[k]) {
    ++open_uses_[m];
    if (held_[m] == Held::kAbsent) {
      held_[m] = Held::kReading;
      held_bytes_ += setup_.bytes[m];
      mine.push_back(m);
    }
  }
  stats_.peak_held_bytes = std::max(stats_.peak_held_bytes, held_bytes_);
  std::vector<Result<std::shared_ptr<const MeshBvh>>> read;
  read.reserve(mine.size());
  lock.unlock();
  for (std::uint32_t m : mine) read.push_back(setup_.loader(m));
  lock.lock();
  for (std::size_t j = 0; j < mine.size(); ++j) {
    const std::uint32_t m = mine[j];
    if (read[j].ok()) {
      meshes_[m] = read[j].value();
      held_[m] = Held::kHeld;
      stats_.bytes_read += setup_.file_bytes[m];
      ++stats_.meshes_read;
    } else {
      errors_[m] = read[j].error().to_string();
      held_[m] = Held::kFailed;
      held_bytes_ -= setup_.bytes[m];
    }
  }
  changed_.notify_all();
  // Some of this tile's meshes may be read by another thread for its own tile.
  changed_.wait(lock, [&] {
    return std::none_of(tile_meshes_[k].begin(), tile_meshes_[k].end(), [&](std::uint32_t m) { return held_[m] == Held::kReading; });
  });
  ready_.insert(ready_.end(), setup_.tiles[k].pairs.begin(), setup_.tiles[k].pairs.end());
  --tiles_reading_;
  changed_.notify_all();
}

std::optional<std::size_t> TileScheduler::finish(std::size_t work_index) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::size_t k = tile_of_work_[work_index];
  if (--pairs_left_[k] != 0) return std::nullopt;
  --tiles_open_;
  for (std::uint32_t m : tile_meshes_[k]) {
    --open_uses_[m];
    if (--uses_left_[m] != 0 || setup_.in_memory[m]) continue;
    if (held_[m] == Held::kHeld) {
      meshes_[m].reset();
      held_bytes_ -= setup_.bytes[m];
      held_[m] = Held::kAbsent;
    }
  }
  changed_.notify_all();
  return setup_.tiles[k].id;
}

TileScheduler::Stats TileScheduler::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace gk::engine
