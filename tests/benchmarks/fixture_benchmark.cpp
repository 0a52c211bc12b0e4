// Fixture assembly (seed 004, §7): the paper's four scenarios rebuilt from a catalogue of modular
// fixture elements made with OCCT (occt_adapters/fixture_elements) - two slot-system and two
// hole-system fixtures - each with an assembling element moved along a 1,000-frame path (over the
// fixture, down beside elements with near misses, a pin into a plate hole with clearance, and a few
// real collisions). Per scenario, in one run:
//  - the assembly session (layer-based projection model, separation-plane box test, exact
//    verdict, between-frames sweep): time per frame, N_b (box and tree-node tests), N_p (triangle
//    pairs tested);
//  - the same frames without the sweep (the paper checks frames only);
//  - the general layout session (engine/scenes/layout_session) on the same elements;
//  - FCL 0.7 with OBB trees (the RAPID-style peer of the paper) on every element, no broad phase,
//    first contact: time, BV tests and leaf (triangle pair) tests from its traversal node;
//  - every frame against brute force (all triangle pairs but those whose boxes are apart);
//  - every motion between frames the sweep let pass, at poses 0.01 mm apart by the frame check.
// Usage: fixture_benchmark [frames=1000]
// NP_TOP=n (environment): lists on stderr the frames-only frames that tested at least n triangle
// pairs, with their contacts and each element's distance below 1 mm (where the work goes).
#include "engine/fixtures/assembly_session.h"
#include "engine/scenes/layout_session.h"
#include "kernel/core/tolerances.h"
#include "kernel/query/rigid_sweep.h"
#include "occt_adapters/fixture_elements.h"
#include "occt_adapters/shape_mesher.h"
#include "tests/support/brute_force.h"
#include "tests/support/fcl_peer.h"

#include <fcl/math/bv/OBB.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

namespace gk {
namespace {

using Clock = std::chrono::steady_clock;
using FclObbModel = fcl::BVHModel<fcl::OBBd>;

struct Element {
  std::string id;
  std::shared_ptr<const MeshBvh> mesh;
  RigidTransform pose;
  std::shared_ptr<FclObbModel> fcl;
  std::vector<engine::CylinderFeature> features = {};
  std::vector<engine::SlotFeature> slots = {};
};

struct Scenario {
  std::string name;
  std::vector<Element> statics;
  Element moving;
  std::vector<RigidTransform> path;
  std::vector<engine::Mate> mates = {};  // the moving element's intended fits
};

// The mesh's triangles whose corners all satisfy `on`.
template <typename On>
std::vector<std::uint32_t> triangles_where(const TriangleMesh& mesh, On on) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    bool all = true;
    for (const Vec3& p : mesh.triangle(t)) all = all && on(p);
    if (all) out.push_back(t);
  }
  return out;
}

// The triangles of a vertical cylinder's side (axis through (cx, cy) along z, radius r, corners
// within z_lo..z_hi), in the mesh's own frame: every corner on the circle and the facet's normal
// across the axis (a fanned end cap has its corners on the circle too).
std::vector<std::uint32_t> cylinder_side(const TriangleMesh& mesh, double cx, double cy, double r, double z_lo, double z_hi) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t : triangles_where(mesh, [&](const Vec3& p) {
         return std::abs(std::hypot(p.x() - cx, p.y() - cy) - r) <= 1e-6 && p.z() >= z_lo - 1e-9 && p.z() <= z_hi + 1e-9;
       })) {
    const Triangle tri = mesh.triangle(t);
    if (std::abs((tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized().z()) < 0.5) out.push_back(t);
  }
  return out;
}

// Meshed as a CAD system exports for a viewer: the angular deflection decides how many facets a
// hole gets, and the holes carry most of the triangles (seed 004, Table 1).
std::shared_ptr<const MeshBvh> meshed(const Result<occt::Shape>& shape, double deflection_mm, double angular_deg = 6.0) {
  if (!shape.ok()) {
    std::fprintf(stderr, "element: %s\n", shape.error().to_string().c_str());
    std::exit(1);
  }
  auto m = occt::mesh_shape(shape.value(), deflection_mm, angular_deg);
  if (!m.ok()) {
    std::fprintf(stderr, "meshing: %s\n", m.error().to_string().c_str());
    std::exit(1);
  }
  return MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(m.value().mesh))).value();
}

