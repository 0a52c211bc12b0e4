// An audit as a client asks for it, checked field by field, with the defaults filled in.
#pragma once

#include "engine/audits/scene_audit.h"

namespace gk::engine {

inline constexpr double kDefaultAuditTileMm = 50000.0;  // tile_mm = 0 means this
inline constexpr int kMaxAuditThreads = 64;

// `asked` as given (tile_mm 0: the default; threads 0: default_threads); an error names the field.
Result<AuditOptions> checked_audit_options(AuditOptions asked, int default_threads);

}  // namespace gk::engine
