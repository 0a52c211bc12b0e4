// A sheet-metal part given parametrically: a rectangular blank, its thickness, flanges already
// bent along its sides and tabs bent up inside it. Made of plates (boxes), in part coordinates:
// the blank spans X [0, width], Y [0, depth], Z [0, thickness].
#pragma once

#include "kernel/core/content_hash.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <memory>
#include <string>
#include <vector>

namespace gk::p4 {

enum class Side { kXMin, kXMax, kYMin, kYMax };

struct FlangeSpec {
  Side side = Side::kYMax;
  double height_mm = 0.0;  // from the blank's edge
  double angle_deg = 90.0;  // + bent up (towards +Z), - bent down
  double start_mm = 0.0;    // along the edge, from the edge's lower-coordinate end
  double length_mm = 0.0;   // 0: the whole edge
};

// A tab cut inside the blank and bent up: a vertical plate standing on the blank's upper face.
struct TabSpec {
  double x_min_mm = 0.0, x_max_mm = 0.0;  // along X
  double y_mm = 0.0;                      // its foot, across Y
  double height_mm = 0.0;
};

struct SheetPartSpec {
  double width_mm = 0.0;  // X
  double depth_mm = 0.0;  // Y
  double thickness_mm = 0.0;
  std::vector<FlangeSpec> flanges;
  std::vector<TabSpec> tabs;
};

// A box: origin + a*e0 + b*e1 + c*e2 for a, b, c in [0, 1]; e0, e1, e2 mutually perpendicular.
struct Plate {
  Vec3 origin = Vec3::Zero();
  std::array<Vec3, 3> edge{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  std::string label;

  std::array<Vec3, 8> corners() const;
  Plate transformed(const RigidTransform& t) const;
};

class SheetPart {
 public:
  // Validates the spec (positive sizes, angles within (-180, 180), tabs inside the blank).
  static Result<SheetPart> create(const SheetPartSpec& spec);
  static SheetPart from_plates(std::vector<Plate> plates, double thickness_mm);
  // A part given as a B-Rep, by its tessellation (e.g. occt::mesh_shape of a STEP part), in part
  // coordinates: the blank's lower face on Z = 0. The deflection (how far the mesh may lie from
  // the exact surface) is added to every clearance the part is checked with.
  static Result<SheetPart> from_surface(TriangleMesh surface, double thickness_mm, double deflection_mm);
  bool has_surface() const { return surface_ != nullptr; }
  const TriangleMesh& surface() const { return *surface_; }
  double deflection_mm() const { return deflection_; }
  // Points whose extent is the part's: plate corners, or surface vertices.
  std::vector<Vec3> extent_points() const;

  const std::vector<Plate>& plates() const { return plates_; }
  double thickness_mm() const { return thickness_; }
  // All plates as one mesh of closed boxes; plate_of_triangle maps back to plates().
  TriangleMesh mesh(std::vector<int>* plate_of_triangle = nullptr) const;
  // A content hash of the geometry, for memo keys.
  // Of the geometry, computed once when the part is made (a part never changes afterwards).
  Hash128 content_hash() const { return hash_; }

  // Splits the part by the vertical plane through the bend line (point, direction in XY; the
  // moving side lies to the left of the direction). Plates on the moving side beyond offset_mm go
  // to `moving`, the rest to `fixed`: the bend zone in between stays with the held side (it is
  // formed, not swung, and whatever stands in it is checked where it stands).
  // A plate the plane crosses obliquely is an error naming it.
  Result<bool> split(const Vec2& point, const Vec2& direction, double offset_mm, std::vector<Plate>& moving,
                     std::vector<Plate>& fixed) const;

  // The same split for a part given by its surface: triangles are clipped at the planes (the bend
  // zone stays with the held side); each side comes back as a triangle soup (empty when nothing
  // lies there).
  Result<bool> split_surface(const Vec2& point, const Vec2& direction, double offset_mm, std::vector<Vec3>& moving_vertices,
                             std::vector<TriangleMesh::Face>& moving_faces, std::vector<Vec3>& fixed_vertices,
                             std::vector<TriangleMesh::Face>& fixed_faces) const;

  // The part turned over (180 degrees about the in-plane axis through `point` along `axis`),
  // resting again on Z = 0.
  SheetPart turned_over(const Vec2& point, const Vec2& axis) const;

 private:
  std::vector<Plate> plates_;
  double thickness_ = 0.0;
  std::shared_ptr<const TriangleMesh> surface_;
  double deflection_ = 0.0;
  Hash128 hash_;
  Hash128 compute_hash() const;
};

TriangleMesh plates_mesh(const std::vector<Plate>& plates);

}  // namespace gk::p4
