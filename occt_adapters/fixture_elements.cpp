#include "occt_adapters/fixture_elements.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/shape_impl.h"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRep_Builder.hxx>
#include <TopoDS_Compound.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pnt2d.hxx>

#include <cmath>
#include <functional>
#include <vector>

namespace gk::occt {
namespace {

constexpr double kPiHere = 3.14159265358979323846;

TopoDS_Shape box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return BRepPrimAPI_MakeBox(gp_Pnt(x0, y0, z0), gp_Pnt(x1, y1, z1)).Shape();
}

// A vertical cylinder from z0 up by height, centred at (x, y).
TopoDS_Shape cylinder(double x, double y, double z0, double radius, double height) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, y, z0), gp_Dir(0, 0, 1)), radius, height).Shape();
}

// A vertical prism over a closed polygon in (x, y), from z0 up by height.
TopoDS_Shape vertical_prism(const std::vector<gp_Pnt2d>& polygon, double z0, double height) {
  BRepBuilderAPI_MakePolygon wire;
  for (const gp_Pnt2d& p : polygon) wire.Add(gp_Pnt(p.X(), p.Y(), z0));
  wire.Close();
  const TopoDS_Face face = BRepBuilderAPI_MakeFace(wire.Wire(), true).Face();
  return BRepPrimAPI_MakePrism(face, gp_Vec(0, 0, height)).Shape();
}

std::vector<gp_Pnt2d> hexagon(double across_flats) {
  const double r = across_flats / std::sqrt(3.0);  // corner radius
  std::vector<gp_Pnt2d> out;
  for (int k = 0; k < 6; ++k) out.emplace_back(r * std::cos(kPiHere / 3.0 * k), r * std::sin(kPiHere / 3.0 * k));
  return out;
}

TopoDS_Shape compound(const std::vector<TopoDS_Shape>& shapes) {
  TopoDS_Compound c;
  BRep_Builder b;
  b.MakeCompound(c);
  for (const TopoDS_Shape& s : shapes) b.Add(c, s);
  return c;
}

// The grid of vertical holes through [z0, z0 + height], centred on the rectangle [0, length] x [0, width].
TopoDS_Shape hole_cutters(double length, double width, double z0, double height, const HoleGrid& holes) {
  std::vector<TopoDS_Shape> cutters;
  const double x0 = 0.5 * (length - (holes.columns - 1) * holes.pitch_mm), y0 = 0.5 * (width - (holes.rows - 1) * holes.pitch_mm);
  for (int i = 0; i < holes.columns; ++i)
    for (int j = 0; j < holes.rows; ++j)
      cutters.push_back(cylinder(x0 + i * holes.pitch_mm, y0 + j * holes.pitch_mm, z0 - 1.0, 0.5 * holes.diameter_mm, height + 2.0));
  return compound(cutters);
}

Result<Shape> built(const std::string& what, const std::function<TopoDS_Shape()>& make) {
  TopoDS_Shape s;
  auto ran = guarded(what, "building a fixture element", [&] { s = make(); });
  if (!ran.ok()) return ran.error();
  if (s.IsNull()) return invalid_argument(what, "OCCT built nothing");
  return wrap(s);
}

bool positive(std::initializer_list<double> values) {
  for (double v : values)
    if (!(v > 0.0) || !std::isfinite(v)) return false;
  return true;
}

}  // namespace

Result<Shape> base_plate(double length_mm, double width_mm, double thickness_mm, const HoleGrid& holes, int slots,
                         double slot_width_mm) {
  if (!positive({length_mm, width_mm, thickness_mm, holes.pitch_mm, holes.diameter_mm, slot_width_mm}) || slots < 0)
    return invalid_argument("base_plate", "sizes must be positive and finite");
  return built("base_plate", [&] {
    TopoDS_Shape plate = box(0, 0, -thickness_mm, length_mm, width_mm, 0);
    if (holes.columns > 0 && holes.rows > 0)
      plate = BRepAlgoAPI_Cut(plate, hole_cutters(length_mm, width_mm, -thickness_mm, thickness_mm, holes)).Shape();
    if (slots > 0) {
      std::vector<TopoDS_Shape> cutters;
      const double pitch = width_mm / (slots + 1), depth = 0.6 * thickness_mm;
      for (int k = 1; k <= slots; ++k) {
        const double y = k * pitch;
        cutters.push_back(box(-1, y - 0.5 * slot_width_mm, -0.5 * depth, length_mm + 1, y + 0.5 * slot_width_mm, 1));
        cutters.push_back(box(-1, y - slot_width_mm, -depth, length_mm + 1, y + slot_width_mm, -0.5 * depth));
      }
      plate = BRepAlgoAPI_Cut(plate, compound(cutters)).Shape();
    }
    return plate;
  });
}

Result<Shape> block_element(double length_mm, double width_mm, double height_mm, const HoleGrid& holes) {
  if (!positive({length_mm, width_mm, height_mm})) return invalid_argument("block", "sizes must be positive and finite");
  return built("block", [&] {
    TopoDS_Shape block = box(0, 0, 0, length_mm, width_mm, height_mm);
    if (holes.columns > 0 && holes.rows > 0) block = BRepAlgoAPI_Cut(block, hole_cutters(length_mm, width_mm, 0, height_mm, holes)).Shape();
    return block;
  });
}

