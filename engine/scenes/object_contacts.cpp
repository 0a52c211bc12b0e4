#include "engine/scenes/object_contacts.h"

#include "engine/scenes/placed_scene.h"
#include "engine/verdicts/pair_verdict.h"

#include <cmath>

namespace gk::engine {

Result<MoveOutcome> object_contacts(const SceneRecord& scene, const std::string& object_id, double clearance_mm,
                                    PartRegistry& parts, const StopToken& stop) {
  if (!std::isfinite(clearance_mm) || clearance_mm < 0.0) return invalid_argument("clearance_mm", "must be >= 0");
  auto self_it = scene.objects.find(object_id);
  if (self_it == scene.objects.end()) return Error{ErrorCode::kNotFound, "object_id", "no object '" + object_id + "'"};
  auto self = place_object(self_it->second, parts);
  if (!self.ok()) return self.error();
  MoveOutcome out;
  for (const auto& [id, other] : scene.objects) {
    if (id == object_id) continue;
    if (stop.stop_requested()) return stopped("the moved object's contacts");
    auto placed = place_object(other, parts);
    if (!placed.ok()) return placed.error();
    // Boxes of triangles: a CAD part's true surface may stand out of its tessellation's box.
    const double deviation = self.value().part->deflection_mm + placed.value().part->deflection_mm;
    if (!placed.value().box.overlaps(self.value().box.expanded(clearance_mm + deviation))) continue;
    ++out.candidates;
    auto v = decide_contact({self.value().part.get(), self.value().pose}, {placed.value().part.get(), placed.value().pose},
                      clearance_mm, stop);
    if (!v.ok()) return v.error();
    if (!v.value()) continue;
    const engine::PairVerdict& pv = *v.value();
    const VerdictResult& r = pv.result;
    out.contacts.push_back({id, r.verdict, r.distance_mm, r.point_a, r.point_b, r.inconclusive_reason, pv.decided_on_brep});
    if (severity(r.verdict) > severity(out.verdict)) out.verdict = r.verdict;
  }
  return out;
}

}  // namespace gk::engine
