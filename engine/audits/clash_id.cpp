#include "engine/audits/clash_id.h"

#include "kernel/core/content_hash.h"

#include <cstdint>
#include <cstdio>

namespace gk::engine {

std::string clash_id(const std::string& scene_id, const std::string& object_a, const std::string& object_b) {
  const std::string& first = object_a < object_b ? object_a : object_b;
  const std::string& second = object_a < object_b ? object_b : object_a;
  static const char kDomain[] = "gatekeeper clash id 2";
  ContentHash hash;
  hash.add_bytes(kDomain, sizeof kDomain);
  // Lengths first: ("ab", "c") and ("a", "bc") must differ.
  hash.add(static_cast<std::uint64_t>(scene_id.size())).add_bytes(scene_id.data(), scene_id.size());
  hash.add(static_cast<std::uint64_t>(first.size())).add_bytes(first.data(), first.size());
  hash.add(static_cast<std::uint64_t>(second.size())).add_bytes(second.data(), second.size());
  const Hash128 h = hash.value();
  // Version 8 in the 13th hex digit, variant 10 in the 17th.
  const std::uint64_t high = (h.high & 0xFFFFFFFFFFFF0FFFull) | 0x0000000000008000ull;
  const std::uint64_t low = (h.low & 0x3FFFFFFFFFFFFFFFull) | 0x8000000000000000ull;
  char text[37];
  std::snprintf(text, sizeof text, "%08llx-%04llx-%04llx-%04llx-%012llx", static_cast<unsigned long long>(high >> 32),
                static_cast<unsigned long long>((high >> 16) & 0xFFFF), static_cast<unsigned long long>(high & 0xFFFF),
                static_cast<unsigned long long>(low >> 48), static_cast<unsigned long long>(low & 0xFFFFFFFFFFFFull));
  return text;
}

}  // namespace gk::engine
