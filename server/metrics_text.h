// The daemon's metrics in Prometheus' text exposition format (version 0.0.4): call counts and
// latency histograms per method, work queue depths, cache hits and memory. Rendering only; the
// numbers are gathered by GatekeeperService::metrics() and served by server/metrics_endpoint.h.
#pragma once

#include "engine/parts/part_registry.h"
#include "engine/steps/step_answers.h"
#include "server/process_memory.h"
#include "server/rpc_stats.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gk::server {

struct PoolLoad {
  std::string pool;          // its role, e.g. "validation", "clearance"
  std::size_t queued = 0;    // jobs waiting for a worker
  std::size_t capacity = 0;  // queued beyond which calls are refused (RESOURCE_EXHAUSTED)
  std::size_t threads = 0;
};

struct MetricsSnapshot {
  std::vector<RpcStats::Summary> rpcs;
  std::vector<PoolLoad> pools;
  engine::StepAnswers::CacheStats step_cache;
  engine::PartRegistry::MemoryStats parts;
  std::uint64_t parts_stored = 0;
  std::size_t audits_running = 0, audits_in_memory = 0;
  std::size_t uploads_open = 0;
  ProcessMemory process;
};

std::string prometheus_text(const MetricsSnapshot& metrics);

}  // namespace gk::server
