#include "machine_models/p4/manipulator_geometry.h"

#include <cmath>
#include <string>

namespace gk::p4 {

std::vector<Plate> manipulator_plates(const ManipulatorSpec& spec, const Vec2& point, double rotation_deg,
                                      double sheet_top_z) {
  const double a = rotation_deg * 3.14159265358979323846 / 180.0;
  const Vec3 ex(std::cos(a), std::sin(a), 0.0), ey(-std::sin(a), std::cos(a), 0.0), ez = Vec3::UnitZ();
  const Vec3 centre(point.x(), point.y(), sheet_top_z);
  // A box centred on (cx, cy) in the gripper's frame, from height z0 above the sheet, dz tall.
  auto box = [&](double cx, double cy, double half_x, double half_y, double z0, double dz, std::string label) {
    Plate p;
    p.origin = centre + (cx - half_x) * ex + (cy - half_y) * ey + z0 * ez;
    p.edge = {2.0 * half_x * ex, 2.0 * half_y * ey, dz * ez};
    p.label = std::move(label);
    return p;
  };
  std::vector<Plate> plates;
  for (std::size_t i = 0; i < spec.cup_offsets_mm.size(); ++i)
    plates.push_back(box(spec.cup_offsets_mm[i].x(), spec.cup_offsets_mm[i].y(), spec.cup_half_width_mm,
                         spec.cup_half_width_mm, 0.0, spec.cup_height_mm, "manipulator.cup." + std::to_string(i)));
  plates.push_back(box(0.0, 0.0, spec.frame_half_size_mm.x(), spec.frame_half_size_mm.y(), spec.cup_height_mm,
                       spec.frame_thickness_mm, "manipulator.frame"));
  plates.push_back(box(0.0, 0.0, spec.rotator_radius_mm, spec.rotator_radius_mm,
                       spec.cup_height_mm + spec.frame_thickness_mm, spec.rotator_height_mm, "manipulator.rotator"));
  return plates;
}

}  // namespace gk::p4