Result<Shape> cylinder_element(double diameter_mm, double height_mm, double hole_diameter_mm) {
  if (!positive({diameter_mm, height_mm, hole_diameter_mm}) || hole_diameter_mm >= diameter_mm)
    return invalid_argument("cylinder", "sizes must be positive, the hole narrower than the cylinder");
  return built("cylinder", [&] {
    return BRepAlgoAPI_Cut(cylinder(0, 0, 0, 0.5 * diameter_mm, height_mm), cylinder(0, 0, -1, 0.5 * hole_diameter_mm, height_mm + 2)).Shape();
  });
}

Result<Shape> locator_element(double body_diameter_mm, double body_height_mm, double pin_diameter_mm, double pin_height_mm,
                              double spigot_diameter_mm, double spigot_length_mm) {
  if (!positive({body_diameter_mm, body_height_mm, pin_diameter_mm, pin_height_mm}) || pin_diameter_mm >= body_diameter_mm)
    return invalid_argument("locator", "sizes must be positive, the pin narrower than the body");
  const bool spigot = spigot_length_mm > 0.0;
  if (spigot_length_mm < 0.0 || !std::isfinite(spigot_length_mm) ||
      (spigot && !(spigot_diameter_mm > 0.0 && spigot_diameter_mm < body_diameter_mm && std::isfinite(spigot_diameter_mm))))
    return invalid_argument("locator", "a spigot's sizes must be positive, the spigot narrower than the body");
  return built("locator", [&] {
    const TopoDS_Shape collar = cylinder(0, 0, 0, 0.65 * body_diameter_mm, 0.15 * body_height_mm);
    const TopoDS_Shape body = cylinder(0, 0, 0, 0.5 * body_diameter_mm, body_height_mm);
    const TopoDS_Shape pin = cylinder(0, 0, body_height_mm, 0.5 * pin_diameter_mm, pin_height_mm);
    TopoDS_Shape locator = BRepAlgoAPI_Fuse(BRepAlgoAPI_Fuse(collar, body).Shape(), pin).Shape();
    if (spigot) locator = BRepAlgoAPI_Fuse(locator, cylinder(0, 0, -spigot_length_mm, 0.5 * spigot_diameter_mm, spigot_length_mm)).Shape();
    return locator;
  });
}

Result<Shape> rhombus_pin(double diameter_mm, double height_mm, double land_width_mm) {
  if (!positive({diameter_mm, height_mm, land_width_mm}) || land_width_mm >= diameter_mm)
    return invalid_argument("rhombus_pin", "sizes must be positive, the land narrower than the pin");
  return built("rhombus_pin", [&] {
    // The round pin less two flats either side of the land, leaving a diamond-like section.
    const double r = 0.5 * diameter_mm, w = 0.5 * land_width_mm;
    std::vector<gp_Pnt2d> relief_a = {{w, r + 1}, {r + 1, w}, {r + 1, r + 1}};
    std::vector<gp_Pnt2d> relief_b = {{-w, -r - 1}, {-r - 1, -w}, {-r - 1, -r - 1}};
    std::vector<gp_Pnt2d> relief_c = {{-w, r + 1}, {-r - 1, r + 1}, {-r - 1, w}};
    std::vector<gp_Pnt2d> relief_d = {{w, -r - 1}, {r + 1, -r - 1}, {r + 1, -w}};
    TopoDS_Shape pin = cylinder(0, 0, 0, r, height_mm);
    pin = BRepAlgoAPI_Cut(pin, compound({vertical_prism(relief_a, -1, height_mm + 2), vertical_prism(relief_b, -1, height_mm + 2),
                                         vertical_prism(relief_c, -1, height_mm + 2), vertical_prism(relief_d, -1, height_mm + 2)}))
              .Shape();
    return pin;
  });
}

Result<Shape> hex_bolt(double across_flats_mm, double head_height_mm, double shank_diameter_mm, double shank_length_mm) {
  if (!positive({across_flats_mm, head_height_mm, shank_diameter_mm, shank_length_mm}) || shank_diameter_mm >= across_flats_mm)
    return invalid_argument("hex_bolt", "sizes must be positive, the shank narrower than the head");
  return built("hex_bolt", [&] {
    return BRepAlgoAPI_Fuse(vertical_prism(hexagon(across_flats_mm), 0, head_height_mm),
                            cylinder(0, 0, -shank_length_mm, 0.5 * shank_diameter_mm, shank_length_mm + 0.5 * head_height_mm))
        .Shape();
  });
}

Result<Shape> hex_nut(double across_flats_mm, double height_mm, double hole_diameter_mm) {
  if (!positive({across_flats_mm, height_mm, hole_diameter_mm}) || hole_diameter_mm >= across_flats_mm)
    return invalid_argument("hex_nut", "sizes must be positive, the hole narrower than the nut");
  return built("hex_nut", [&] {
    return BRepAlgoAPI_Cut(vertical_prism(hexagon(across_flats_mm), 0, height_mm), cylinder(0, 0, -1, 0.5 * hole_diameter_mm, height_mm + 2)).Shape();
  });
}

Result<Shape> strap_clamp(double length_mm, double width_mm, double height_mm, double slot_width_mm) {
  if (!positive({length_mm, width_mm, height_mm, slot_width_mm}) || slot_width_mm >= width_mm)
    return invalid_argument("strap_clamp", "sizes must be positive, the slot narrower than the bar");
  return built("strap_clamp", [&] {
    const TopoDS_Shape bar = box(0, -0.5 * width_mm, 0, length_mm, 0.5 * width_mm, height_mm);
    const TopoDS_Shape slot = box(0.2 * length_mm, -0.5 * slot_width_mm, -1, 0.7 * length_mm, 0.5 * slot_width_mm, height_mm + 1);
    return BRepAlgoAPI_Cut(bar, slot).Shape();
  });
}

}  // namespace gk::occt
