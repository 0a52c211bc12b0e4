#include "server/part_registry.h"

#include "mesh_io/mesh_file_reader.h"
#include "occt_adapters/shape_import.h"
#include "occt_adapters/shape_mesher.h"

#include <filesystem>

namespace gk::server {

Result<TriangleMesh> PartRegistry::read_any(const std::string& path, const std::string& format, double deflection_mm) {
  if (is_cad_format(format)) {
    // OCCT picks its reader by extension: give the file one.
    std::string named = path;
    if (std::filesystem::path(path).extension() != "." + format) {
      named = path + "." + format;
      std::error_code ec;
      std::filesystem::create_hard_link(path, named, ec);
      if (ec) std::filesystem::copy_file(path, named, ec);
    }
    auto shape = occt::read_shape_file(named);
    if (named != path) std::filesystem::remove(named);
    if (!shape.ok()) return invalid_argument("data", shape.error().message);
    auto meshed = occt::mesh_shape(shape.value(), deflection_mm);
    if (!meshed.ok()) return invalid_argument("data", meshed.error().to_string());
    return std::move(meshed.value().mesh);
  }
  mesh_io::ReadOptions options;
  options.build.drop_zero_area_triangles = true;
  std::string named = path;
  if (std::filesystem::path(path).extension() != "." + format) {
    named = path + "." + format;
    std::error_code ec;
    std::filesystem::create_hard_link(path, named, ec);
    if (ec) std::filesystem::copy_file(path, named, ec);
  }
  auto mesh = mesh_io::read_mesh_file(named, options);
  if (named != path) std::filesystem::remove(named);
  if (!mesh.ok()) return invalid_argument("data", mesh.error().message);
  return mesh;
}

Result<std::shared_ptr<const LoadedPart>> PartRegistry::load(const std::string& id, double deflection_mm) {
  auto record = store_.get(id);
  if (!record.ok()) return record.error();
  const double key_deflection = is_cad_format(record.value().format) ? deflection_mm : 0.0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = loaded_.find({id, key_deflection});
    if (it != loaded_.end()) return it->second;
  }
  auto mesh = read_any(store_.path_of(record.value()), record.value().format, deflection_mm);
  if (!mesh.ok()) return mesh.error();
  auto part = std::make_shared<LoadedPart>();
  part->record = record.value();
  part->mesh = std::make_shared<const TriangleMesh>(std::move(mesh).value());
  auto bvh = MeshBvh::build(part->mesh);
  if (!bvh.ok()) return bvh.error();
  part->bvh = bvh.value();
  part->deflection_mm = key_deflection;
  std::lock_guard<std::mutex> lock(mutex_);
  loaded_[{id, key_deflection}] = part;
  return std::shared_ptr<const LoadedPart>(part);
}

}  // namespace gk::server