Element element(const std::string& id, std::shared_ptr<const MeshBvh> mesh, const Vec3& at, double turn_deg = 0.0) {
  Element e{id, std::move(mesh), RigidTransform::from_axis_angle(Vec3::UnitZ(), turn_deg * 3.14159265358979 / 180.0, at), nullptr};
  e.fcl = testing::make_fcl_bvh<fcl::OBBd>(e.mesh->mesh());
  return e;
}

// A path through waypoints (position, turn about z in degrees), frames spread by length.
std::vector<RigidTransform> path_through(const std::vector<std::pair<Vec3, double>>& points, int frames) {
  std::vector<double> at{0.0};
  for (std::size_t k = 1; k < points.size(); ++k) at.push_back(at.back() + (points[k].first - points[k - 1].first).norm() + 1e-9);
  std::vector<RigidTransform> out;
  for (int f = 0; f < frames; ++f) {
    const double s = at.back() * f / (frames - 1);
    std::size_t k = 1;
    while (k + 1 < points.size() && at[k] < s) ++k;
    const double t = std::clamp((s - at[k - 1]) / (at[k] - at[k - 1]), 0.0, 1.0);
    const Vec3 p = points[k - 1].first + t * (points[k].first - points[k - 1].first);
    const double turn = points[k - 1].second + t * (points[k].second - points[k - 1].second);
    // A hand's small wobble about x and y.
    const Mat3 wobble = (Eigen::AngleAxisd(0.01 * std::sin(0.05 * f), Vec3::UnitX()) * Eigen::AngleAxisd(0.01 * std::cos(0.07 * f), Vec3::UnitY())).toRotationMatrix();
    out.push_back({Eigen::AngleAxisd(turn * 3.14159265358979 / 180.0, Vec3::UnitZ()).toRotationMatrix() * wobble, p});
  }
  return out;
}

// Scenario (a): a slot-system fixture; the assembling element is a nut.
Scenario slot_fixture_with_nut(int frames) {
  Scenario s{"(a) slot system, nut", {}, {}, {}};
  s.statics.push_back(element("base", meshed(occt::base_plate(300, 200, 30, {}, 3, 14), 0.05), Vec3::Zero()));
  const auto block = meshed(occt::block_element(60, 40, 40, {2, 1, 30, 10}), 0.05, 3.0);
  s.statics.push_back(element("block0", block, Vec3(20, 20, 0)));
  s.statics.push_back(element("block1", block, Vec3(220, 20, 0)));
  s.statics.push_back(element("block2", block, Vec3(20, 140, 0)));
  const auto support = meshed(occt::cylinder_element(30, 50, 12), 0.05, 3.0);
  s.statics.push_back(element("support0", support, Vec3(150, 150, 0)));
  s.statics.push_back(element("support1", support, Vec3(250, 150, 0)));
  // A stud standing on its head on the plate (the bolt turned over: head z 0 to 8, shank up to 38).
  const auto bolt = meshed(occt::hex_bolt(19, 8, 12, 30), 0.05, 3.0);
  Element stud = element("stud", bolt, Vec3(150, 50, 8));
  stud.pose.rotation = Eigen::AngleAxisd(3.14159265358979, Vec3::UnitX()).toRotationMatrix();
  stud.features.push_back({"shank", Vec3(0, 0, -15), Vec3::UnitZ(), 6.0, 15.0, false, cylinder_side(bolt->mesh(), 0, 0, 6.0, -30.0, 0.0)});
  s.statics.push_back(stud);
  s.moving = element("nut", meshed(occt::hex_nut(19, 10, 12.6), 0.2, 15.0), Vec3(0, 0, 150));
  s.moving.features.push_back({"hole", Vec3(0, 0, 5), Vec3::UnitZ(), 6.3, 5.0, true, cylinder_side(s.moving.mesh->mesh(), 0, 0, 6.3, 0.0, 10.0)});
  // The nut's hole over the stud's shank: 0.6 mm clearance, and the hand may lean it 0.1 mm into
  // the shank (tolerance 0.8).
  s.mates.push_back({"hole", "stud", "shank", {0.6, 0.8}});
  // Over the fixture, down over the stud's shank 0.3 mm off its axis (hole and shank line to line
  // on one side: the fit's intended contact, the hole's facets 0.05 mm into the shank's), onto its
  // head (a real collision), beside block1 0.5 mm off, into block0's side by 2 mm, and away.
  s.path = path_through({{Vec3(-50, -50, 150), 0}, {Vec3(150, 50.3, 80), 30}, {Vec3(150, 50.3, 5), 30}, {Vec3(150, 50.3, 80), 30},
                         {Vec3(220 - 11.5, 40, 20), 0}, {Vec3(220 - 11.5, 60, 20), 0}, {Vec3(80 + 9.0, 40, 20), 0},
                         {Vec3(80 + 12.0, 40, 20), 0}, {Vec3(150, 120, 120), 45}},
                        frames);
  return s;
}

