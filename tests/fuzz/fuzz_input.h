// What the fuzz targets share: the input split into a selector byte and the rest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace gk::fuzz {

// The first byte picks one of `count` variants (a format, a reader); the rest is the payload.
struct SelectedInput {
  std::size_t variant = 0;
  std::string payload;
};

inline SelectedInput select(const std::uint8_t* data, std::size_t size, std::size_t count) {
  SelectedInput in;
  if (size == 0) return in;
  in.variant = data[0] % count;
  in.payload.assign(reinterpret_cast<const char*>(data + 1), size - 1);
  return in;
}

}  // namespace gk::fuzz
