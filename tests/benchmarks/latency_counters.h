// Per-query latencies as Google Benchmark counters: mean, p10, median, p90, p99 and max in
// microseconds, and the number of queries.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace gk::bench {

inline void report_latencies(benchmark::State& state, std::vector<double> us) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  double total = 0.0;
  for (double x : us) total += x;
  state.counters["mean_us"] = total / static_cast<double>(us.size());
  state.counters["p10_us"] = us[us.size() / 10];
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["p90_us"] = us[us.size() * 9 / 10];
  state.counters["p99_us"] = us[us.size() * 99 / 100];
  state.counters["max_us"] = us.back();
  state.counters["queries"] = static_cast<double>(us.size());
}

}  // namespace gk::bench
