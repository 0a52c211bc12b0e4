#include "machine_models/p4/sheet_part.h"

#include "kernel/core/tolerances.h"
#include "kernel/core/content_hash.h"
#include "kernel/core/units.h"

#include <cmath>

namespace gk::p4 {
namespace {


// Outward normal of a side, and the axis an up-bend turns about (outward x up).
Vec3 outward(Side s) {
  switch (s) {
    case Side::kXMin: return -Vec3::UnitX();
    case Side::kXMax: return Vec3::UnitX();
    case Side::kYMin: return -Vec3::UnitY();
    case Side::kYMax: return Vec3::UnitY();
  }
  return Vec3::UnitY();
}

const char* side_name(Side s) {
  switch (s) {
    case Side::kXMin: return "x_min";
    case Side::kXMax: return "x_max";
    case Side::kYMin: return "y_min";
    case Side::kYMax: return "y_max";
  }
  return "?";
}

}  // namespace

std::array<Vec3, 8> Plate::corners() const {
  std::array<Vec3, 8> out;
  for (int k = 0; k < 8; ++k)
    out[k] = origin + ((k & 1) ? edge[0] : Vec3::Zero()) + ((k & 2) ? edge[1] : Vec3::Zero()) +
             ((k & 4) ? edge[2] : Vec3::Zero());
  return out;
}

Plate Plate::transformed(const RigidTransform& t) const {
  Plate p = *this;
  p.origin = t.apply(origin);
  for (Vec3& e : p.edge) e = t.apply_direction(e);
  return p;
}

Result<SheetPart> SheetPart::create(const SheetPartSpec& spec) {
  for (auto [value, field] : {std::pair{spec.width_mm, "width_mm"}, std::pair{spec.depth_mm, "depth_mm"},
                              std::pair{spec.thickness_mm, "thickness_mm"}})
    if (!(value > 0.0) || !(value <= tolerances::kMaxMachineLengthMm))
      return invalid_argument(field, "must be a positive length of at most 1e5 mm");
  // A part of more features than any sheet has is malformed (and would hold a worker for long).
  if (spec.flanges.size() > 100) return invalid_argument("flanges", "at most 100 flanges");
  if (spec.tabs.size() > 1000) return invalid_argument("tabs", "at most 1000 tabs");
  SheetPart part;
  part.thickness_ = spec.thickness_mm;
  const double t = spec.thickness_mm;
  part.plates_.push_back({Vec3::Zero(), {Vec3(spec.width_mm, 0, 0), Vec3(0, spec.depth_mm, 0), Vec3(0, 0, t)}, "blank"});
  for (std::size_t i = 0; i < spec.flanges.size(); ++i) {
    const FlangeSpec& f = spec.flanges[i];
    const std::string field = "flanges[" + std::to_string(i) + "]";
    if (!(f.height_mm > 0.0) || !(f.height_mm <= tolerances::kMaxMachineLengthMm))
      return invalid_argument(field + ".height_mm", "must be positive and at most 1e5 mm");
    if (!std::isfinite(f.start_mm) || !(f.length_mm >= 0.0) || !(f.length_mm <= tolerances::kMaxMachineLengthMm))
      return invalid_argument(field + ".length_mm", "start_mm must be finite, length_mm in [0, 1e5] mm (0: the whole edge)");
    if (!std::isfinite(f.angle_deg) || f.angle_deg == 0.0 || std::fabs(f.angle_deg) >= 180.0)
      return invalid_argument(field + ".angle_deg", "must be non-zero and within (-180, 180) degrees");
    const bool along_x = f.side == Side::kYMin || f.side == Side::kYMax;
    const double edge_length = along_x ? spec.width_mm : spec.depth_mm;
    const double length = f.length_mm > 0.0 ? f.length_mm : edge_length - f.start_mm;
    if (f.start_mm < 0.0 || !(length > 0.0) || f.start_mm + length > edge_length + tolerances::kMachineLengthSlackMm)
      return invalid_argument(field + ".length_mm", "the flange must lie on its edge");
    const Vec3 n = outward(f.side);
    const Vec3 along = along_x ? Vec3::UnitX() : Vec3::UnitY();
    // The edge line on the blank's lower face, and the flat flange beyond it.
    Vec3 edge_point = Vec3::Zero();
    if (f.side == Side::kXMax) edge_point.x() = spec.width_mm;
    if (f.side == Side::kYMax) edge_point.y() = spec.depth_mm;
    Plate flat;
    flat.origin = edge_point + along * f.start_mm + (n.sum() < 0.0 ? Vec3(n * f.height_mm) : Vec3::Zero());
    flat.edge = {along * length, n.cwiseAbs() * f.height_mm, Vec3(0, 0, t)};
    flat.label = std::string("flange.") + side_name(f.side) + "." + std::to_string(i);
    // Up-bends turn about the upper edge, down-bends about the lower one.
    const bool up = f.angle_deg > 0.0;
    const Vec3 hinge = edge_point + Vec3(0, 0, up ? t : 0.0);
    const Vec3 axis = n.cross(Vec3::UnitZ());
    const RigidTransform turn = RigidTransform::from_translation(hinge) *
                                RigidTransform::from_axis_angle(axis, f.angle_deg * kPi / 180.0) *
                                RigidTransform::from_translation(-hinge);
    part.plates_.push_back(flat.transformed(turn));
  }
  for (std::size_t i = 0; i < spec.tabs.size(); ++i) {
    const TabSpec& tab = spec.tabs[i];
    const std::string field = "tabs[" + std::to_string(i) + "]";
    if (!(tab.x_max_mm > tab.x_min_mm) || tab.x_min_mm < 0.0 || tab.x_max_mm > spec.width_mm)
      return invalid_argument(field + ".x_mm", "must be an interval inside the blank's width");
    if (!(tab.y_mm >= 0.0) || tab.y_mm + t > spec.depth_mm) return invalid_argument(field + ".y_mm", "must lie on the blank");
    if (!(tab.height_mm > 0.0) || !(tab.height_mm <= tolerances::kMaxMachineLengthMm))
      return invalid_argument(field + ".height_mm", "must be positive and at most 1e5 mm");
    part.plates_.push_back({Vec3(tab.x_min_mm, tab.y_mm, t),
                            {Vec3(tab.x_max_mm - tab.x_min_mm, 0, 0), Vec3(0, t, 0), Vec3(0, 0, tab.height_mm)},
                            "tab." + std::to_string(i)});
  }
  part.hash_ = part.compute_hash();
  return part;
}

SheetPart SheetPart::from_plates(std::vector<Plate> plates, double thickness_mm) {
  SheetPart p;
  p.plates_ = std::move(plates);
  p.thickness_ = thickness_mm;
  p.hash_ = p.compute_hash();
  return p;
}

Result<SheetPart> SheetPart::from_surface(TriangleMesh surface, double thickness_mm, double deflection_mm) {
  if (!(thickness_mm > 0.0) || !(thickness_mm <= tolerances::kMaxMachineLengthMm))
    return invalid_argument("thickness_mm", "must be a positive length of at most 1e5 mm");
  if (!(deflection_mm >= 0.0) || !(deflection_mm <= 1000.0)) return invalid_argument("deflection_mm", "must be in [0, 1000] mm");
  SheetPart part;
  part.thickness_ = thickness_mm;
  part.deflection_ = deflection_mm;
  part.surface_ = std::make_shared<const TriangleMesh>(std::move(surface));
  part.hash_ = part.compute_hash();
  return part;
}

std::vector<Vec3> SheetPart::extent_points() const {
  if (surface_) return surface_->vertices();
  std::vector<Vec3> out;
  out.reserve(8 * plates_.size());
  for (const Plate& p : plates_)
    for (const Vec3& c : p.corners()) out.push_back(c);
  return out;
}

namespace {

// Keeps the part of polygon `poly` where s(x) >= 0 (one Sutherland-Hodgman step).
std::vector<Vec3> clip_polygon(const std::vector<Vec3>& poly, const Vec3& n, const Vec3& q, double offset) {
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec3& a = poly[i];
    const Vec3& b = poly[(i + 1) % poly.size()];
    const double sa = n.dot(a - q) - offset, sb = n.dot(b - q) - offset;
    if (sa >= 0.0) out.push_back(a);
    if ((sa >= 0.0) != (sb >= 0.0)) out.push_back(a + (sa / (sa - sb)) * (b - a));
  }
  return out;
}

}  // namespace

