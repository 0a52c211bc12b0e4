#include "machine_models/p4/plate_shapes.h"

#include "occt_adapters/shape_builders.h"

namespace gk::p4 {

Result<occt::Shape> plates_shape(const std::vector<Plate>& plates, const RigidTransform& pose) {
  std::vector<occt::Shape> boxes;
  for (const Plate& p : plates) {
    // A plate is a box with perpendicular edges; make it right-handed by walking an edge backwards.
    Plate q = p;
    if (q.edge[0].cross(q.edge[1]).dot(q.edge[2]) < 0.0) {
      q.origin += q.edge[2];
      q.edge[2] = -q.edge[2];
    }
    RigidTransform frame;
    for (int k = 0; k < 3; ++k) frame.rotation.col(k) = q.edge[k].normalized();
    frame.translation = q.origin;
    auto box = occt::make_box(Vec3::Zero(), Vec3(q.edge[0].norm(), q.edge[1].norm(), q.edge[2].norm()));
    if (!box.ok()) return box.error();
    auto placed = occt::place(box.value(), pose * frame);
    if (!placed.ok()) return placed.error();
    boxes.push_back(placed.value());
  }
  return occt::make_compound(boxes);
}

}  // namespace gk::p4
