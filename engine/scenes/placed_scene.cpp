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

}  // namespace gk::engine
