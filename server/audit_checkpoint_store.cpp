#include "server/audit_checkpoint_store.h"

#include "audit_archive.pb.h"
#include "server/proto_convert.h"

#include <sqlite3.h>

#include <chrono>

namespace gk::server {
namespace {

namespace spb = ::gatekeeper::server;

void put(const Vec3& v, pb::Vec3* out) { to_proto(v, out); }
Vec3 get(const pb::Vec3& v) { return Vec3(v.x_mm(), v.y_mm(), v.z_mm()); }

Error storage_error(const std::string& what, sqlite3* db) {
  return Error{ErrorCode::kInternal, "checkpoint", what + ": " + sqlite3_errmsg(db)};
}

// One statement with text/blob parameters, run to completion.
Result<bool> execute(sqlite3* db, const char* sql, const std::vector<std::string>& texts, const std::string* blob = nullptr,
                     const long long* number = nullptr) {
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK) return storage_error("cannot prepare", db);
  int k = 1;
  for (const std::string& t : texts) sqlite3_bind_text(stmt, k++, t.c_str(), -1, SQLITE_TRANSIENT);
  if (number) sqlite3_bind_int64(stmt, k++, *number);
  if (blob) sqlite3_bind_blob(stmt, k++, blob->data(), static_cast<int>(blob->size()), SQLITE_TRANSIENT);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return storage_error("cannot write", db);
  return true;
}

}  // namespace

constexpr std::uint32_t kTileMagic = 0x474b5431;

std::string encode_tile(const std::vector<PairClash>& clashes) {
  spb::CheckpointTile tile;
  tile.set_magic(kTileMagic);
  tile.set_clash_count(static_cast<std::uint32_t>(clashes.size()));
  for (const PairClash& c : clashes) {
    spb::CheckpointClash* o = tile.add_clashes();
    o->set_a(c.a);
    o->set_b(c.b);
    o->set_verdict(static_cast<int>(c.verdict));
    o->set_inconclusive_reason(static_cast<int>(c.inconclusive_reason));
    o->set_distance_mm(c.distance_mm);
    o->set_clearance_violation(c.clearance_violation);
    put(c.point_a, o->mutable_point_a());
    put(c.point_b, o->mutable_point_b());
    for (const engine::ContactPlace& p : c.regions) to_proto(p, o->add_regions());
    o->set_contacts(c.contacts);
    o->set_contacts_truncated(c.contacts_truncated);
    o->set_depth_mm(c.depth_mm);
    o->set_depth_direction_set(c.depth_direction.has_value());
    if (c.depth_direction) put(c.depth_direction->vector(), o->mutable_depth_direction());
    o->set_volume_mm3(c.volume_mm3);
    o->set_volume_error_bound_mm3(c.volume_error_bound_mm3);
    o->set_error(c.error);
  }
  return tile.SerializeAsString();
}

Result<std::vector<PairClash>> decode_tile(const std::string& bytes) {
  spb::CheckpointTile tile;
  if (!tile.ParseFromString(bytes) || tile.magic() != kTileMagic || tile.clash_count() != static_cast<std::uint32_t>(tile.clashes_size()))
    return Error{ErrorCode::kInternal, "checkpoint", "a tile's record cannot be read (damaged or cut short)"};
  std::vector<PairClash> out;
  for (const spb::CheckpointClash& o : tile.clashes()) {
    PairClash c;
    c.a = o.a();
    c.b = o.b();
    if (!(c.a < c.b)) return Error{ErrorCode::kInternal, "checkpoint", "a tile's clash names its objects out of order"};
    if (o.verdict() < 0 || o.verdict() > static_cast<int>(Verdict::kInconclusive))
      return Error{ErrorCode::kInternal, "checkpoint", "a tile's clash has an unknown verdict"};
    if (o.inconclusive_reason() < 0 || o.inconclusive_reason() > static_cast<int>(InconclusiveReason::kPairFailed))
      return Error{ErrorCode::kInternal, "checkpoint", "a tile's clash has an unknown inconclusive reason"};
    c.verdict = static_cast<Verdict>(o.verdict());
    c.inconclusive_reason = static_cast<InconclusiveReason>(o.inconclusive_reason());
    c.distance_mm = o.distance_mm();
    c.clearance_violation = o.clearance_violation();
    c.point_a = get(o.point_a());
    c.point_b = get(o.point_b());
    for (const pb::ContactRegion& r : o.regions()) {
      engine::ContactPlace p;
      p.min_distance_mm = r.min_distance_mm();
      p.point_a = get(r.point_a());
      p.point_b = get(r.point_b());
      p.triangle_pairs = r.triangle_pairs();
      p.bounds = Aabb{get(r.bounds_min()), get(r.bounds_max())};
      for (std::uint32_t f : r.faces_a()) p.faces_a.push_back(static_cast<int>(f));
      for (std::uint32_t f : r.faces_b()) p.faces_b.push_back(static_cast<int>(f));
      c.regions.push_back(std::move(p));
    }
    c.contacts = o.contacts();
    c.contacts_truncated = o.contacts_truncated();
    c.depth_mm = o.depth_mm();
    if (o.depth_direction_set()) {
      c.depth_direction = Direction::restored(get(o.depth_direction()));
      if (!c.depth_direction) return Error{ErrorCode::kInternal, "checkpoint", "a tile's clash has a depth direction of length other than 1"};
    }
    c.volume_mm3 = o.volume_mm3();
    c.volume_error_bound_mm3 = o.volume_error_bound_mm3();
    c.error = o.error();
    out.push_back(std::move(c));
  }
  return out;
}

