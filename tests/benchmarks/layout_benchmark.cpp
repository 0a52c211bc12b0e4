// A layout frame: one machine dragged among the static objects of a generated factory, at a
// frame's worth of motion per step (40 mm and 0.2 degrees), through robot cells, conveyors,
// columns and racks. Prints per-frame latency percentiles and what each level cleared.
//   build/tests/benchmarks/layout_benchmark [objects] [frames] [clearance_mm] [weave|hug|heavy|mesh FILE WEAVE_MM [SIZE_MM [SPLITS]]]
// weave: along a bay row, 3 m either side, turning (through robot cells, conveyors, racks);
// hug: along the first column line, the machine's box 30 mm from the columns' faces, so every
// column it passes is a candidate for many frames;
// heavy: a copy of a robot's base (KUKA KR10 base_link, 70,010 triangles) dragged along the row of
// robot cells at the robots' height, swinging 1.5 m either side of the robots' line and turning,
// so most frames have it within the clearance of several robot links, touching or driven into them.
// mesh FILE WEAVE_MM: gatekeeper-dragbench's scene in process, for any mesh (both sides heavy):
// copies of the mesh in rows (two widths apart along x; rows so that a copy midway between two
// has 30 mm to both boxes), one more dragged 40 mm per frame along the rows midway, swinging
// WEAVE_MM either side (sin(0.02 f)), unturned. SIZE_MM: the mesh scaled so that its box's largest
// side is that long; SPLITS: each triangle split in four at its edges' midpoints that many times
// (a scan of a few thousand triangles made a heavy part of the same shape).
#include "engine/scenes/layout_session.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/factory_scene.h"

#include <array>
#include <map>
#include <cmath>

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
  const bool hug = path == "hug", heavy = path == "heavy", mesh_rows = path == "mesh";
  if (!hug && !heavy && !mesh_rows && path != "weave") {
    std::fprintf(stderr, "path must be weave, hug, heavy or mesh FILE WEAVE_MM\n");
    return 2;
  }
  if (mesh_rows && argc < 7) {
    std::fprintf(stderr, "mesh FILE WEAVE_MM\n");
    return 2;
  }
  gk::testing::FactoryScene scene;
  if (!mesh_rows) scene = gk::testing::generate_factory_scene(scene_options);
  std::uint32_t moving = 0;
  double x_pitch = 0.0, row_pitch = 0.0, weave = 0.0;
  int side = 0;
  if (mesh_rows) {
    auto read = gk::mesh_io::read_mesh_file(argv[5]);
    if (!read.ok()) {
      std::fprintf(stderr, "%s\n", read.error().to_string().c_str());
      return 1;
    }
    gk::TriangleMesh mesh = std::move(read).value();
    if (argc > 7) {
      const gk::Aabb b0 = mesh.bounds();
      const double scale = std::atof(argv[7]) / (b0.max - b0.min).maxCoeff();
      const int splits = argc > 8 ? std::atoi(argv[8]) : 0;
      std::vector<gk::Vec3> vertices;
      for (const gk::Vec3& v : mesh.vertices()) vertices.push_back(scale * v);
      std::vector<std::array<std::uint32_t, 3>> faces(mesh.faces().begin(), mesh.faces().end());
      for (int k = 0; k < splits; ++k) {
        std::vector<std::array<std::uint32_t, 3>> finer;
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;  // one per edge: the mesh stays closed
        for (const auto& f : faces) {
          std::uint32_t m[3];
          for (int e = 0; e < 3; ++e) {
            const std::uint32_t u = f[e], w = f[(e + 1) % 3];
            const auto key = std::minmax(u, w);
            auto it = midpoint.find(key);
            if (it == midpoint.end()) {
              vertices.push_back(0.5 * (vertices[u] + vertices[w]));
              it = midpoint.emplace(key, static_cast<std::uint32_t>(vertices.size() - 1)).first;
            }
            m[e] = it->second;
          }
          finer.push_back({f[0], m[0], m[2]});
          finer.push_back({m[0], f[1], m[1]});
          finer.push_back({m[2], m[1], f[2]});
          finer.push_back({m[0], m[1], m[2]});
        }
        faces = std::move(finer);
      }
      auto rebuilt = gk::TriangleMesh::create(std::move(vertices), std::move(faces));
      if (!rebuilt.ok()) {
        std::fprintf(stderr, "%s\n", rebuilt.error().to_string().c_str());
        return 1;
      }
      mesh = std::move(rebuilt).value();
    }
    auto bvh = gk::MeshBvh::build(std::make_shared<const gk::TriangleMesh>(std::move(mesh))).value();
    const gk::Aabb b = bvh->root_bounds();
    x_pitch = 2.0 * (b.max.x() - b.min.x());
    row_pitch = 2.0 * (b.max.y() - b.min.y()) + 60.0;
    weave = std::atof(argv[6]);
    side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(scene_options.objects))));
    for (std::size_t i = 0; i < scene_options.objects; ++i)
      scene.objects.push_back({"copy", "mesh", "", bvh,
                               gk::RigidTransform::from_translation(gk::Vec3(x_pitch * static_cast<double>(static_cast<int>(i) % side),
                                                                             row_pitch * static_cast<double>(static_cast<int>(i) / side), 0.0)),
                               0.0, std::nullopt});
    scene.objects.push_back({"dragged", "mesh", "", bvh, gk::RigidTransform::from_translation(gk::Vec3(-1.5 * x_pitch, 0.5 * row_pitch, 0.0)),
                             0.0, std::nullopt});
    moving = static_cast<std::uint32_t>(scene.objects.size() - 1);
  } else if (heavy) {
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
  std::vector<double> us, us_colliding, us_near, us_apart;
  unsigned long long colliding_frames = 0, near_frames = 0;
  unsigned long long candidates = 0, hits = 0, box_clears = 0, crossing_hits = 0, exact = 0, contacts = 0;
  for (int f = 0; f < frames; ++f) {
    gk::RigidTransform pose;
    if (mesh_rows) {
      const double along = 40.0 * f, row_length = x_pitch * (side + 1);
      const int row = static_cast<int>(along / row_length) % std::max(1, side - 1);
      pose.translation = gk::Vec3(-0.5 * x_pitch + std::fmod(along, row_length), row_pitch * row + 0.5 * row_pitch + weave * std::sin(0.02 * f), 0.0);
    } else if (hug) {
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
    (answer.value().worst == gk::Verdict::kCollision ? us_colliding : !answer.value().contacts.empty() ? us_near : us_apart).push_back(us.back());
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
  for (const auto& [name, v] : {std::pair<const char*, std::vector<double>*>{"colliding", &us_colliding}, {"within the clearance", &us_near},
                          {"apart", &us_apart}}) {
    if (v->empty()) continue;
    std::sort(v->begin(), v->end());
    std::printf("  frames %s (%zu): p50 %.1f us | p99 %.1f us | max %.1f us\n", name, v->size(), (*v)[v->size() / 2],
                (*v)[v->size() * 99 / 100], v->back());
  }
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
