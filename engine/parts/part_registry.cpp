#include "engine/parts/part_registry.h"

#include "kernel/core/tolerances.h"

#include "mesh_io/mesh_file_reader.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"
#include "engine/parts/cad_sandbox.h"

#include <filesystem>

namespace gk::engine {
namespace {

// The readers pick their format by the file's extension: a stored or staged file gets a link
// (or copy) with one, removed again when this goes out of scope.
class NamedByFormat {
 public:
  NamedByFormat(const std::string& path, const std::string& format) : path_(path) {
    if (std::filesystem::path(path).extension() == "." + format) return;
    path_ = path + "." + format;
    std::error_code ec;
    std::filesystem::create_hard_link(path, path_, ec);
    if (ec) std::filesystem::copy_file(path, path_, ec);
    owned_ = true;
  }
  ~NamedByFormat() {
    std::error_code ec;
    if (owned_) std::filesystem::remove(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  bool owned_ = false;
};

}  // namespace

Result<TriangleMesh> PartRegistry::read_any(const std::string& path, const std::string& format, double deflection_mm,
                                            occt::Shape* shape_out, std::vector<int>* face_of_triangle, double* used_deflection_mm) {
  if (is_cad_format(format))
    if (auto checked = check_cad_in_child(path, format, deflection_mm); !checked.ok()) return checked.error();
  return read_in_process(path, format, deflection_mm, shape_out, face_of_triangle, used_deflection_mm);
}

Result<TriangleMesh> PartRegistry::read_in_process(const std::string& path, const std::string& format, double deflection_mm,
                                                   occt::Shape* shape_out, std::vector<int>* face_of_triangle,
                                                   double* used_deflection_mm) {
  const NamedByFormat named(path, format);
  if (is_cad_format(format)) {
    auto shape = occt::read_shape_file(named.path());
    if (!shape.ok()) return invalid_argument("data", shape.error().message);
    // A huge part is tessellated coarser (a 200 m sphere at 0.05 mm took the daemon past 20 GB):
    // its window of exact-face decisions grows instead.
    const Aabb box = shape.value().bounds();
    const double diagonal = box.empty() ? 0.0 : (box.max - box.min).norm();
    const double deflection = std::max(deflection_mm, tolerances::kCadDeflectionRelative * diagonal);
    auto meshed = occt::mesh_shape(shape.value(), deflection);
    if (!meshed.ok()) return invalid_argument("data", meshed.error().to_string());
    // What the triangles were measured to keep to (wider than asked on some surfaces).
    if (used_deflection_mm) *used_deflection_mm = meshed.value().deflection_mm;
    if (shape_out) *shape_out = shape.value();
    if (face_of_triangle) *face_of_triangle = meshed.value().face_of_triangle;
    return std::move(meshed.value().mesh);
  }
  mesh_io::ReadOptions options;
  options.build.drop_zero_area_triangles = true;
  auto mesh = mesh_io::read_mesh_file(named.path(), options);
  if (!mesh.ok()) return invalid_argument("data", mesh.error().message);
  return mesh;
}

Result<std::shared_ptr<const LoadedPart>> PartRegistry::load(const std::string& id, double deflection_mm) {
  // Parts never change (the id is their content's hash): a loaded one is answered from memory,
  // without asking the database. Mesh parts are kept under deflection 0, CAD parts under theirs.
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (double key : {0.0, deflection_mm}) {
      auto it = loaded_.find({id, key});
      if (it != loaded_.end()) {
        it->second.last_used = ++use_clock_;
        ++hits_;
        return it->second.part;
      }
    }
  }
  auto record = store_.get(id);
  if (!record.ok()) return record.error();
  const double key_deflection = is_cad_format(record.value().format) ? deflection_mm : 0.0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = loaded_.find({id, key_deflection});
    if (it != loaded_.end()) {
      it->second.last_used = ++use_clock_;
      ++hits_;
      return it->second.part;
    }
    ++loads_;
  }
  auto part = std::make_shared<LoadedPart>();
  double used_deflection = key_deflection;
  auto mesh = read_any(store_.path_of(record.value()), record.value().format, deflection_mm, &part->shape,
                       &part->face_of_triangle, &used_deflection);
  if (!mesh.ok()) return mesh.error();
  part->record = record.value();
  part->mesh = std::make_shared<const TriangleMesh>(std::move(mesh).value());
  auto bvh = bvh_cache_.get_or_build(part->mesh);
  if (!bvh.ok()) return bvh.error();
  part->bvh = bvh.value();
  // A CAD part of planes and straight edges is tessellated exactly; curved ones deviate.
  part->deflection_mm = part->shape.is_polyhedral() ? 0.0 : used_deflection;
  const std::size_t bytes = part->mesh->triangle_count() * kBytesPerTriangle + part->mesh->vertices().size() * sizeof(Vec3);
  std::lock_guard<std::mutex> lock(mutex_);
  auto [it, fresh] = loaded_.insert({{id, key_deflection}, Loaded{part, bytes, ++use_clock_}});
  if (!fresh) return it->second.part;  // another call loaded it meanwhile: one copy is kept
  loaded_bytes_ += bytes;
  // Over budget: drop the least recently used, never the part just loaded.
  while (loaded_bytes_ > memory_budget_bytes_ && loaded_.size() > 1) {
    auto oldest = loaded_.end();
    for (auto e = loaded_.begin(); e != loaded_.end(); ++e)
      if (e != it && (oldest == loaded_.end() || e->second.last_used < oldest->second.last_used)) oldest = e;
    loaded_bytes_ -= oldest->second.bytes;
    loaded_.erase(oldest);
    ++evicted_;
  }
  return std::shared_ptr<const LoadedPart>(part);
}

PartRegistry::MemoryStats PartRegistry::memory_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {loaded_.size(), loaded_bytes_, evicted_, memory_budget_bytes_, hits_, loads_, bvh_cache_.stats()};
}

}  // namespace gk::engine