Result<bool> SheetPart::split_surface(const Vec2& point, const Vec2& direction, double offset_mm,
                                      std::vector<Vec3>& moving_vertices, std::vector<TriangleMesh::Face>& moving_faces,
                                      std::vector<Vec3>& fixed_vertices, std::vector<TriangleMesh::Face>& fixed_faces) const {
  if (!surface_) return invalid_argument("part", "has no surface");
  if (!point.allFinite()) return invalid_argument("bend_line.point", "not finite");
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("bend_line.direction", "must be a non-zero vector");
  const Vec2 d = direction.normalized();
  const Vec3 n(-d.y(), d.x(), 0.0), q(point.x(), point.y(), 0.0);
  moving_vertices.clear();
  moving_faces.clear();
  fixed_vertices.clear();
  fixed_faces.clear();
  auto add = [](const std::vector<Vec3>& kept, std::vector<Vec3>& vertices, std::vector<TriangleMesh::Face>& faces) {
    if (kept.size() < 3) return;
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), kept.begin(), kept.end());
    for (std::uint32_t k = 1; k + 1 < kept.size(); ++k) faces.push_back({base, base + k, base + k + 1});
  };
  for (std::size_t t = 0; t < surface_->triangle_count(); ++t) {
    const Triangle tri = surface_->triangle(t);
    add(clip_polygon({tri[0], tri[1], tri[2]}, n, q, offset_mm), moving_vertices, moving_faces);
    add(clip_polygon({tri[0], tri[1], tri[2]}, -n, q, -offset_mm), fixed_vertices, fixed_faces);
  }
  return true;
}

