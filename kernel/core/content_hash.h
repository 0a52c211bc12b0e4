// The project's one content hash: XXH3, 128 bits (Debian's libxxhash), over the bytes it is given
// in order. It names what a cache keeps (a mesh's BVH on disk, a machine step's prepared bodies
// and answers): two different contents share a key with probability about 2^-128 per pair.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <string>

namespace gk {

struct Hash128 {
  std::uint64_t low = 0, high = 0;
  bool operator==(const Hash128& o) const { return low == o.low && high == o.high; }
  bool operator!=(const Hash128& o) const { return !(*this == o); }
  std::string hex() const {
    char text[33];
    std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(high), static_cast<unsigned long long>(low));
    return text;
  }
  // For hash maps keyed by a content hash.
  struct Std {
    std::size_t operator()(const Hash128& h) const { return static_cast<std::size_t>(h.low ^ (h.high * 0x9E3779B97F4A7C15ull)); }
  };
};

// 64 bits of XXH3 over a few bytes, for hash tables (not a content key).
std::uint64_t hash_bytes64(const void* data, std::size_t size);

class ContentHash {
 public:
  ContentHash();
  ~ContentHash();
  ContentHash(const ContentHash&) = delete;
  ContentHash& operator=(const ContentHash&) = delete;
  ContentHash& add_bytes(const void* data, std::size_t size);
  ContentHash& add(double value) { return add_bytes(&value, sizeof value); }
  ContentHash& add(std::uint64_t value) { return add_bytes(&value, sizeof value); }
  ContentHash& add(const Hash128& h) { return add(h.low).add(h.high); }
  ContentHash& add(std::initializer_list<double> values) {
    for (double v : values) add(v);
    return *this;
  }
  Hash128 value() const;

 private:
  struct State;  // libxxhash's streaming state (kept out of this header)
  std::unique_ptr<State> state_;
};

}  // namespace gk