Result<std::unique_ptr<AuditCheckpointStore>> AuditCheckpointStore::open(const std::string& directory) {
  std::unique_ptr<AuditCheckpointStore> store(new AuditCheckpointStore());
  if (sqlite3_open((directory + "/gatekeeper.sqlite").c_str(), &store->db_) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot open the audit database in " + directory};
  // synchronous=FULL: a tile counts as kept only once it is on disk.
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA busy_timeout=5000;"
      "CREATE TABLE IF NOT EXISTS running_audits (id TEXT PRIMARY KEY, begun INTEGER, data BLOB, cancelled INTEGER DEFAULT 0);"
      "CREATE TABLE IF NOT EXISTS audit_tiles (job_id TEXT, tile INTEGER, data BLOB, PRIMARY KEY (job_id, tile));";
  if (sqlite3_exec(store->db_, schema, nullptr, nullptr, nullptr) != SQLITE_OK)
    return Error{ErrorCode::kInternal, "data_dir", "cannot prepare the checkpoint tables"};
  // Tables written before cancels were kept get the column (an error when it is there already).
  sqlite3_exec(store->db_, "ALTER TABLE running_audits ADD COLUMN cancelled INTEGER DEFAULT 0", nullptr, nullptr, nullptr);
  return store;
}

AuditCheckpointStore::~AuditCheckpointStore() {
  if (db_) sqlite3_close(db_);
}

Result<bool> AuditCheckpointStore::begin(const std::string& job_id, const SceneRecord& scene, const AuditOptions& options,
                                         const std::string& baseline_job_id) {
  spb::RunningAudit r;
  r.set_job_id(job_id);
  scene_to_proto(scene, r.mutable_scene());
  r.set_clearance_mm(options.clearance_mm);
  r.set_tile_mm(options.tile_mm);
  r.set_threads(options.threads);
  r.set_compute_depth(options.compute_depth);
  r.set_compute_volume(options.compute_volume);
  r.set_region_merge_mm(options.region_merge_mm);
  r.set_max_contacts_per_pair(options.max_contacts_per_pair);
  for (const engine::ContactRule& rule : options.rules) {
    pb::ContactRule* o = r.add_rules();
    o->set_name(rule.name);
    o->set_category_a(rule.category_a);
    o->set_category_b(rule.category_b);
    o->set_same_group_only(rule.same_group_only);
  }
  for (std::uint32_t id : options.only_objects) r.add_only_objects(id);
  r.set_baseline_job_id(baseline_job_id);
  const std::string bytes = r.SerializeAsString();
  const long long begun =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  return execute(db_, "INSERT OR REPLACE INTO running_audits (id, begun, data) VALUES (?, ?, ?)", {job_id}, &bytes, &begun);
}

Result<bool> AuditCheckpointStore::tile_done(const std::string& job_id, std::size_t tile, const std::vector<PairClash>& clashes) {
  const std::string bytes = encode_tile(clashes);
  const auto number = static_cast<long long>(tile);
  return execute(db_, "INSERT OR REPLACE INTO audit_tiles (job_id, tile, data) VALUES (?, ?, ?)", {job_id}, &bytes, &number);
}

Result<bool> AuditCheckpointStore::cancelled(const std::string& job_id) {
  return execute(db_, "UPDATE running_audits SET cancelled = 1 WHERE id = ?", {job_id});
}

Result<bool> AuditCheckpointStore::forget(const std::string& job_id) {
  if (sqlite3_exec(db_, "BEGIN", nullptr, nullptr, nullptr) != SQLITE_OK) return storage_error("cannot begin", db_);
  auto tiles = execute(db_, "DELETE FROM audit_tiles WHERE job_id = ?", {job_id});
  auto job = tiles.ok() ? execute(db_, "DELETE FROM running_audits WHERE id = ?", {job_id}) : tiles;
  if (!job.ok()) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    return job;
  }
  if (sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) return storage_error("cannot commit", db_);
  return true;
}

