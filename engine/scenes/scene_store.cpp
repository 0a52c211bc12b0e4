#include "engine/scenes/scene_store.h"
#include "kernel/core/units.h"

#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <random>

namespace gk::engine {
namespace {

Error storage_error(const std::string& what) { return {ErrorCode::kInternal, "storage", what}; }

}  // namespace

RigidTransform StoredPose::transform() const {
  if (angle_deg == 0.0) return RigidTransform::from_translation(translation);
  return RigidTransform::from_axis_angle(axis, angle_deg * kPi / 180.0, translation);
}

Result<std::unique_ptr<SceneStore>> SceneStore::open(const std::string& directory) {
  std::unique_ptr<SceneStore> store(new SceneStore());
  if (sqlite3_open((directory + "/gatekeeper.sqlite").c_str(), &store->db_) != SQLITE_OK)
    return storage_error("cannot open the scene database in " + directory);
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA busy_timeout=5000;"
      "CREATE TABLE IF NOT EXISTS scenes (id TEXT PRIMARY KEY, name TEXT);"
      "CREATE TABLE IF NOT EXISTS scene_objects (scene_id TEXT, id TEXT, name TEXT, category TEXT, part_id TEXT,"
      " tx REAL, ty REAL, tz REAL, ax REAL, ay REAL, az REAL, angle REAL, PRIMARY KEY (scene_id, id));";
  char* err = nullptr;
  if (sqlite3_exec(store->db_, schema, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string message = err ? err : "unknown";
    sqlite3_free(err);
    return storage_error("cannot prepare the scene tables: " + message);
  }
  // Objects gained a group after the first release: databases written before get the column.
  sqlite3_exec(store->db_, "ALTER TABLE scene_objects ADD COLUMN grp TEXT NOT NULL DEFAULT ''", nullptr, nullptr, nullptr);
  store->load();
  return store;
}

Result<std::unique_ptr<SceneStore>> SceneStore::open_read_only(const std::string& directory) {
  std::unique_ptr<SceneStore> store(new SceneStore());
  if (sqlite3_open_v2((directory + "/gatekeeper.sqlite").c_str(), &store->db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
    return storage_error("cannot open the scene database in " + directory + " for reading");
  sqlite3_busy_timeout(store->db_, 5000);
  store->load();
  return store;
}

void SceneStore::load() {
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "SELECT id, name FROM scenes", -1, &stmt, nullptr);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    SceneRecord s;
    s.id = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    s.name = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
    scenes_[s.id] = s;
  }
  sqlite3_finalize(stmt);
  sqlite3_prepare_v2(db_, "SELECT scene_id, id, name, category, part_id, tx, ty, tz, ax, ay, az, angle, grp FROM scene_objects",
                     -1, &stmt, nullptr);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    SceneObjectRecord o;
    const std::string scene = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    o.id = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
    o.name = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 2));
    o.category = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 3));
    o.part_id = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 4));
    for (int k = 0; k < 3; ++k) {
      o.pose.translation[k] = sqlite3_column_double(stmt, 5 + k);
      o.pose.axis[k] = sqlite3_column_double(stmt, 8 + k);
    }
    o.pose.angle_deg = sqlite3_column_double(stmt, 11);
    o.group = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 12));
    scenes_[scene].objects[o.id] = o;
  }
  sqlite3_finalize(stmt);
}

SceneStore::~SceneStore() {
  if (db_) sqlite3_close(db_);
}

std::string SceneStore::new_id(const char* prefix) {
  static thread_local std::mt19937_64 rng(std::random_device{}() ^
                                          static_cast<unsigned long long>(std::chrono::steady_clock::now().time_since_epoch().count()));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s-%016llx-%llu", prefix, static_cast<unsigned long long>(rng()), ++counter_);
  return buf;
}

Result<SceneRecord> SceneStore::create(const std::string& name) {
  std::lock_guard<std::mutex> lock(mutex_);
  SceneRecord s;
  s.id = new_id("scene");
  s.name = name;
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "INSERT INTO scenes (id, name) VALUES (?, ?)", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, s.id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 2, s.name.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return storage_error("cannot record the scene");
  scenes_[s.id] = s;
  return s;
}

Result<SceneRecord> SceneStore::get(const std::string& scene_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  return it->second;
}

Result<std::uint64_t> SceneStore::version(const std::string& scene_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  return it->second.version;
}

Result<bool> SceneStore::write_object(const std::string& scene_id, const SceneObjectRecord& o) {
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "INSERT OR REPLACE INTO scene_objects (scene_id, id, name, category, part_id, tx, ty, tz, ax, ay, az, angle, grp)"
                     " VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?)", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, scene_id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 2, o.id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 3, o.name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 4, o.category.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 5, o.part_id.c_str(), -1, SQLITE_TRANSIENT);
  for (int k = 0; k < 3; ++k) {
    sqlite3_bind_double(stmt, 6 + k, o.pose.translation[k]);
    sqlite3_bind_double(stmt, 9 + k, o.pose.axis[k]);
  }
  sqlite3_bind_double(stmt, 12, o.pose.angle_deg);
  sqlite3_bind_text(stmt, 13, o.group.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return storage_error("cannot record the object");
  return true;
}

