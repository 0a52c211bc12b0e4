#include "engine/audits/audit_request.h"

#include <algorithm>
#include <cmath>

namespace gk::engine {

Result<AuditOptions> checked_audit_options(AuditOptions asked, int default_threads) {
  if (!std::isfinite(asked.clearance_mm) || asked.clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be a finite distance >= 0");
  if (!std::isfinite(asked.tile_mm) || asked.tile_mm < 0.0) return invalid_argument("tile_mm", "must be a finite length >= 0");
  if (asked.threads < 0 || asked.threads > kMaxAuditThreads) return invalid_argument("threads", "at most 64");
  if (asked.tile_mm == 0.0) asked.tile_mm = kDefaultAuditTileMm;
  if (asked.threads == 0) asked.threads = std::max(1, default_threads);
  for (std::size_t i = 0; i < asked.rules.size(); ++i) {
    const std::string field = "rules[" + std::to_string(i) + "]";
    if (asked.rules[i].category_a.empty()) return invalid_argument(field + ".category_a", "is empty (use \"*\" for any)");
    if (asked.rules[i].category_b.empty()) return invalid_argument(field + ".category_b", "is empty (use \"*\" for any)");
  }
  return asked;
}

}  // namespace gk::engine
