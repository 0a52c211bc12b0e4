// Per-RPC call counts, error counts, latency percentiles (over the last 4096 calls) and a latency
// histogram over all calls (what GetServerInfo and /metrics report).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace gk::server {

class RpcStats {
 public:
  // Bucket i < kBounded counts calls of at most 2^i microseconds (and more than 2^(i-1)); the
  // last bucket counts the longer ones (beyond 2^24 us, about 16.8 s).
  static constexpr std::size_t kBounded = 25;
  static constexpr std::size_t kBuckets = kBounded + 1;
  static double bucket_bound_us(std::size_t i) { return static_cast<double>(1ull << i); }
  struct Summary {
    std::string method;
    std::uint64_t calls = 0, errors = 0;
    double p50_us = 0.0, p99_us = 0.0;
    double total_us = 0.0;  // over all calls
    std::array<std::uint64_t, kBuckets> histogram{};
  };

  void record(const std::string& method, double micros, bool error) {
    std::lock_guard<std::mutex> lock(mutex_);
    Entry& e = entries_[method];
    ++e.calls;
    if (error) ++e.errors;
    e.recent[e.next++ % e.recent.size()] = micros;
    e.total_us += micros;
    std::size_t bucket = 0;
    while (bucket < kBounded && bucket_bound_us(bucket) < micros) ++bucket;
    ++e.histogram[bucket];
  }

  std::vector<Summary> summaries() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Summary> out;
    for (const auto& [method, e] : entries_) {
      const std::size_t n = std::min<std::size_t>(e.calls, e.recent.size());
      std::vector<double> sorted(e.recent.begin(), e.recent.begin() + static_cast<long>(n));
      std::sort(sorted.begin(), sorted.end());
      Summary s{method, e.calls, e.errors, 0.0, 0.0, e.total_us, e.histogram};
      if (n > 0) {
        s.p50_us = sorted[n / 2];
        s.p99_us = sorted[std::min(n - 1, n * 99 / 100)];
      }
      out.push_back(s);
    }
    return out;
  }

 private:
  struct Entry {
    std::uint64_t calls = 0, errors = 0;
    std::array<double, 4096> recent{};
    std::uint64_t next = 0;
    double total_us = 0.0;
    std::array<std::uint64_t, kBuckets> histogram{};
  };
  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;
};

}  // namespace gk::server