Result<SceneObjectRecord> SceneStore::put(const std::string& scene_id, SceneObjectRecord object,
                                          std::optional<SceneObjectRecord>* previous) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  if (object.id.empty()) object.id = new_id("obj");
  if (previous) {
    auto before = it->second.objects.find(object.id);
    *previous = before == it->second.objects.end() ? std::nullopt : std::optional<SceneObjectRecord>(before->second);
  }
  auto written = write_object(scene_id, object);
  if (!written.ok()) return written.error();
  it->second.objects[object.id] = object;
  ++it->second.version;
  return object;
}

Result<std::vector<SceneObjectRecord>> SceneStore::put_many(const std::string& scene_id, std::vector<SceneObjectRecord> objects) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  for (SceneObjectRecord& o : objects)
    if (o.id.empty()) o.id = new_id("obj");
  if (sqlite3_exec(db_, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr) != SQLITE_OK)
    return storage_error("cannot begin the transaction for the objects");
  for (const SceneObjectRecord& o : objects) {
    auto written = write_object(scene_id, o);
    if (!written.ok()) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      return written.error();
    }
  }
  if (sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr) != SQLITE_OK) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    return storage_error("cannot commit the objects");
  }
  for (const SceneObjectRecord& o : objects) it->second.objects[o.id] = o;
  ++it->second.version;
  return objects;
}

Result<SceneObjectRecord> SceneStore::move(const std::string& scene_id, const std::string& object_id, const StoredPose& pose,
                                           std::optional<SceneObjectRecord>* previous, WriteDurability durability) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  auto ob = it->second.objects.find(object_id);
  if (ob == it->second.objects.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  if (previous) *previous = ob->second;
  SceneObjectRecord moved = ob->second;
  moved.pose = pose;
  // The connection's sync level is switched for this one write (the store's mutex is held).
  const bool logged = durability == WriteDurability::kLogged;
  if (logged) sqlite3_exec(db_, "PRAGMA synchronous=NORMAL", nullptr, nullptr, nullptr);
  auto written = write_object(scene_id, moved);
  if (logged) sqlite3_exec(db_, "PRAGMA synchronous=FULL", nullptr, nullptr, nullptr);
  if (!written.ok()) return written.error();
  ob->second = moved;
  ++it->second.version;
  return moved;
}

Result<bool> SceneStore::sync() {
  std::lock_guard<std::mutex> lock(mutex_);
  // A checkpoint syncs the write-ahead log before it copies pages back (synchronous=FULL): every
  // logged frame is then on the disk. PASSIVE: it never waits for readers.
  if (sqlite3_wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_PASSIVE, nullptr, nullptr) != SQLITE_OK)
    return storage_error("cannot sync the scene database's log");
  return true;
}

Result<bool> SceneStore::delete_object(const std::string& scene_id, const std::string& object_id) {
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "DELETE FROM scene_objects WHERE scene_id = ? AND id = ?", -1, &stmt, nullptr);
  sqlite3_bind_text(stmt, 1, scene_id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(stmt, 2, object_id.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(stmt);
  sqlite3_finalize(stmt);
  if (rc != SQLITE_DONE) return storage_error("cannot delete the object");
  return true;
}

Result<SceneRecord> SceneStore::remove(const std::string& scene_id, const std::string& object_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return Error{ErrorCode::kNotFound, "scene_id", "no scene '" + scene_id + "'"};
  if (!it->second.objects.count(object_id)) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  if (auto deleted = delete_object(scene_id, object_id); !deleted.ok()) return deleted.error();
  it->second.objects.erase(object_id);
  ++it->second.version;
  return it->second;
}

namespace {

bool same_record(const SceneObjectRecord& a, const SceneObjectRecord& b) {
  return a.id == b.id && a.name == b.name && a.category == b.category && a.part_id == b.part_id && a.group == b.group &&
         a.pose.translation == b.pose.translation && a.pose.axis == b.pose.axis && a.pose.angle_deg == b.pose.angle_deg;
}

}  // namespace

Result<bool> SceneStore::revert(const std::string& scene_id, const SceneObjectRecord& stored,
                                const std::optional<SceneObjectRecord>& previous) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = scenes_.find(scene_id);
  if (it == scenes_.end()) return false;
  auto ob = it->second.objects.find(stored.id);
  if (ob == it->second.objects.end() || !same_record(ob->second, stored)) return false;  // edited since: kept
  if (previous) {
    if (auto written = write_object(scene_id, *previous); !written.ok()) return written.error();
    ob->second = *previous;
  } else {
    if (auto deleted = delete_object(scene_id, stored.id); !deleted.ok()) return deleted.error();
    it->second.objects.erase(ob);
  }
  ++it->second.version;
  return true;
}

}  // namespace gk::engine
