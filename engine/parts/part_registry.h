// Uploaded parts as meshes, loaded from the store on first use and kept in memory.
#pragma once

#include "engine/parts/part_geometry.h"
#include "engine/parts/bvh_cache.h"
#include "kernel/bvh/mesh_bvh.h"
#include "occt_adapters/shape.h"
#include "engine/parts/part_store.h"
#include "kernel/core/tolerances.h"

#include <map>
#include <memory>
#include <mutex>
#include <utility>

namespace gk::engine {

// CAD parts are tessellated at tolerances::kPartDeflectionMm for every query.
inline constexpr double kPartDeflectionMm = tolerances::kPartDeflectionMm;

// An uploaded part's geometry (engine/part_geometry) and its stored record.
struct LoadedPart : engine::PartGeometry {
  PartRecord record;
};

class PartRegistry {
 public:
  // BVHs are kept on disk in bvh_cache_dir (by mesh content), so a restarted daemon loads them.
  // Loaded parts are kept in memory up to memory_budget_bytes (estimated); beyond it the least
  // recently used are dropped (what a scene or a running query holds stays alive with it) and read
  // again from disk when next asked for.
  PartRegistry(PartStore& store, const std::string& bvh_cache_dir, std::size_t memory_budget_bytes = kDefaultPartMemoryBytes)
      : store_(store), bvh_cache_(bvh_cache_dir), memory_budget_bytes_(memory_budget_bytes) {}
  static constexpr std::size_t kDefaultPartMemoryBytes = 8ull << 30;
  // A loaded part's memory, estimated from its triangles: 150 bytes per triangle plus 24 per vertex
  // is above what a mesh with its BVH was measured to keep (71-97 bytes per triangle, vertices
  // included, with the compact tree: kernel_fcl_table in docs/PERFORMANCE.md), so the budget errs
  // towards dropping parts early, never towards exceeding it.
  static constexpr std::size_t kBytesPerTriangle = 150;

  struct MemoryStats {
    std::size_t parts = 0, bytes = 0, evicted = 0;
    std::size_t budget_bytes = 0;
    std::uint64_t hits = 0, loads = 0;  // load() answered from memory, and read from the store
    BvhCache::Stats bvh_cache;          // trees loaded from disk, built, rejected (damaged or foreign)
  };
  MemoryStats memory_stats() const;

  // The part's mesh: mesh formats as stored, CAD formats tessellated at deflection_mm.
  Result<std::shared_ptr<const LoadedPart>> load(const std::string& id, double deflection_mm);

  // Reads any supported file into a mesh (used to describe an upload before it is recorded); for
  // CAD files also the shape and each triangle's face.
  // CAD parts larger than deflection_mm / kCadDeflectionRelative are tessellated coarser
  // (used_deflection_mm says at what).
  static Result<TriangleMesh> read_any(const std::string& path, const std::string& format, double deflection_mm,
                                       occt::Shape* shape = nullptr, std::vector<int>* face_of_triangle = nullptr,
                                       double* used_deflection_mm = nullptr);
  // The same without the child process (CAD files are otherwise read in a child first:
  // engine/parts/cad_sandbox.h); the child itself reads with this.
  static Result<TriangleMesh> read_in_process(const std::string& path, const std::string& format, double deflection_mm,
                                       occt::Shape* shape = nullptr, std::vector<int>* face_of_triangle = nullptr,
                                       double* used_deflection_mm = nullptr);

  PartStore& store() { return store_; }
  const PartStore& store() const { return store_; }

 private:
  PartStore& store_;
  BvhCache bvh_cache_;
  struct Loaded {
    std::shared_ptr<const LoadedPart> part;
    std::size_t bytes = 0;
    std::uint64_t last_used = 0;
  };
  const std::size_t memory_budget_bytes_;
  mutable std::mutex mutex_;
  std::map<std::pair<std::string, double>, Loaded> loaded_;
  std::size_t loaded_bytes_ = 0, evicted_ = 0;
  std::uint64_t hits_ = 0, loads_ = 0;
  std::uint64_t use_clock_ = 0;
};

}  // namespace gk::engine
