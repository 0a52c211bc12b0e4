// A seeded, realistic factory scene for audit tests and benchmarks: a hall of 10 m bays with
// building columns and walls, pipes crossing the whole hall, robot cells (the KUKA KR10 meshes
// from ../shared/data, 7 links each), machines (TR12J, motor, turbine, fandisk), rack rows and
// conveyors with bolts resting on them, from millimetres to tens of metres. Identical meshes are
// shared (one MeshBvh for every copy). Beside the hall, deliberate clashes and near misses
// between crates whose answers are known.
#pragma once

#include "engine/audits/scene_audit.h"

#include <cstddef>
#include <string>
#include <vector>

namespace gk::testing {

struct FactorySceneOptions {
  unsigned seed = 1;
  std::size_t objects = 1000;          // about this many objects ...
  std::size_t triangles = 5'000'000;   // ... and this many triangles (counted per instance)
  int deliberate_clashes = 10;         // crate pairs overlapping by clash_depth_mm
  int near_misses = 10;                // crate pairs apart by near_miss_gap_mm
  double clash_depth_mm = 5.0;
  double near_miss_gap_mm = 2.0;
  // Every robot link and machine gets its own mesh and BVH (a copy) instead of sharing one: the
  // cost of a scene without instancing.
  bool distinct_meshes = false;
  // With distinct_meshes: each copy randomly deformed (a smooth displacement field of up to
  // deform_mm, its own per object), so every copy is its own content, as in a real plant.
  bool deformed = false;
  double deform_mm = 0.5;
  // When set, BVHs are loaded from (and saved to) this engine/parts/bvh_cache directory.
  std::string bvh_cache_dir;
  // When set, every object's mesh and tree are written to this directory as packs
  // (engine/parts/packed_mesh_file) and the object is given `packed` instead of its mesh, which
  // is released as soon as written (an out-of-core scene); an index of the scene is written
  // beside them (read_factory_scene_index).
  std::string pack_dir;
};

struct KnownPair {
  std::uint32_t a = 0, b = 0;  // a < b
  bool clash = false;          // overlapping crates; otherwise a near miss
  double gap_mm = 0.0;         // near misses: the exact distance
};

struct FactoryScene {
  std::vector<engine::AuditObject> objects;
  std::vector<KnownPair> known;
  std::vector<engine::ContactRule> rules;  // the scene's intended contacts
  std::size_t unique_meshes = 0;
  std::size_t triangles = 0;
};

// Throws std::runtime_error if a shared mesh cannot be read (or a pack cannot be written).
FactoryScene generate_factory_scene(const FactorySceneOptions& options);

// The scene a generation with pack_dir wrote, every object `packed` (no mesh read), or an error
// when the directory holds no complete index.
Result<FactoryScene> read_factory_scene_index(const std::string& pack_dir);

}  // namespace gk::testing
