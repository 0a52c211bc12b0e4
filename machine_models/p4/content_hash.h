// FNV-1a over the bytes of doubles: stable, order-sensitive keys for the memo caches.
#pragma once

#include <cstdint>
#include <cstring>
#include <initializer_list>

namespace gk::p4 {

class ContentHash {
 public:
  ContentHash& add(double value) {
    unsigned char bytes[sizeof value];
    std::memcpy(bytes, &value, sizeof value);
    for (unsigned char b : bytes) hash_ = (hash_ ^ b) * 1099511628211ull;
    return *this;
  }
  ContentHash& add(std::initializer_list<double> values) {
    for (double v : values) add(v);
    return *this;
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 1469598103934665603ull;
};

}  // namespace gk::p4
