// Where a running audit keeps what it has finished, tile by tile, so that a daemon killed in the
// middle of a nightly audit (kill -9, power loss, or a stop) resumes it when it starts again
// instead of starting over (the daemon keeps them in its database: server/audit_checkpoints).
// The engine only asks.
#pragma once

#include "engine/audits/scene_audit.h"
#include "engine/scenes/scene_store.h"

#include <map>
#include <string>
#include <vector>

namespace gk::engine {

// An audit that had not ended when the daemon stopped: what it audits, how, and its finished tiles.
struct UnfinishedAudit {
  std::string job_id;
  SceneRecord scene;        // the snapshot audited
  AuditOptions options;     // the answer options, tiles and threads (no callbacks)
  std::string baseline_job_id;  // a re-audit's baseline (finished, archived), or empty
  std::map<std::size_t, std::vector<PairClash>> tiles;  // finished tiles and their clashes
  bool cancelled = false;   // a client cancelled it before the daemon stopped: it ends CANCELLED
  // Its record could not be read (damaged): it ends FAILED with this message. Tiles that cannot be
  // read are simply left out (computed again).
  std::string unreadable;
};

class AuditCheckpoints {
 public:
  virtual ~AuditCheckpoints() = default;
  // A job begins: its snapshot and options are kept until forget().
  virtual Result<bool> begin(const std::string& job_id, const SceneRecord& scene, const AuditOptions& options,
                             const std::string& baseline_job_id) = 0;
  // One tile of the job is finished, with these clashes (kernel answers; object indices are the
  // snapshot's objects in id order).
  virtual Result<bool> tile_done(const std::string& job_id, std::size_t tile, const std::vector<PairClash>& clashes) = 0;
  // A client cancelled the job: after a stop it ends CANCELLED instead of resuming.
  virtual Result<bool> cancelled(const std::string& job_id) = 0;
  // The job ended and is archived: its checkpoint goes.
  virtual Result<bool> forget(const std::string& job_id) = 0;
  // Every job begun and not forgotten, oldest first.
  virtual Result<std::vector<UnfinishedAudit>> unfinished() const = 0;
};

}  // namespace gk::engine
