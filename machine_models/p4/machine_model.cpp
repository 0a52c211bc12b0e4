#include "machine_models/p4/machine_model.h"

#include "kernel/core/tolerances.h"

#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace gk::p4 {
namespace {

Result<double> number(const toml::table& t, const std::string& key, const std::string& field) {
  const auto v = t[key].value<double>();
  if (!v) return invalid_argument(field, "missing or not a number");
  if (!std::isfinite(*v) || std::fabs(*v) > tolerances::kMaxMachineLengthMm)
    return invalid_argument(field, "must be finite and within 1e5 (mm or degrees)");
  return *v;
}

Result<double> positive(const toml::table& t, const std::string& key, const std::string& field) {
  auto v = number(t, key, field);
  if (v.ok() && !(v.value() > 0.0)) return invalid_argument(field, "must be positive");
  return v;
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// A convex polygon with at least three corners, turned counter-clockwise if given clockwise.
Result<std::vector<Vec2>> convex_profile(const toml::node* node, const std::string& field) {
  const toml::array* arr = node ? node->as_array() : nullptr;
  if (!arr || arr->size() < 3) return invalid_argument(field, "needs at least three [y, z] points");
  std::vector<Vec2> pts;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::array* p = (*arr)[i].as_array();
    const std::string f = field + "[" + std::to_string(i) + "]";
    if (!p || p->size() != 2) return invalid_argument(f, "must be a [y, z] pair");
    const auto y = (*p)[0].value<double>(), z = (*p)[1].value<double>();
    if (!y || !z || !(std::fabs(*y) <= tolerances::kMaxMachineLengthMm) || !(std::fabs(*z) <= tolerances::kMaxMachineLengthMm))
      return invalid_argument(f, "must be two finite numbers within 1e5 mm");
    pts.emplace_back(*y, *z);
  }
  double area2 = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) area2 += cross2(pts[i], pts[(i + 1) % pts.size()]);
  if (area2 == 0.0) return invalid_argument(field, "profile has no area");
  if (area2 < 0.0) std::reverse(pts.begin(), pts.end());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2& a = pts[i];
    const Vec2& b = pts[(i + 1) % pts.size()];
    const Vec2& c = pts[(i + 2) % pts.size()];
    if (cross2(b - a, c - b) < 0.0) return invalid_argument(field, "profile must be convex");
  }
  return pts;
}

}  // namespace

double MachineModel::slot_x_min(std::size_t i) const {
  double total = 0.0;
  for (double w : aba.segment_widths_mm) total += w;
  total += aba.gap_mm * static_cast<double>(aba.segment_widths_mm.size() - 1);
  double x = -0.5 * total;
  for (std::size_t k = 0; k < i; ++k) x += aba.segment_widths_mm[k] + aba.gap_mm;
  return x;
}

double MachineModel::slot_x_max(std::size_t i) const { return slot_x_min(i) + aba.segment_widths_mm[i]; }

std::vector<std::pair<double, double>> MachineModel::slot_spans() const {
  std::vector<std::pair<double, double>> spans;
  spans.reserve(aba.segment_widths_mm.size());
  if (aba.segment_widths_mm.empty()) return spans;
  double x = slot_x_min(0);
  for (double w : aba.segment_widths_mm) {
    spans.emplace_back(x, x + w);
    x += w + aba.gap_mm;
  }
  return spans;
}