Result<std::vector<engine::UnfinishedAudit>> AuditCheckpointStore::unfinished() const {
  std::vector<engine::UnfinishedAudit> out;
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db_, "SELECT id, data, cancelled FROM running_audits ORDER BY begun, id", -1, &stmt, nullptr) != SQLITE_OK)
    return storage_error("cannot read", db_);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    const unsigned char* id_text = sqlite3_column_text(stmt, 0);
    if (!id_text) continue;  // no job can own it
    engine::UnfinishedAudit u;
    u.job_id = reinterpret_cast<const char*>(id_text);
    u.cancelled = sqlite3_column_int(stmt, 2) != 0;
    spb::RunningAudit r;
    const void* blob = sqlite3_column_blob(stmt, 1);
    if (!blob || !r.ParseFromArray(blob, sqlite3_column_bytes(stmt, 1))) {
      u.unreadable = "its checkpoint record is damaged";
      out.push_back(std::move(u));
      continue;
    }
    auto scene = scene_from_proto(r.scene());
    if (!scene.ok()) {
      u.unreadable = "its checkpoint's scene cannot be read: " + scene.error().message;
      out.push_back(std::move(u));
      continue;
    }
    u.scene = std::move(scene).value();
    u.options.clearance_mm = r.clearance_mm();
    u.options.tile_mm = r.tile_mm();
    u.options.threads = r.threads();
    u.options.compute_depth = r.compute_depth();
    u.options.compute_volume = r.compute_volume();
    u.options.region_merge_mm = r.region_merge_mm();
    u.options.max_contacts_per_pair = static_cast<std::size_t>(r.max_contacts_per_pair());
    for (const pb::ContactRule& rule : r.rules())
      u.options.rules.push_back({rule.name(), rule.category_a(), rule.category_b(), rule.same_group_only()});
    u.options.only_objects.assign(r.only_objects().begin(), r.only_objects().end());
    u.baseline_job_id = r.baseline_job_id();
    out.push_back(std::move(u));
  }
  sqlite3_finalize(stmt);
  for (engine::UnfinishedAudit& u : out) {
    if (!u.unreadable.empty()) continue;
    if (sqlite3_prepare_v2(db_, "SELECT tile, data FROM audit_tiles WHERE job_id = ? ORDER BY tile", -1, &stmt, nullptr) != SQLITE_OK)
      return storage_error("cannot read", db_);
    sqlite3_bind_text(stmt, 1, u.job_id.c_str(), -1, SQLITE_TRANSIENT);
    while (sqlite3_step(stmt) == SQLITE_ROW) {
      const sqlite3_int64 tile = sqlite3_column_int64(stmt, 0);
      const void* blob = sqlite3_column_blob(stmt, 1);
      const std::string bytes = blob ? std::string(static_cast<const char*>(blob), static_cast<std::size_t>(sqlite3_column_bytes(stmt, 1))) : "";
      auto clashes = decode_tile(bytes);
      if (tile < 0 || !clashes.ok()) continue;  // damaged: the tile is computed again
      u.tiles[static_cast<std::size_t>(tile)] = std::move(clashes).value();
    }
    sqlite3_finalize(stmt);
  }
  return out;
}

}  // namespace gk::server
