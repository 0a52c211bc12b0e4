#include "server/metrics_text.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace gk::server {
namespace {

// Label values are the service's own method and pool names; escaped anyway as the format asks.
std::string label_value(const std::string& v) {
  std::string out;
  for (const char c : v) {
    if (c == '\\') out += "\\\\";
    else if (c == '"') out += "\\\"";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string number(double v) {
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  if (std::isnan(v)) return "NaN";
  // The shortest text that reads back as v (0.001024, not 0.0010239999999999999).
  char out[40];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(out, sizeof out, "%.*g", digits, v);
    if (std::strtod(out, nullptr) == v) break;
  }
  return out;
}

class Writer {
 public:
  void family(const char* name, const char* type, const char* help) {
    text_ += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
  }
  void sample(const std::string& name, const std::string& labels, double value) {
    text_ += name;
    if (!labels.empty()) text_ += "{" + labels + "}";
    text_ += " " + number(value) + "\n";
  }
  // A family of one unlabelled sample.
  template <typename Number>
  void single(const char* name, const char* type, const char* help, Number value) {
    family(name, type, help);
    sample(name, "", static_cast<double>(value));
  }
  std::string take() { return std::move(text_); }

 private:
  std::string text_;
};

std::string label(const char* key, const std::string& value) { return std::string(key) + "=\"" + label_value(value) + "\""; }

}  // namespace

std::string prometheus_text(const MetricsSnapshot& m) {
  Writer w;
  w.family("gatekeeper_rpc_calls_total", "counter", "Calls answered, per method (a drag frame counts as DragObject.move).");
  for (const auto& r : m.rpcs) w.sample("gatekeeper_rpc_calls_total", label("method", r.method), static_cast<double>(r.calls));
  w.family("gatekeeper_rpc_errors_total", "counter", "Calls answered with a status other than OK, per method.");
  for (const auto& r : m.rpcs) w.sample("gatekeeper_rpc_errors_total", label("method", r.method), static_cast<double>(r.errors));
  w.family("gatekeeper_rpc_latency_seconds", "histogram", "Time from a call's arrival to its answer, per method.");
  for (const auto& r : m.rpcs) {
    const std::string method = label("method", r.method);
    std::uint64_t cumulative = 0;
    for (std::size_t b = 0; b < RpcStats::kBuckets; ++b) {
      cumulative += r.histogram[b];
      const double le = b < RpcStats::kBounded ? RpcStats::bucket_bound_us(b) * 1e-6 : INFINITY;
      w.sample("gatekeeper_rpc_latency_seconds_bucket", method + "," + label("le", number(le)), static_cast<double>(cumulative));
    }
    w.sample("gatekeeper_rpc_latency_seconds_sum", method, r.total_us * 1e-6);
    w.sample("gatekeeper_rpc_latency_seconds_count", method, static_cast<double>(cumulative));
  }
  const auto per_pool = [&](const char* name, const char* help, std::size_t PoolLoad::*field) {
    w.family(name, "gauge", help);
    for (const auto& p : m.pools) w.sample(name, label("pool", p.pool), static_cast<double>(p.*field));
  };
  per_pool("gatekeeper_queue_depth", "Jobs waiting for a worker, per work pool.", &PoolLoad::queued);
  per_pool("gatekeeper_queue_capacity", "Waiting jobs beyond which calls are refused (RESOURCE_EXHAUSTED), per pool.",
           &PoolLoad::capacity);
  per_pool("gatekeeper_pool_threads", "Worker threads, per work pool.", &PoolLoad::threads);

  w.single("gatekeeper_step_cache_hits_total", "counter", "ValidateStep questions answered from the answer cache.", m.step_cache.hits);
  w.single("gatekeeper_step_cache_misses_total", "counter", "ValidateStep cache lookups that found no answer.", m.step_cache.misses);
  w.single("gatekeeper_step_cache_entries", "gauge", "Answers in the ValidateStep cache.", m.step_cache.entries);

  w.single("gatekeeper_parts_stored", "gauge", "Uploaded parts in the store.", m.parts_stored);
  w.single("gatekeeper_parts_in_memory", "gauge", "Uploaded parts loaded (mesh and tree).", m.parts.parts);
  w.single("gatekeeper_part_memory_bytes", "gauge", "Estimated memory of the loaded parts.", m.parts.bytes);
  w.single("gatekeeper_part_memory_budget_bytes", "gauge", "Part memory beyond which the least recently used are dropped.", m.parts.budget_bytes);
  w.single("gatekeeper_part_loads_total", "counter", "Parts read from the store (a miss of the loaded parts).", m.parts.loads);
  w.single("gatekeeper_part_hits_total", "counter", "Part lookups answered from the loaded parts.", m.parts.hits);
  w.single("gatekeeper_parts_evicted_total", "counter", "Loaded parts dropped to stay within the budget.", m.parts.evicted);
  w.family("gatekeeper_bvh_cache_total", "counter", "Part trees by where they came from: the disk cache, built, or a cache file rejected.");
  w.sample("gatekeeper_bvh_cache_total", label("outcome", "loaded"), static_cast<double>(m.parts.bvh_cache.loaded));
  w.sample("gatekeeper_bvh_cache_total", label("outcome", "built"), static_cast<double>(m.parts.bvh_cache.built));
  w.sample("gatekeeper_bvh_cache_total", label("outcome", "rejected"), static_cast<double>(m.parts.bvh_cache.rejected));
  w.sample("gatekeeper_bvh_cache_total", label("outcome", "write_failed"), static_cast<double>(m.parts.bvh_cache.write_failures));

  w.single("gatekeeper_audits_running", "gauge", "Audit jobs started and not ended.", m.audits_running);
  w.single("gatekeeper_audits_in_memory", "gauge", "Audit jobs held in memory (running and recently ended).", m.audits_in_memory);
  w.single("gatekeeper_uploads_open", "gauge", "Upload streams open.", m.uploads_open);

  if (m.process.read) {
    w.single("process_resident_memory_bytes", "gauge", "Resident memory size in bytes.", m.process.resident_bytes);
    w.single("process_resident_memory_max_bytes", "gauge", "Peak resident memory size in bytes.", m.process.peak_resident_bytes);
    w.single("process_virtual_memory_bytes", "gauge", "Virtual memory size in bytes.", m.process.virtual_bytes);
  }
  w.single("process_cpu_seconds_total", "counter", "User and system CPU time spent in seconds.", m.process.cpu_seconds);
  return w.take();
}

}  // namespace gk::server