Result<MachineModel> parse_machine_model(const std::string& toml_text) {
  toml::table root;
  try {
    root = toml::parse(toml_text);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << "line " << e.source().begin.line << ", column " << e.source().begin.column;
    return invalid_argument("model (" + where.str() + ")", std::string(e.description()));
  }
  MachineModel m;
  const toml::table* machine = root["machine"].as_table();
  if (!machine) return invalid_argument("machine", "missing [machine] table");
  m.name = (*machine)["name"].value_or(std::string("unnamed"));
#define GK_READ(dst, table, key, reader)                              \
  {                                                                    \
    auto v = reader(*table, key, std::string(#table ".") + key);       \
    if (!v.ok()) return v.error();                                     \
    dst = v.value();                                                   \
  }
  GK_READ(m.max_bend_length_mm, machine, "max_bend_length_mm", positive)
  GK_READ(m.max_bend_height_mm, machine, "max_bend_height_mm", positive)
  GK_READ(m.min_thickness_mm, machine, "min_thickness_mm", positive)
  GK_READ(m.max_thickness_mm, machine, "max_thickness_mm", positive)
  GK_READ(m.max_bend_angle_deg, machine, "max_bend_angle_deg", positive)
  GK_READ(m.bend_zone_mm, machine, "bend_zone_mm", number)
  GK_READ(m.aba_lift_for_rotation_mm, machine, "aba_lift_for_rotation_mm", number)
  if (m.max_bend_angle_deg > 180.0) return invalid_argument("machine.max_bend_angle_deg", "must be at most 180");
  if (m.min_thickness_mm > m.max_thickness_mm) return invalid_argument("machine.min_thickness_mm", "exceeds max_thickness_mm");

  const toml::table* aba = root["aba"].as_table();
  if (!aba) return invalid_argument("aba", "missing [aba] table");
  const toml::array* widths = (*aba)["segment_widths_mm"].as_array();
  if (!widths || widths->empty()) return invalid_argument("aba.segment_widths_mm", "needs at least one segment");
  for (std::size_t i = 0; i < widths->size(); ++i) {
    const auto w = (*widths)[i].value<double>();
    if (!w || !(*w > 0.0) || !(*w <= tolerances::kMaxMachineLengthMm))
      return invalid_argument("aba.segment_widths_mm[" + std::to_string(i) + "]", "must be a positive width");
    m.aba.segment_widths_mm.push_back(*w);
  }
  GK_READ(m.aba.gap_mm, aba, "gap_mm", number)
  GK_READ(m.aba.retract_z_mm, aba, "retract_z_mm", number)
  auto aba_profile = convex_profile(root["aba"]["profile_yz_mm"].node(), "aba.profile_yz_mm");
  if (!aba_profile.ok()) return aba_profile.error();
  m.aba.profile_yz_mm = aba_profile.value();

  if (const toml::array* organs = root["organ"].as_array()) {
    for (std::size_t i = 0; i < organs->size(); ++i) {
      const toml::table* o = (*organs)[i].as_table();
      const std::string f = "organ[" + std::to_string(i) + "]";
      if (!o) return invalid_argument(f, "must be a table");
      PrismOrganSpec spec;
      spec.name = (*o)["name"].value_or(std::string());
      if (spec.name.empty()) return invalid_argument(f + ".name", "missing");
      const std::string rel = (*o)["relative_to"].value_or(std::string("machine"));
      if (rel != "machine" && rel != "clamp") return invalid_argument(f + ".relative_to", "must be \"machine\" or \"clamp\"");
      spec.relative_to_clamp = rel == "clamp";
      const toml::array* x = (*o)["x_mm"].as_array();
      if (!x || x->size() != 2 || !(*x)[0].value<double>() || !(*x)[1].value<double>())
        return invalid_argument(f + ".x_mm", "must be [min, max]");
      spec.x_min_mm = *(*x)[0].value<double>();
      spec.x_max_mm = *(*x)[1].value<double>();
      if (!(spec.x_max_mm > spec.x_min_mm) || !(std::fabs(spec.x_min_mm) <= tolerances::kMaxMachineLengthMm) ||
          !(std::fabs(spec.x_max_mm) <= tolerances::kMaxMachineLengthMm))
        return invalid_argument(f + ".x_mm", "max must exceed min, both within 1e5 mm");
      auto profile = convex_profile((*o)["profile_yz_mm"].node(), f + ".profile_yz_mm");
      if (!profile.ok()) return profile.error();
      spec.profile_yz_mm = profile.value();
      spec.support = (*o)["support"].value_or(false);
      m.organs.push_back(std::move(spec));
    }
  }

  const toml::table* manip = root["manipulator"].as_table();
  if (!manip) return invalid_argument("manipulator", "missing [manipulator] table");
  for (const char* key : {"travel_x_mm", "travel_y_mm"}) {
    const toml::array* r = (*manip)[key].as_array();
    if (!r || r->size() != 2 || !(*r)[0].value<double>() || !(*r)[1].value<double>())
      return invalid_argument(std::string("manipulator.") + key, "must be [min, max]");
    double* dst = std::string(key) == "travel_x_mm" ? m.manipulator.travel_x_mm : m.manipulator.travel_y_mm;
    dst[0] = *(*r)[0].value<double>();
    dst[1] = *(*r)[1].value<double>();
  }
  auto sane = [](double v) { return std::fabs(v) <= tolerances::kMaxMachineLengthMm; };
  if (!(m.manipulator.travel_x_mm[1] >= m.manipulator.travel_x_mm[0]) || !sane(m.manipulator.travel_x_mm[0]) ||
      !sane(m.manipulator.travel_x_mm[1]))
    return invalid_argument("manipulator.travel_x_mm", "must be finite with max >= min");
  if (!(m.manipulator.travel_y_mm[1] >= m.manipulator.travel_y_mm[0]) || !sane(m.manipulator.travel_y_mm[0]) ||
      !sane(m.manipulator.travel_y_mm[1]))
    return invalid_argument("manipulator.travel_y_mm", "must be finite with max >= min");
  GK_READ(m.manipulator.cup_half_width_mm, manip, "cup_half_width_mm", positive)
  GK_READ(m.manipulator.cup_height_mm, manip, "cup_height_mm", positive)
  GK_READ(m.manipulator.frame_thickness_mm, manip, "frame_thickness_mm", positive)
  GK_READ(m.manipulator.rotator_radius_mm, manip, "rotator_radius_mm", positive)
  GK_READ(m.manipulator.rotator_height_mm, manip, "rotator_height_mm", positive)
  {
    const toml::array* half = (*manip)["frame_half_size_mm"].as_array();
    if (!half || half->size() != 2 || !(*half)[0].value<double>() || !(*half)[1].value<double>() ||
        !(*(*half)[0].value<double>() > 0.0) || !(*(*half)[1].value<double>() > 0.0) ||
        !sane(*(*half)[0].value<double>()) || !sane(*(*half)[1].value<double>()))
      return invalid_argument("manipulator.frame_half_size_mm", "must be [half_x, half_y], both positive");
    m.manipulator.frame_half_size_mm = Vec2(*(*half)[0].value<double>(), *(*half)[1].value<double>());
    const toml::array* cups = (*manip)["cup_offsets_mm"].as_array();
    if (!cups || cups->empty()) return invalid_argument("manipulator.cup_offsets_mm", "needs at least one cup [x, y]");
    for (std::size_t i = 0; i < cups->size(); ++i) {
      const toml::array* xy = (*cups)[i].as_array();
      const std::string f = "manipulator.cup_offsets_mm[" + std::to_string(i) + "]";
      if (!xy || xy->size() != 2 || !(*xy)[0].value<double>() || !(*xy)[1].value<double>())
        return invalid_argument(f, "must be [x, y]");
      const Vec2 c(*(*xy)[0].value<double>(), *(*xy)[1].value<double>());
      if (!c.allFinite() || std::fabs(c.x()) > m.manipulator.frame_half_size_mm.x() ||
          std::fabs(c.y()) > m.manipulator.frame_half_size_mm.y())
        return invalid_argument(f, "must lie under the gripper frame");
      m.manipulator.cup_offsets_mm.push_back(c);
    }
  }
#undef GK_READ
  return m;
}

Result<MachineModel> load_machine_model_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return invalid_argument(path, "cannot open machine model file");
  std::stringstream text;
  text << in.rdbuf();
  auto model = parse_machine_model(text.str());
  if (!model.ok()) return invalid_argument(path + ": " + model.error().field, model.error().message);
  return model;
}

Result<MachineModel> default_machine_model() { return parse_machine_model(embedded_default_model_toml()); }

}  // namespace gk::p4