// Scenario (b): a hole-system fixture; the assembling element is a locator.
Scenario hole_fixture_with_locator(int frames) {
  Scenario s{"(b) hole system, locator", {}, {}, {}};
  s.statics.push_back(element("base", meshed(occt::base_plate(400, 300, 30, {7, 5, 50, 12}), 0.03), Vec3::Zero()));
  const auto block = meshed(occt::block_element(80, 50, 40, {3, 2, 25, 10}), 0.03);
  s.statics.push_back(element("block0", block, Vec3(25, 25, 0)));
  s.statics.push_back(element("block1", block, Vec3(275, 25, 0)));
  s.statics.push_back(element("block2", block, Vec3(25, 200, 0), 90));
  s.statics.push_back(element("block3", block, Vec3(300, 225, 0)));
  const auto support = meshed(occt::cylinder_element(30, 60, 12), 0.03);
  for (int k = 0; k < 3; ++k) s.statics.push_back(element("support" + std::to_string(k), support, Vec3(150 + 50 * k, 200, 0)));
  s.statics.push_back(element("clamp", meshed(occt::strap_clamp(100, 30, 15, 13), 0.03), Vec3(150, 100, 40)));
  // The locator has a spigot below its collar (11.9 mm, 10 long) that locates it in a plate hole.
  s.moving = element("locator", meshed(occt::locator_element(20, 30, 10, 15, 11.9, 10), 0.03, 25.0), Vec3(0, 0, 150));
  s.moving.features.push_back({"spigot", Vec3(0, 0, -5), Vec3::UnitZ(), 5.95, 5.0, false, cylinder_side(s.moving.mesh->mesh(), 0, 0, 5.95, -10.0, 0.0)});
  Element& base = s.statics[0];
  base.features.push_back({"hole150", Vec3(150, 150, -15), Vec3::UnitZ(), 6.0, 15.0, true, cylinder_side(base.mesh->mesh(), 150, 150, 6.0, -30.0, 0.0)});
  // A loose locating fit (clearance 0.1 mm, tolerance 0.3): the hand's 0.01 rad wobble leans the
  // spigot up to 0.1 mm at its end, pressing it up to 0.05 mm into the hole's wall.
  s.mates.push_back({"spigot", "base", "hole150", {0.1, 0.3}});
  // The locator comes down with its spigot into the plate's hole at (150, 150) until its collar
  // stands 0.5 mm above the plate, lifts out, passes 1 mm over the clamp with the spigot's end,
  // and is pushed into a support's side.
  s.path = path_through({{Vec3(-60, 150, 150), 0}, {Vec3(150, 150, 60), 0}, {Vec3(150, 150, 0.5), 0}, {Vec3(150, 150, 30), 0},
                         {Vec3(200, 100, 66), 10}, {Vec3(230, 100, 66), 20}, {Vec3(200, 170, 20), 0}, {Vec3(200, 178, 20), 0},
                         {Vec3(350, 250, 150), 0}},
                        frames);
  return s;
}

