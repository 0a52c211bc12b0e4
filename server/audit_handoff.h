// Hands a large audit to a distributed driver (gatekeeper-audit under mpiexec, or any command
// taking its options) and follows it as if it ran here: the job's snapshot and options go to a
// job file in a work directory under the data directory; the command runs in its own process
// group; each tile the driver finishes is read back as it appears (progress, clashes, the
// daemon's own checkpoint); a cancel or a stop ends the driver; the result is what audit_scene
// gives (the tiles' clashes in pair order), so the job's exact-face decisions, archive and
// statuses follow as for any audit. The work directory is kept per job id: a resumed job's
// driver skips the tiles it already wrote.
#pragma once

#include "engine/audits/audit_job.h"

#include <string>

namespace gk::server {

struct AuditHandoffOptions {
  std::string command;   // e.g. "mpiexec -n 4 --hostfile hosts /usr/bin/gatekeeper-audit"
  std::string data_dir;  // the daemon's: shared with the driver's processes
};

engine::AuditRunner make_audit_handoff(AuditHandoffOptions options);

}  // namespace gk::server
