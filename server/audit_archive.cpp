#include "server/audit_archive.h"

#include "audit_archive.pb.h"
#include "server/audit_report.h"
#include "server/proto_convert.h"

#include <sqlite3.h>

namespace gk::server {

Result<std::unique_ptr<AuditArchive>> AuditArchive::open(const std::string& directory) {
  std::unique_ptr<AuditArchive> archive(new AuditArchive());
  if (sqlite3_open((directory + "/gatekeeper.sqlite").c_str(), &archive->db_) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot open the audit database in " + directory};
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA busy_timeout=5000;"
      "CREATE TABLE IF NOT EXISTS audits (id TEXT PRIMARY KEY, scene_id TEXT, data BLOB);";
  if (sqlite3_exec(archive->db_, schema, nullptr, nullptr, nullptr) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot prepare the audit table"};
  return archive;
}

AuditArchive::~AuditArchive() {
  if (db_) sqlite3_close(db_);
}

Result<bool> AuditArchive::save(const std::string& job_id, const AuditJob& job, const AuditSnapshot& snapshot) {
  ::gatekeeper::server::ArchivedAudit archived;
  archived.set_job_id(job_id);
  progress_to_proto(job_id, snapshot, archived.mutable_report()->mutable_progress());
  report_to_proto(snapshot, job.scene().id, archived.mutable_report());
  scene_to_proto(job.scene(), archived.mutable_scene());
  for (const AuditedObject& o : job.objects()) {
    auto* a = archived.add_objects();
    a->set_id(o.id);
    a->set_name(o.name);
    a->set_category(o.category);
    to_proto(o.box.min, a->mutable_box_min());
    to_proto(o.box.max, a->mutable_box_max());
  }
  for (const std::string& option : job.answer_options()) archived.add_answer_options(option);
  const std::string bytes = archived.SerializeAsString();
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "INSERT OR REPLACE INTO audits (id, scene_id, data) VALUES (?, ?, ?)", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, job_id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 2, job.scene().id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_blob(stmt, 3, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return Error{ErrorCode::kInternal, "job_id", "cannot store the audit"};
  return true;
}

namespace {

// A stored row back into an ended job; null when it cannot be read.
std::shared_ptr<AuditJob> decode(const void* blob, int size) {
  ::gatekeeper::server::ArchivedAudit archived;
  if (!blob || !archived.ParseFromArray(blob, size)) return nullptr;
  auto scene = scene_from_proto(archived.scene());
  if (!scene.ok()) return nullptr;
  std::vector<AuditedObject> objects;
  for (const auto& o : archived.objects()) {
    const Vec3 lo(o.box_min().x_mm(), o.box_min().y_mm(), o.box_min().z_mm());
    const Vec3 hi(o.box_max().x_mm(), o.box_max().y_mm(), o.box_max().z_mm());
    objects.push_back({o.id(), o.name(), o.category(), Aabb{lo, hi}});
  }
  return AuditJob::restored(std::move(scene).value(), snapshot_from_report(archived.report()), std::move(objects),
                            {archived.answer_options().begin(), archived.answer_options().end()});
}

}  // namespace

Result<std::shared_ptr<AuditJob>> AuditArchive::load(const std::string& job_id) const {
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "SELECT data FROM audits WHERE id = ?", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, job_id.c_str(), -1, SQLITE_TRANSIENT);
  std::shared_ptr<AuditJob> job;
  bool found = false;
  if (sqlite3_step(stmt) == SQLITE_ROW) {
    found = true;
    job = decode(sqlite3_column_blob(stmt, 0), sqlite3_column_bytes(stmt, 0));
  }
  sqlite3_finalize(stmt);
  if (!found) return Error{ErrorCode::kNotFound, "job_id", "no audit job '" + job_id + "'"};
  if (!job) return Error{ErrorCode::kInternal, "job_id", "the archived audit '" + job_id + "' cannot be read"};
  return job;
}

}  // namespace gk::server
