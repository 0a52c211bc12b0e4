#include "kernel/core/content_hash.h"

#include <xxhash.h>

#include <new>

namespace gk {

std::uint64_t hash_bytes64(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

struct ContentHash::State {
  XXH3_state_t* xxh = XXH3_createState();
  ~State() { XXH3_freeState(xxh); }
};

ContentHash::ContentHash() : state_(std::make_unique<State>()) {
  if (!state_->xxh) throw std::bad_alloc();
  XXH3_128bits_reset(state_->xxh);
}

ContentHash::~ContentHash() = default;

ContentHash& ContentHash::add_bytes(const void* data, std::size_t size) {
  XXH3_128bits_update(state_->xxh, data, size);
  return *this;
}

Hash128 ContentHash::value() const {
  const XXH128_hash_t h = XXH3_128bits_digest(state_->xxh);
  return {h.low64, h.high64};
}

}  // namespace gk