TriangleMesh plates_mesh(const std::vector<Plate>& plates) {
  std::vector<Vec3> v;
  std::vector<TriangleMesh::Face> f;
  v.reserve(8 * plates.size());
  f.reserve(12 * plates.size());
  // Box faces for corner numbering k = a + 2b + 4c, wound outward for a right-handed edge triple.
  static const std::uint32_t kFaces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                                              {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (const Plate& p : plates) {
    const auto base = static_cast<std::uint32_t>(v.size());
    for (const Vec3& c : p.corners()) v.push_back(c);
    const bool right_handed = p.edge[0].cross(p.edge[1]).dot(p.edge[2]) > 0.0;
    for (const auto& face : kFaces) {
      if (right_handed) f.push_back({base + face[0], base + face[1], base + face[2]});
      else f.push_back({base + face[0], base + face[2], base + face[1]});
    }
  }
  return TriangleMesh::create(std::move(v), std::move(f)).value();
}

TriangleMesh SheetPart::mesh(std::vector<int>* plate_of_triangle) const {
  if (plate_of_triangle) {
    plate_of_triangle->clear();
    for (std::size_t i = 0; i < plates_.size(); ++i) plate_of_triangle->insert(plate_of_triangle->end(), 12, static_cast<int>(i));
  }
  return plates_mesh(plates_);
}

Hash128 SheetPart::compute_hash() const {
  ContentHash h;
  h.add(thickness_);
  if (surface_) {
    h.add({deflection_, static_cast<double>(surface_->triangle_count())});
    for (const Vec3& v : surface_->vertices()) h.add({v.x(), v.y(), v.z()});
    for (const auto& f : surface_->faces()) h.add({double(f[0]), double(f[1]), double(f[2])});
  }
  for (const Plate& p : plates_) {
    h.add({p.origin.x(), p.origin.y(), p.origin.z()});
    for (const Vec3& e : p.edge) h.add({e.x(), e.y(), e.z()});
  }
  return h.value();
}

Result<bool> SheetPart::split(const Vec2& point, const Vec2& direction, double offset_mm, std::vector<Plate>& moving,
                              std::vector<Plate>& fixed) const {
  if (!point.allFinite()) return invalid_argument("bend_line.point", "not finite");
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("bend_line.direction", "must be a non-zero vector");
  const Vec2 d = direction.normalized();
  const Vec3 n(-d.y(), d.x(), 0.0);  // left of the direction: the moving side
  const Vec3 q(point.x(), point.y(), 0.0);
  moving.clear();
  fixed.clear();
  for (const Plate& p : plates_) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& c : p.corners()) {
      const double s = n.dot(c - q);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    if (lo >= offset_mm - tolerances::kMachineLengthSlackMm) {
      moving.push_back(p);
      continue;
    }
    if (hi <= offset_mm + tolerances::kMachineLengthSlackMm) {  // on the held side, or in the bend zone (held, checked where it stands)
      fixed.push_back(p);
      continue;
    }
    // The plane crosses the plate: it must cut one edge direction square.
    int k = -1;
    for (int e = 0; e < 3; ++e)
      if (std::fabs(std::fabs(n.dot(p.edge[e])) - p.edge[e].norm()) <= tolerances::kComparisonSlackRelative * std::max(1.0, p.edge[e].norm())) k = e;
    if (k < 0) return invalid_argument("bend_line", "crosses plate '" + p.label + "' obliquely");
    const double s0 = n.dot(p.origin - q), rate = n.dot(p.edge[k]);
    auto piece = [&](double s_from, double s_to) {  // the part of p with s in [s_from, s_to]
      double a0 = (s_from - s0) / rate, a1 = (s_to - s0) / rate;
      if (a0 > a1) std::swap(a0, a1);
      a0 = std::max(a0, 0.0);
      a1 = std::min(a1, 1.0);
      Plate out = p;
      out.origin = p.origin + a0 * p.edge[k];
      out.edge[k] = (a1 - a0) * p.edge[k];
      return std::pair<Plate, bool>(out, a1 - a0 > 1e-12);
    };
    if (auto [part, ok] = piece(lo - 1.0, offset_mm); ok) fixed.push_back(part);
    if (auto [part, ok] = piece(offset_mm, hi + 1.0); ok) moving.push_back(part);
  }
  return true;
}

SheetPart SheetPart::turned_over(const Vec2& point, const Vec2& axis) const {
  const Vec3 a(axis.x(), axis.y(), 0.0);
  const Vec3 c(point.x(), point.y(), 0.5 * thickness_);
  const RigidTransform flip = RigidTransform::from_translation(c) * RigidTransform::from_axis_angle(a, kPi) *
                              RigidTransform::from_translation(-c);
  SheetPart out;
  out.thickness_ = thickness_;
  out.deflection_ = deflection_;
  for (const Plate& p : plates_) out.plates_.push_back(p.transformed(flip));
  if (surface_) {
    std::vector<Vec3> v = surface_->vertices();
    for (Vec3& x : v) x = flip.apply(x);
    // A rotation keeps the winding outward: only the positions change.
    TriangleMesh turned = *surface_;
    (void)turned.set_vertices(std::move(v));
    out.surface_ = std::make_shared<const TriangleMesh>(std::move(turned));
  }
  out.hash_ = out.compute_hash();
  return out;
}

}  // namespace gk::p4