// Scenario (c): a slot-system fixture; the assembling element is a bolt into a T-slot.
Scenario slot_fixture_with_bolt(int frames) {
  Scenario s{"(c) slot system, bolt", {}, {}, {}};
  s.statics.push_back(element("base", meshed(occt::base_plate(400, 250, 35, {}, 4, 14), 0.02), Vec3::Zero()));
  const auto block = meshed(occt::block_element(60, 40, 40, {3, 2, 18, 10}), 0.02, 4.5);
  for (int k = 0; k < 3; ++k) s.statics.push_back(element("block" + std::to_string(k), block, Vec3(40 + 120 * k, 120, 0)));
  const auto support = meshed(occt::cylinder_element(25, 45, 10), 0.02, 4.5);
  for (int k = 0; k < 3; ++k) s.statics.push_back(element("support" + std::to_string(k), support, Vec3(70 + 120 * k, 200, 0)));
  s.moving = element("bolt", meshed(occt::hex_bolt(19, 8, 12, 40), 0.3, 15.0), Vec3(0, 0, 150));
  // The shank is mated with the first T-slot's narrow part (y = 50, 14 wide, z -10.5 to 0): a
  // 2 mm clearance fit. The shank's side and the slot's walls are found by their coordinates.
  const TriangleMesh& bolt = s.moving.mesh->mesh();
  // (The side only: the end cap, fanned between rim points, has every corner on the circle too.)
  std::vector<std::uint32_t> side;
  for (std::uint32_t t : triangles_where(bolt, [](const Vec3& p) { return std::abs(std::hypot(p.x(), p.y()) - 6.0) <= 1e-6 && p.z() <= 4.0 + 1e-9; })) {
    const Triangle tri = bolt.triangle(t);
    if (std::abs((tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized().z()) < 0.5) side.push_back(t);
  }
  s.moving.features.push_back({"shank", Vec3(0, 0, -18), Vec3::UnitZ(), 6.0, 22.0, false, side});
  const TriangleMesh& base = s.statics[0].mesh->mesh();
  // (The walls only: a triangle of the plate's end face may have its corners on both walls' lines.)
  std::vector<std::uint32_t> walls;
  for (std::uint32_t t : triangles_where(base, [](const Vec3& p) {
         return (std::abs(p.y() - 43.0) <= 1e-9 || std::abs(p.y() - 57.0) <= 1e-9) && p.z() >= -10.5 - 1e-9;
       })) {
    const Triangle tri = base.triangle(t);
    if (std::abs((tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized().y()) > 0.999) walls.push_back(t);
  }
  s.statics[0].slots.push_back({"slot50", Vec3(200, 50, -5.25), Vec3::UnitY(), Vec3::UnitX(), 14.0, 200.0, 5.25, walls});
  // A fit that lets the shank lean 0.5 mm into a wall (clearance 2, tolerance 3): the hand's
  // wobble of 0.01 rad tilts it by up to 0.4 mm over its length.
  s.mates.push_back({"shank", "base", "slot50", {2.0, 3.0}});
  // Down into the first T-slot 1.05 mm beside its mid-plane (the shank's facets 0.05 mm into the
  // wall at y = 57: the fit's intended contact), along it, up, then sideways into block1.
  s.path = path_through({{Vec3(-50, 51.05, 150), 0}, {Vec3(60, 51.05, 60), 0}, {Vec3(60, 51.05, 5), 0}, {Vec3(200, 51.05, 5), 0},
                         {Vec3(200, 50, 60), 30}, {Vec3(200, 120, 60), 30}, {Vec3(200, 120, 35), 30}, {Vec3(250, 140, 150), 0}},
                        frames);
  return s;
}

// Scenario (d): a larger slot-system fixture; the assembling element is a rhombus pin.
Scenario slot_fixture_with_rhombus_pin(int frames) {
  Scenario s{"(d) slot system, rhombus pin", {}, {}, {}};
  s.statics.push_back(element("base", meshed(occt::base_plate(500, 300, 35, {}, 5, 14), 0.015), Vec3::Zero()));
  const auto block = meshed(occt::block_element(60, 40, 40, {3, 2, 18, 12}), 0.02, 3.5);
  for (int k = 0; k < 4; ++k) s.statics.push_back(element("block" + std::to_string(k), block, Vec3(30 + 120 * k, 130, 0)));
  s.statics.push_back(element("riser", block, Vec3(30, 130, 40)));
  const auto support = meshed(occt::cylinder_element(30, 60, 12), 0.02, 3.5);
  for (int k = 0; k < 2; ++k) s.statics.push_back(element("support" + std::to_string(k), support, Vec3(120 + 200 * k, 250, 0)));
  s.moving = element("rhombus_pin", meshed(occt::rhombus_pin(12, 25, 5), 0.1, 12.0), Vec3(0, 0, 150));
  // The pin's lands in the riser's first hole (its centre at x 12, y 11 in the block's frame):
  // 12 mm in 12 mm, a line-to-line fit the hand may lean 0.15 mm into the wall (tolerance 0.3).
  s.moving.features.push_back({"lands", Vec3(0, 0, 12.5), Vec3::UnitZ(), 6.0, 12.5, false, cylinder_side(s.moving.mesh->mesh(), 0, 0, 6.0, 0.0, 25.0)});
  Element& riser = s.statics[5];
  riser.features.push_back({"hole", Vec3(12, 11, 20), Vec3::UnitZ(), 6.0, 20.0, true, cylinder_side(riser.mesh->mesh(), 12, 11, 6.0, 0.0, 40.0)});
  s.mates.push_back({"lands", "riser", "hole", {0.0, 0.3}});
  // 10 mm into the riser's hole, past the supports 1 mm off, and down onto block2.
  s.path = path_through({{Vec3(-50, -50, 150), 0}, {Vec3(42, 141, 120), 0}, {Vec3(42, 141, 70), 0}, {Vec3(42, 141, 120), 0},
                         {Vec3(120 + 16.0, 230, 20), 0}, {Vec3(120 + 16.0, 270, 20), 0}, {Vec3(270, 150, 60), 45},
                         {Vec3(270, 150, 30), 45}, {Vec3(400, 300, 150), 0}},
                        frames);
  return s;
}

struct Timing {
  std::vector<double> us;
  void add(Clock::time_point t0) { us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count()); }
  double mean() const {
    double s = 0;
    for (double v : us) s += v;
    return us.empty() ? 0.0 : s / static_cast<double>(us.size());
  }
  double quantile(double q) const {
    std::vector<double> v = us;
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
  }
};

void run(const Scenario& s) {
  std::size_t static_triangles = 0;
  for (const Element& e : s.statics) static_triangles += e.mesh->mesh().triangle_count();
  const int frames = static_cast<int>(s.path.size());

  // Brute force: which elements each frame's pose meets.
  std::vector<std::set<std::string>> expected(s.path.size());
  std::vector<std::set<std::string>> expected_crossing(s.path.size());
  int frames_meeting = 0;
  for (std::size_t f = 0; f < s.path.size(); ++f) {
    for (const Element& e : s.statics)
      if (testing::brute_force_any_within(s.moving.mesh->mesh(), s.path[f], e.mesh->mesh(), e.pose, tolerances::kContactMm))
        expected[f].insert(e.id);
    frames_meeting += expected[f].empty() ? 0 : 1;
  }

  int intended_frames = 0;  // frames with a contact a declared fit makes intended
  // The sweep's answer per frame: its verdict, and whether it denied the motion before it.
  std::vector<Verdict> swept_verdict(s.path.size(), Verdict::kClear);
  std::vector<bool> denied_between(s.path.size(), false);
  double assemble_ms = 0.0, begin_moving_ms = 0.0;  // the frames-only run's: each element's tree built again with its groups and slabs
  auto session_run = [&](bool sweep_too, Timing& time, engine::AssemblyWork& work, int& wrong, int& colliding, int& between) {
    engine::AssemblySession session(Mat3::Identity());
    const auto assemble_start = Clock::now();
    for (const Element& e : s.statics) {
      auto added = session.assemble({e.id, e.mesh, e.pose, e.features, nullptr, e.slots});
      if (!added.ok()) {
        std::fprintf(stderr, "assemble %s: %s\n", e.id.c_str(), added.error().to_string().c_str());
        std::exit(1);
      }
    }
    assemble_ms = std::chrono::duration<double, std::milli>(Clock::now() - assemble_start).count();
    for (std::size_t f = 0; f < s.path.size(); ++f) {
      if (f == 0) {
        const auto begin_start = Clock::now();
        auto begun = session.begin_moving({s.moving.id, s.moving.mesh, s.path[f], s.moving.features}, s.mates);
        begin_moving_ms = std::chrono::duration<double, std::milli>(Clock::now() - begin_start).count();
        if (!begun.ok()) {
          std::fprintf(stderr, "begin_moving: %s\n", begun.error().to_string().c_str());
          std::exit(1);
        }
      }
      const auto t0 = Clock::now();
      auto frame = session.frame(s.path[f], {}, sweep_too);
      time.add(t0);
      if (!frame.ok()) {
        std::fprintf(stderr, "frame %zu: %s\n", f, frame.error().to_string().c_str());
        std::exit(1);
      }
      work.add(frame.value().work);
      if (!sweep_too && std::getenv("NP_TOP") != nullptr && frame.value().work.triangle_pairs >= static_cast<std::uint64_t>(std::atoi(std::getenv("NP_TOP")))) {
        std::fprintf(stderr, "frame %zu: N_p %llu, N_b %llu, verdict %s:", f, static_cast<unsigned long long>(frame.value().work.triangle_pairs),
                     static_cast<unsigned long long>(frame.value().work.bounding_volume_tests()), to_string(frame.value().verdict));
        for (const auto& c : frame.value().contacts)
          std::fprintf(stderr, " [%s %s%s]", c.element_id.c_str(), to_string(c.verdict), c.intended ? " intended" : "");
        for (const Element& e : s.statics) {
          auto d = gk::distance(*s.moving.mesh, s.path[f], *e.mesh, e.pose);
          if (d.ok() && d.value().distance_mm < 1.0) std::fprintf(stderr, " {%s at %.3g mm}", e.id.c_str(), d.value().distance_mm);
        }
        std::fprintf(stderr, "\n");
      }
      std::set<std::string> got;
      if (sweep_too) swept_verdict[f] = frame.value().verdict;
      for (const auto& c : frame.value().contacts) {
        if (c.between_frames) {
          ++between;
          if (sweep_too && (c.verdict == Verdict::kCollision || c.verdict == Verdict::kInconclusive)) denied_between[f] = true;
          continue;
        }
        got.insert(c.element_id);
        if (c.intended && sweep_too) ++intended_frames;
      }
      wrong += got == expected[f] ? 0 : 1;
      colliding += frame.value().verdict == Verdict::kCollision ? 1 : 0;
    }
  };
  Timing lpm_time, frames_only_time;
  engine::AssemblyWork lpm_work, frames_only_work;
  int lpm_wrong = 0, lpm_colliding = 0, lpm_between = 0, fo_wrong = 0, fo_colliding = 0, fo_between = 0;
  session_run(true, lpm_time, lpm_work, lpm_wrong, lpm_colliding, lpm_between);
  session_run(false, frames_only_time, frames_only_work, fo_wrong, fo_colliding, fo_between);

  // Between frames: every motion whose two ends are not COLLISION and that the sweep let pass,
  // checked at poses kBetweenSampleMm of the farthest point's travel apart by the frame check
  // (itself checked against brute force above): a COLLISION at one is a motion the sweep missed.
  constexpr double kBetweenSampleMm = 0.01;
  int motions_sampled = 0, motions_missed = 0;
  {
    engine::AssemblySession sampler(Mat3::Identity());
    for (const Element& e : s.statics) (void)sampler.assemble({e.id, e.mesh, e.pose, e.features, nullptr, e.slots});
    (void)sampler.begin_moving({s.moving.id, s.moving.mesh, s.path[0], s.moving.features}, s.mates);
    for (std::size_t f = 1; f < s.path.size(); ++f) {
      if (denied_between[f] || swept_verdict[f] == Verdict::kCollision || swept_verdict[f - 1] == Verdict::kCollision) continue;
      double travel = 0.0;
      for (const Vec3& v : s.moving.mesh->mesh().vertices()) travel = std::max(travel, (s.path[f].apply(v) - s.path[f - 1].apply(v)).norm());
      const int n = static_cast<int>(std::ceil(travel / kBetweenSampleMm));
      ++motions_sampled;
      for (int k = 1; k < n; ++k) {
        auto at = sampler.frame(pose_between(s.path[f - 1], s.path[f], static_cast<double>(k) / n), {}, false);
        if (at.ok() && at.value().verdict == Verdict::kCollision) {
          ++motions_missed;
          std::fprintf(stderr, "frame %zu: a COLLISION at s %.4f between frames, not reported\n", f, static_cast<double>(k) / n);
          break;
        }
      }
    }
  }

  // The general layout session.
  std::vector<engine::AuditObject> objects;
  for (const Element& e : s.statics) objects.push_back({e.id, "element", "", e.mesh, e.pose});
  objects.push_back({s.moving.id, "moving", "", s.moving.mesh, s.path[0]});
  auto layout = engine::LayoutSession::create(objects, static_cast<std::uint32_t>(objects.size() - 1), 0.0).value();
  Timing layout_time;
  int layout_wrong = 0;
  std::uint64_t layout_exact = 0;
  for (std::size_t f = 0; f < s.path.size(); ++f) {
    const auto t0 = Clock::now();
    auto a = layout->move_to(s.path[f]);
    layout_time.add(t0);
    std::set<std::string> got;
    for (const auto& c : a.value().contacts)
      if (c.verdict != Verdict::kClear) got.insert(s.statics[c.other].id);
    layout_wrong += got == expected[f] ? 0 : 1;
    layout_exact += a.value().exact_checks;
  }

  // FCL with OBB trees, every element, first contact.
  Timing fcl_time;
  std::uint64_t fcl_bv = 0, fcl_leaf = 0;
  int fcl_frames_colliding = 0;
  for (std::size_t f = 0; f < s.path.size(); ++f) {
    const auto t0 = Clock::now();
    bool any = false;
    for (const Element& e : s.statics) {
      fcl::CollisionRequestd request;
      fcl::CollisionResultd result;
      fcl::detail::MeshCollisionTraversalNodeOBB<double> node;
      fcl::detail::initialize(node, *s.moving.fcl, testing::to_fcl(s.path[f]), *e.fcl, testing::to_fcl(e.pose), request, result);
      node.enable_statistics = true;
      fcl::detail::collide(&node);
      fcl_bv += static_cast<std::uint64_t>(node.num_bv_tests);
      fcl_leaf += static_cast<std::uint64_t>(node.num_leaf_tests);
      any = any || result.isCollision();
    }
    fcl_time.add(t0);
    fcl_frames_colliding += any ? 1 : 0;
  }

  std::printf("\n%s: static %zu triangles in %zu elements, moving %zu triangles, %d frames, %d frames meeting an element (brute force)\n",
              s.name.c_str(), static_triangles, s.statics.size(), s.moving.mesh->mesh().triangle_count(), frames, frames_meeting);
  std::printf("| pipeline | mean us | p50 us | p99 us | max us | N_b: box + node tests, total (per frame) | N_p: triangle pairs tested, total (per frame) | frames wrong vs brute force |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  auto count = [&](std::uint64_t n) {
    char text[64];
    std::snprintf(text, sizeof text, "%llu (%.1f)", static_cast<unsigned long long>(n), static_cast<double>(n) / frames);
    return std::string(text);
  };
  auto row = [&](const char* name, const Timing& t, const std::string& nb, const std::string& np, const std::string& wrong) {
    std::printf("| %s | %.1f | %.1f | %.1f | %.1f | %s | %s | %s |\n", name, t.mean(), t.quantile(0.5), t.quantile(0.99), t.quantile(1.0),
                nb.c_str(), np.c_str(), wrong.c_str());
  };
  row("assembly session (LPM + exact + sweep)", lpm_time, count(lpm_work.bounding_volume_tests()), count(lpm_work.triangle_pairs),
      std::to_string(lpm_wrong) + " (" + std::to_string(lpm_between) + " contacts between frames)");
  row("assembly session, frames only", frames_only_time, count(frames_only_work.bounding_volume_tests()), count(frames_only_work.triangle_pairs),
      std::to_string(fo_wrong));
  row("layout session (general)", layout_time, "not counted", "not counted", std::to_string(layout_wrong) + " (" + std::to_string(layout_exact) + " exact checks)");
  row("FCL 0.7 OBB, every element, first contact", fcl_time, count(fcl_bv), count(fcl_leaf),
      std::to_string(fcl_frames_colliding) + " frames colliding (FCL counts touching as colliding)");
  std::printf("between frames: %d motions with neither end COLLISION and none reported on the way, each checked at poses %.2f mm apart: "
              "%d with a COLLISION the sweep missed\n",
              motions_sampled, kBetweenSampleMm, motions_missed);
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::printf("assembly session: %d frames COLLISION, %d with an intended contact (%zu mates); N_b = broad phase box tests %llu + tree "
              "node pairs %llu + triangle-to-leaf bounds %llu (frames only: %llu + %llu + %llu), exact checks %llu, sweep steps %llu\n",
              lpm_colliding, intended_frames, s.mates.size(), u(lpm_work.box_tests), u(lpm_work.node_tests), u(lpm_work.triangle_node_tests),
              u(frames_only_work.box_tests), u(frames_only_work.node_tests), u(frames_only_work.triangle_node_tests), u(lpm_work.exact_checks),
              u(lpm_work.sweep_steps));
  std::printf("set-up (frames-only run): assembling the %zu static elements %.2f ms, begin_moving %.2f ms\n", s.statics.size(), assemble_ms,
              begin_moving_ms);
}

}  // namespace
}  // namespace gk

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(2, std::atoi(argv[1])) : 1000;
  for (auto make : {gk::slot_fixture_with_nut, gk::hole_fixture_with_locator, gk::slot_fixture_with_bolt, gk::slot_fixture_with_rhombus_pin})
    gk::run(make(frames));
  return 0;
}
