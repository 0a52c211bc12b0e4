#include "server/clash_status_store.h"

#include <sqlite3.h>

#include <map>
#include <set>

namespace gk::server {
namespace {

using engine::ClashStatus;
using engine::ClashStatusRecord;

Error storage_error(const std::string& what) { return Error{ErrorCode::kInternal, "clash_status", what}; }

// A prepared statement, finalized on every path.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) { sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr); }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  bool ok() const { return stmt_ != nullptr; }
  Statement& text(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& integer(int i, long long v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  int step() { return sqlite3_step(stmt_); }
  std::string column_text(int i) const {
    const unsigned char* t = sqlite3_column_text(stmt_, i);
    return t ? std::string(reinterpret_cast<const char*>(t), static_cast<std::size_t>(sqlite3_column_bytes(stmt_, i))) : "";
  }
  long long column_integer(int i) const { return sqlite3_column_int64(stmt_, i); }

 private:
  sqlite3_stmt* stmt_ = nullptr;
};

// BEGIN IMMEDIATE (the write lock first, waiting up to busy_timeout: a read turned into a write
// fails at once when another connection wrote in between), rolled back unless committed.
class WriteTransaction {
 public:
  explicit WriteTransaction(sqlite3* db) : db_(db), begun_(sqlite3_exec(db, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) == SQLITE_OK) {}
  ~WriteTransaction() {
    if (begun_ && !committed_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  WriteTransaction(const WriteTransaction&) = delete;
  WriteTransaction& operator=(const WriteTransaction&) = delete;
  bool begun() const { return begun_; }
  bool commit() { return committed_ = sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr) == SQLITE_OK; }

 private:
  sqlite3* db_;
  bool begun_;
  bool committed_ = false;
};

constexpr const char* kColumns = "scene_id, clash_id, object_a, object_b, status, set_by_user, first_job, last_job";

// Stored as the enumeration's number; an unknown number (a damaged row) reads as ACTIVE, which
// keeps the clash in view rather than hiding it.
ClashStatus status_of(long long v) {
  return v >= 0 && v <= static_cast<long long>(ClashStatus::kResolved) ? static_cast<ClashStatus>(v) : ClashStatus::kActive;
}

ClashStatusRecord record_of(const Statement& s) {
  ClashStatusRecord r;
  r.scene_id = s.column_text(0);
  r.clash_id = s.column_text(1);
  r.object_a = s.column_text(2);
  r.object_b = s.column_text(3);
  r.status = status_of(s.column_integer(4));
  r.set_by_user = s.column_integer(5) != 0;
  r.first_job_id = s.column_text(6);
  r.last_job_id = s.column_text(7);
  return r;
}

Result<std::vector<ClashStatusRecord>> rows_of(sqlite3* db, const std::string& scene_id) {
  Statement s(db, (std::string("SELECT ") + kColumns + " FROM clash_statuses WHERE scene_id = ? ORDER BY clash_id").c_str());
  if (!s.ok()) return storage_error("cannot read the clash statuses");
  s.text(1, scene_id);
  std::vector<ClashStatusRecord> out;
  int rc;
  while ((rc = s.step()) == SQLITE_ROW) out.push_back(record_of(s));
  if (rc != SQLITE_DONE) return storage_error("cannot read the clash statuses");
  return out;
}

Result<bool> write_row(sqlite3* db, const ClashStatusRecord& r) {
  Statement s(db, (std::string("INSERT OR REPLACE INTO clash_statuses (") + kColumns + ") VALUES (?, ?, ?, ?, ?, ?, ?, ?)").c_str());
  if (!s.ok()) return storage_error("cannot write a clash status");
  s.text(1, r.scene_id).text(2, r.clash_id).text(3, r.object_a).text(4, r.object_b);
  s.integer(5, static_cast<long long>(r.status)).integer(6, r.set_by_user ? 1 : 0).text(7, r.first_job_id).text(8, r.last_job_id);
  if (s.step() != SQLITE_DONE) return storage_error("cannot write a clash status");
  return true;
}

}  // namespace

Result<std::unique_ptr<ClashStatusStore>> ClashStatusStore::open(const std::string& directory) {
  std::unique_ptr<ClashStatusStore> store(new ClashStatusStore());
  if (sqlite3_open((directory + "/gatekeeper.sqlite").c_str(), &store->db_) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot open the clash status database in " + directory};
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA busy_timeout=5000;"
      "CREATE TABLE IF NOT EXISTS clash_statuses (scene_id TEXT, clash_id TEXT, object_a TEXT, object_b TEXT,"
      " status INTEGER, set_by_user INTEGER, first_job TEXT, last_job TEXT, PRIMARY KEY (scene_id, clash_id));";
  if (sqlite3_exec(store->db_, schema, nullptr, nullptr, nullptr) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot prepare the clash status table"};
  return store;
}

ClashStatusStore::~ClashStatusStore() {
  if (db_) sqlite3_close(db_);
}

Result<bool> ClashStatusStore::record_audit(const std::string& scene_id, const std::string& job_id,
                                            const std::vector<engine::FoundClash>& found) {
  std::lock_guard<std::mutex> lock(mutex_);
  WriteTransaction transaction(db_);
  if (!transaction.begun()) return storage_error("cannot begin the clash status transaction");
  auto rows = rows_of(db_, scene_id);
  if (!rows.ok()) return rows.error();
  std::map<std::string, ClashStatusRecord> known;
  for (ClashStatusRecord& r : rows.value()) known.emplace(r.clash_id, std::move(r));
  std::set<std::string> seen;
  for (const engine::FoundClash& f : found) {
    if (!seen.insert(f.clash_id).second) continue;
    auto it = known.find(f.clash_id);
    ClashStatusRecord r;
    if (it == known.end()) {
      r = {scene_id, f.clash_id, f.object_a, f.object_b, ClashStatus::kNew, false, job_id, job_id};
    } else {
      r = it->second;
      if (r.last_job_id != job_id && (r.status == ClashStatus::kNew || r.status == ClashStatus::kResolved)) {
        r.status = ClashStatus::kActive;
        r.set_by_user = false;
      }
      r.last_job_id = job_id;
    }
    if (auto w = write_row(db_, r); !w.ok()) return w.error();
  }
  for (const auto& [id, r] : known) {
    if (seen.count(id) || r.status == ClashStatus::kResolved) continue;
    ClashStatusRecord gone = r;
    gone.status = ClashStatus::kResolved;
    gone.set_by_user = false;
    if (auto w = write_row(db_, gone); !w.ok()) return w.error();
  }
  if (!transaction.commit()) return storage_error("cannot commit the clash statuses");
  return true;
}

Result<ClashStatusRecord> ClashStatusStore::set(const std::string& scene_id, const std::string& clash_id, ClashStatus status) {
  if (status == ClashStatus::kNew)
    return invalid_argument("status", "NEW is the audits' own status; set REVIEWED, APPROVED, ACTIVE or RESOLVED");
  std::lock_guard<std::mutex> lock(mutex_);
  WriteTransaction transaction(db_);
  if (!transaction.begun()) return storage_error("cannot begin the clash status transaction");
  ClashStatusRecord r;
  {
    Statement s(db_, (std::string("SELECT ") + kColumns + " FROM clash_statuses WHERE scene_id = ? AND clash_id = ?").c_str());
    if (!s.ok()) return storage_error("cannot read the clash status");
    s.text(1, scene_id).text(2, clash_id);
    const int rc = s.step();
    if (rc == SQLITE_DONE)
      return Error{ErrorCode::kNotFound, "clash_id", "no audit of scene '" + scene_id + "' found a clash '" + clash_id + "'"};
    if (rc != SQLITE_ROW) return storage_error("cannot read the clash status");
    r = record_of(s);
  }
  r.status = status;
  r.set_by_user = true;
  if (auto w = write_row(db_, r); !w.ok()) return w.error();
  if (!transaction.commit()) return storage_error("cannot commit the clash status");
  return r;
}

Result<std::vector<ClashStatusRecord>> ClashStatusStore::list(const std::string& scene_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rows_of(db_, scene_id);
}

}  // namespace gk::server
