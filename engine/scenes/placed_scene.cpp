#include "engine/scenes/placed_scene.h"

namespace gk::engine {

Result<PlacedObject> place_object(const SceneObjectRecord& o, PartRegistry& parts) {
  auto part = parts.load(o.part_id, kPartDeflectionMm);
  if (!part.ok()) return Error{part.error().code, "objects[" + o.id + "].part_id", part.error().message};
  const RigidTransform pose = o.pose.transform();
  return PlacedObject{&o, part.value(), pose, transformed_box(part.value()->mesh->bounds(), pose)};
}

Result<PlacedScene> place_scene(const SceneRecord& scene, PartRegistry& parts) {
  PlacedScene out;
  for (const auto& [id, o] : scene.objects) {
    auto p = place_object(o, parts);
    if (!p.ok()) return p.error();
    out.index_of[id] = static_cast<std::uint32_t>(out.objects.size());
    out.objects.push_back({o.name, o.category, o.group, p.value().part->bvh, p.value().pose, p.value().part->deflection_mm});
    out.parts.push_back(p.value().part);
    out.records.push_back(&o);
    out.boxes.push_back(p.value().box);
  }
  return out;
}

Result<PlacedScene> place_scene_packed(const SceneRecord& scene, PartRegistry& parts, const std::string& pack_dir) {
  PlacedScene out;
  std::map<std::string, std::pair<PackedMeshFile, double>> packs;  // part id -> its pack, its deflection
  for (const auto& [id, o] : scene.objects) {
    auto known = packs.find(o.part_id);
    if (known == packs.end()) {
      auto part = parts.load(o.part_id, kPartDeflectionMm);
      if (!part.ok()) return Error{part.error().code, "objects[" + o.id + "].part_id", part.error().message};
      auto file = write_packed_mesh(*part.value()->bvh, pack_dir);
      if (!file.ok()) return file.error();
      known = packs.emplace(o.part_id, std::make_pair(file.value(), part.value()->deflection_mm)).first;
    }
    const RigidTransform pose = o.pose.transform();
    AuditObject object{o.name, o.category, o.group, nullptr, pose, known->second.second};
    object.packed = known->second.first;
    out.index_of[id] = static_cast<std::uint32_t>(out.objects.size());
    out.boxes.push_back(transformed_box(object.packed->bounds, pose));
    out.objects.push_back(std::move(object));
    out.parts.push_back(nullptr);
    out.records.push_back(&o);
  }
  return out;
}

}  // namespace gk::engine
