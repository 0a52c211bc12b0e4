// A layout frame: one machine dragged among the static objects of a generated factory, at a
// frame's worth of motion per step (40 mm and 0.2 degrees), through robot cells, conveyors,
// columns and racks. Prints per-frame latency percentiles and what each level cleared.
//   build/tests/benchmarks/layout_benchmark [objects] [frames] [clearance_mm] [weave|hug|heavy]
// weave: along a bay row, 3 m either side, turning (through robot cells, conveyors, racks);
// hug: along the first column line, the machine's box 30 mm from the columns' faces, so every
// column it passes is a candidate for many frames;
// heavy: a copy of a robot's base (KUKA KR10 base_link, 70,010 triangles) dragged along the row of
// robot cells at the robots' height, swinging 1.5 m either side of the robots' line and turning,
// so most frames have it within the clearance of several robot links, touching or driven into them.
#include "engine/scenes/layout_session.h"
#include "tests/support/factory_scene.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  gk::testing::FactorySceneOptions scene_options;
  scene_options.objects = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 10000;
  scene_options.triangles = 100000000ULL;
  const int frames = argc > 2 ? std::atoi(argv[2]) : 5000;
  const double clearance = argc > 3 ? std::atof(argv[3]) : 50.0;
  const std::string path = argc > 4 ? argv[4] : "weave";
  const bool hug = path == "hug", heavy = path == "heavy";
  if (!hug && !heavy && path != "weave") {
    std::fprintf(stderr, "path must be weave, hug or heavy\n");
    return 2;
  }
  gk::testing::FactoryScene scene = gk::testing::generate_factory_scene(scene_options);
  std::uint32_t moving = 0;
  if (heavy) {
    // The first robot's base, copied as one more object (not part of any robot's group).
    std::uint32_t base = 0;
    while (scene.objects[base].category != "robot") ++base;
    gk::engine::AuditObject dragged = scene.objects[base];
    dragged.name = "dragged robot base";
    dragged.category = "machine";
    dragged.group.clear();
    dragged.pose = gk::RigidTransform::from_translation(scene.objects[base].pose.translation + gk::Vec3(-4000.0, 0.0, 0.0));
    scene.objects.push_back(dragged);
    moving = static_cast<std::uint32_t>(scene.objects.size() - 1);
  } else {
    while (scene.objects[moving].category != "machine") ++moving;  // the first machine: fandisk, 31,682 triangles
  }
  const auto t_setup = std::chrono::steady_clock::now();
  auto session = gk::engine::LayoutSession::create(scene.objects, moving, clearance);
  if (!session.ok()) {
    std::fprintf(stderr, "%s\n", session.error().to_string().c_str());
    return 1;
  }
  const double setup_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_setup).count();
  const gk::RigidTransform start = scene.objects[moving].pose;
  std::vector<double> us;
  unsigned long long colliding_frames = 0, near_frames = 0;
  unsigned long long candidates = 0, hits = 0, box_clears = 0, crossing_hits = 0, exact = 0, contacts = 0;
  for (int f = 0; f < frames; ++f) {
    gk::RigidTransform pose;
    if (hug) {
      const gk::Aabb local = scene.objects[moving].mesh->root_bounds();
      pose.translation = gk::Vec3(-2000.0 + 40.0 * f, 200.0 + 30.0 - local.min.y(), 0.0);
    } else if (heavy) {
      const gk::Vec3 at = start.translation + gk::Vec3(40.0 * f, 1500.0 * std::sin(f * 0.01), 0.0);
      pose = gk::RigidTransform::from_axis_angle(gk::Vec3::UnitZ(), 0.0035 * f, at);
    } else {
      const gk::Vec3 at = start.translation + gk::Vec3(40.0 * f, 3000.0 * std::sin(f * 0.004), 0.0);
      pose = gk::RigidTransform::from_axis_angle(gk::Vec3::UnitZ(), 0.0035 * f, at);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto answer = session.value()->move_to(pose);
    us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    if (!answer.ok()) return 1;
    candidates += answer.value().candidates;
    if (answer.value().worst == gk::Verdict::kCollision) ++colliding_frames;
    else if (!answer.value().contacts.empty()) ++near_frames;
    hits += answer.value().axis_cache_hits;
    box_clears += answer.value().box_axis_clears;
    exact += answer.value().exact_checks;
    crossing_hits += answer.value().crossing_cache_hits;
    contacts += answer.value().contacts.size();
  }
  std::sort(us.begin(), us.end());
  std::printf("path %s, static objects %zu, moving '%s' (%zu triangles), clearance %.0f mm, %d frames, session set-up %.1f ms\n",
              path.c_str(), scene.objects.size() - 1, scene.objects[moving].name.c_str(), scene.objects[moving].mesh->mesh().triangle_count(),
              clearance, frames, setup_ms);
  std::printf("frame p50 %.1f us | p90 %.1f us | p99 %.1f us | max %.1f us\n", us[us.size() / 2], us[us.size() * 9 / 10],
              us[us.size() * 99 / 100], us.back());
  std::printf("per frame: candidates %.2f, cleared by cached axis %.2f, by a new box axis %.2f, still crossing at the "
              "cached triangles %.2f, exact %.2f, reported %.2f\n",
              static_cast<double>(candidates) / frames, static_cast<double>(hits) / frames,
              static_cast<double>(box_clears) / frames, static_cast<double>(crossing_hits) / frames,
              static_cast<double>(exact) / frames,
              static_cast<double>(contacts) / frames);
  std::printf("frames with a collision %llu, with contacts or pairs within the clearance only %llu\n", colliding_frames,
              near_frames);
  return 0;
}
