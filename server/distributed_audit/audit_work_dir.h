// The files of a distributed audit's work directory, shared by the driver (gatekeeper-audit) and
// the daemon that hands it an audit (server/audit_handoff):
//   job.json          the scene's snapshot and the audit's options (written by the daemon; the
//                     driver audits exactly that snapshot, not the scene as it is later)
//   audit.fingerprint what the tiles were computed from: another audit's directory is refused
//   tile-N.bin        tile N's clashes, with a header naming the audit, the tile and the length
// Files are written whole, synced and renamed into place: a reader never sees half of one.
#pragma once

#include "engine/audits/scene_audit.h"
#include "engine/scenes/scene_store.h"
#include "kernel/core/status.h"

#include <string>
#include <vector>

namespace gk::server {

bool write_whole(const std::string& path, const std::string& bytes);
std::string read_whole(const std::string& path);

// The fingerprint of a scene snapshot and the options that shape answers or tiles (hex).
std::string audit_fingerprint(const engine::SceneRecord& scene, const engine::AuditOptions& options);

std::string tile_path(const std::string& work_dir, std::size_t tile);
std::string tile_file_bytes(const std::string& fingerprint, std::size_t tile, const std::vector<engine::PairClash>& clashes);
// Tile `tile` as written for the audit `fingerprint`; an error when the file is another audit's,
// another tile's, cut short or damaged.
Result<std::vector<engine::PairClash>> read_tile_file(const std::string& path, const std::string& fingerprint, std::size_t tile);

// The job file: the snapshot's objects and the options (clearance, tile, depth, volume, region
// merge, contacts kept, rules, threads).
struct AuditJobFile {
  engine::SceneRecord scene;
  engine::AuditOptions options;
};
std::string job_file_text(const engine::SceneRecord& scene, const engine::AuditOptions& options);
Result<AuditJobFile> read_job_file(const std::string& path);

}  // namespace gk::server
