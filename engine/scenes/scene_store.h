// Scenes for layout tools: named objects (an uploaded part at a pose) kept in memory and in the
// SQLite database beside the parts, so an acknowledged change survives a restart.
#pragma once

#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <map>
#include <optional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

struct sqlite3;

namespace gk::engine {

struct StoredPose {
  Vec3 translation = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double angle_deg = 0.0;
  RigidTransform transform() const;
};

struct SceneObjectRecord {
  std::string id, name, category, part_id;
  StoredPose pose;
  std::string group;
};

struct SceneRecord {
  std::string id, name;
  std::map<std::string, SceneObjectRecord> objects;
  std::uint64_t version = 0;  // in memory: counts the changes since the daemon started
};

// When a stored change counts as kept. A drag's frames are logged: committed to the database's
// write-ahead log without waiting for the disk, so they survive the daemon being killed (the log
// is in the system's buffers) but the last ones may be lost to a power cut until the next synced
// write or sync(); the drag's end syncs. Every other change is synced before it is answered.
enum class WriteDurability { kSynced, kLogged };

class SceneStore {
 public:
  static Result<std::unique_ptr<SceneStore>> open(const std::string& directory);
  // For a batch program reading a daemon's data directory beside it (the MPI audit driver, whose
  // processes open it at once): reads only, writes nothing, not even the schema.
  static Result<std::unique_ptr<SceneStore>> open_read_only(const std::string& directory);
  ~SceneStore();

  Result<SceneRecord> create(const std::string& name);
  Result<SceneRecord> get(const std::string& scene_id) const;
  // The scene's change counter alone (no copy of its objects): how a drag knows nobody else edited.
  Result<std::uint64_t> version(const std::string& scene_id) const;
  // Inserts or replaces; an empty object id gets a new one. Returns the stored object; `previous`
  // (when given) receives what the id held before (nothing for a new object).
  Result<SceneObjectRecord> put(const std::string& scene_id, SceneObjectRecord object,
                                std::optional<SceneObjectRecord>* previous = nullptr);
  // All or nothing, in one transaction; returns the stored objects (with their ids) in order.
  Result<std::vector<SceneObjectRecord>> put_many(const std::string& scene_id, std::vector<SceneObjectRecord> objects);
  Result<SceneObjectRecord> move(const std::string& scene_id, const std::string& object_id, const StoredPose& pose,
                                 std::optional<SceneObjectRecord>* previous = nullptr,
                                 WriteDurability durability = WriteDurability::kSynced);
  // Every change logged so far is on the disk when this returns (the log synced).
  Result<bool> sync();
  // Takes back an edit whose answer failed: the object returns to `previous` (or goes, when it
  // was new) only if it is still exactly as that edit stored it (a later edit is kept). Returns
  // whether it was taken back.
  Result<bool> revert(const std::string& scene_id, const SceneObjectRecord& stored,
                      const std::optional<SceneObjectRecord>& previous);
  Result<SceneRecord> remove(const std::string& scene_id, const std::string& object_id);

 private:
  SceneStore() = default;
  void load();  // every scene and object from the database into memory
  Result<bool> write_object(const std::string& scene_id, const SceneObjectRecord& o);
  Result<bool> delete_object(const std::string& scene_id, const std::string& object_id);  // mutex_ held
  std::string new_id(const char* prefix);

  sqlite3* db_ = nullptr;
  mutable std::mutex mutex_;
  std::map<std::string, SceneRecord> scenes_;
  unsigned long long counter_ = 0;
};

}  // namespace gk::engine
