#include "engine/audits/tile_scheduler.h"

#include <algorithm>

namespace gk::engine {

TileScheduler::TileScheduler(Setup setup) : setup_(std::move(setup)) {
  const std::size_t n_objects = setup_.in_memory.size();
  setup_.tiles.erase(std::remove_if(setup_.tiles.begin(), setup_.tiles.end(), [](const Tile& t) { return t.pairs.empty(); }),
                     setup_.tiles.end());
  tile_objects_.resize(setup_.tiles.size());
  tile_of_work_.assign(setup_.work ? setup_.work->size() : 0, 0);
  pairs_left_.resize(setup_.tiles.size());
  uses_left_.assign(n_objects, 0);
  held_.assign(n_objects, Held::kAbsent);
  meshes_.resize(n_objects);
  errors_.resize(n_objects);
  setup_.bytes.resize(n_objects, 0);
  setup_.file_bytes.resize(n_objects, 0);
  std::vector<std::size_t> seen_in(n_objects, static_cast<std::size_t>(-1));
  for (std::size_t k = 0; k < setup_.tiles.size(); ++k) {
    pairs_left_[k] = setup_.tiles[k].pairs.size();
    for (std::size_t i : setup_.tiles[k].pairs) {
      tile_of_work_[i] = k;
      for (std::uint32_t o : {(*setup_.work)[i].first, (*setup_.work)[i].second}) {
        if (seen_in[o] == k) continue;
        seen_in[o] = k;
        tile_objects_[k].push_back(o);
        ++uses_left_[o];
      }
    }
  }
  for (std::size_t o = 0; o < n_objects; ++o)
    if (setup_.in_memory[o]) {
      meshes_[o] = setup_.in_memory[o];
      held_[o] = Held::kHeld;
    }
}

std::optional<TileScheduler::Assignment> TileScheduler::next(const std::atomic<bool>* cancel) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    if (cancel && cancel->load()) return std::nullopt;
    if (ready_at_ < ready_.size()) {
      Assignment s;
      s.work_index = ready_[ready_at_++];
      const auto [a, b] = (*setup_.work)[s.work_index];
      s.a = meshes_[a];
      s.b = meshes_[b];
      s.error = held_[a] == Held::kFailed ? errors_[a] : held_[b] == Held::kFailed ? errors_[b] : std::string();
      return s;
    }
    if (next_tile_ < setup_.tiles.size()) {
      std::uint64_t need = 0;
      for (std::uint32_t o : tile_objects_[next_tile_])
        if (held_[o] == Held::kAbsent) need += setup_.bytes[o];
      if (tiles_open_ == 0 || setup_.budget_bytes == 0 || held_bytes_ + need <= setup_.budget_bytes) {
        if (setup_.budget_bytes != 0 && held_bytes_ + need > setup_.budget_bytes) ++stats_.tiles_over_budget;
        admit(lock);
        continue;
      }
    } else if (tiles_reading_ == 0) {
      return std::nullopt;  // every pair is handed out; the other threads finish theirs
    }
    changed_.wait(lock);
  }
}

void TileScheduler::admit(std::unique_lock<std::mutex>& lock) {
  const std::size_t k = next_tile_++;
  ++tiles_open_;
  ++tiles_reading_;
  std::vector<std::uint32_t> mine;
  for (std::uint32_t o : tile_objects_[k])
    if (held_[o] == Held::kAbsent) {
      held_[o] = Held::kReading;
      held_bytes_ += setup_.bytes[o];
      mine.push_back(o);
    }
  stats_.peak_held_bytes = std::max(stats_.peak_held_bytes, held_bytes_);
  std::vector<Result<std::shared_ptr<const MeshBvh>>> read;
  read.reserve(mine.size());
  lock.unlock();
  for (std::uint32_t o : mine) read.push_back(setup_.loader(o));
  lock.lock();
  for (std::size_t j = 0; j < mine.size(); ++j) {
    const std::uint32_t o = mine[j];
    if (read[j].ok()) {
      meshes_[o] = read[j].value();
      held_[o] = Held::kHeld;
      stats_.bytes_read += setup_.file_bytes[o];
      ++stats_.meshes_read;
    } else {
      errors_[o] = read[j].error().to_string();
      held_[o] = Held::kFailed;
      held_bytes_ -= setup_.bytes[o];
    }
  }
  changed_.notify_all();
  // Some of this tile's meshes may be read by another thread for its own tile.
  changed_.wait(lock, [&] {
    return std::none_of(tile_objects_[k].begin(), tile_objects_[k].end(), [&](std::uint32_t o) { return held_[o] == Held::kReading; });
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
  for (std::uint32_t o : tile_objects_[k]) {
    if (--uses_left_[o] != 0 || setup_.in_memory[o]) continue;
    if (held_[o] == Held::kHeld) {
      meshes_[o].reset();
      held_bytes_ -= setup_.bytes[o];
      held_[o] = Held::kAbsent;
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
