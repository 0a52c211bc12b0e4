// A scene's objects ready for the kernel: each object's part loaded (one mesh and BVH per part,
// shared by every copy) and placed at its pose.
#pragma once

#include "engine/parts/part_registry.h"
#include "engine/scenes/scene_store.h"
#include "engine/audits/scene_audit.h"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace gk::engine {

// One object at its pose, with its world box (of its triangles).
struct PlacedObject {
  const SceneObjectRecord* object;
  std::shared_ptr<const LoadedPart> part;
  RigidTransform pose;
  Aabb box;
};
Result<PlacedObject> place_object(const SceneObjectRecord& o, PartRegistry& parts);

// Every object in id order.
struct PlacedScene {
  std::vector<AuditObject> objects;
  std::vector<std::shared_ptr<const LoadedPart>> parts;  // each object's part (its exact B-Rep for CAD)
  std::vector<const SceneObjectRecord*> records;  // into the SceneRecord it was placed from
  std::vector<Aabb> boxes;
  std::map<std::string, std::uint32_t> index_of;
};
Result<PlacedScene> place_scene(const SceneRecord& scene, PartRegistry& parts);

// The same objects for an audit out of core: each distinct part is loaded once, written to pack_dir
// as a pack (engine/parts/packed_mesh_file, kept there for later audits) and let go, and every
// object names its part's pack instead of holding the mesh (`parts` are then empty). Only the
// registry's own budget of parts is in memory while the packs are written.
Result<PlacedScene> place_scene_packed(const SceneRecord& scene, PartRegistry& parts, const std::string& pack_dir);

}  // namespace gk::engine
