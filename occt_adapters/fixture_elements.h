// Modular fixture elements built with OCCT (seed 004's catalogue): parametric, with realistic
// dimensions, and with the hole grids and slots that carry most of their triangles once meshed
// (the paper's Table 1). Each element stands on z = 0 in its own frame (a base plate's top face is
// z = 0), x and y along its length and width. Hole-system plates carry a grid of through holes,
// slot-system plates T-slots along x.
#pragma once

#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

namespace gk::occt {

struct HoleGrid {
  int columns = 0, rows = 0;  // holes along x and along y
  double pitch_mm = 50.0;     // between hole centres
  double diameter_mm = 12.0;
};

// A base plate, top face at z = 0: with a grid of through holes (hole system) or with T-slots along
// x (slot system, slots > 0: slot width at the top, undercut twice as wide below).
Result<Shape> base_plate(double length_mm, double width_mm, double thickness_mm, const HoleGrid& holes, int slots = 0,
                         double slot_width_mm = 14.0);
// A block (support, spacer) with a grid of vertical through holes.
Result<Shape> block_element(double length_mm, double width_mm, double height_mm, const HoleGrid& holes);
// A cylindrical support with a coaxial through hole.
Result<Shape> cylinder_element(double diameter_mm, double height_mm, double hole_diameter_mm);
// A locator: a cylindrical body with a collar at its foot and a thinner locating pin on top; with a
// spigot (spigot_length_mm > 0), a locating spigot below the collar (z from -length to 0) that goes
// into a base plate's hole.
Result<Shape> locator_element(double body_diameter_mm, double body_height_mm, double pin_diameter_mm, double pin_height_mm,
                              double spigot_diameter_mm = 0.0, double spigot_length_mm = 0.0);
// A rhombus (diamond) pin: a locating pin relieved on two sides, as used with a round pin so the
// part is not over-constrained.
Result<Shape> rhombus_pin(double diameter_mm, double height_mm, double land_width_mm);
// A hexagon-head bolt: head across flats, shank diameter and length (shank down from z = 0).
Result<Shape> hex_bolt(double across_flats_mm, double head_height_mm, double shank_diameter_mm, double shank_length_mm);
// A hexagon nut with a through hole.
Result<Shape> hex_nut(double across_flats_mm, double height_mm, double hole_diameter_mm);
// A strap clamp: a bar with a slot along it for its bolt.
Result<Shape> strap_clamp(double length_mm, double width_mm, double height_mm, double slot_width_mm);

}  // namespace gk::occt
