#include "tests/support/factory_scene.h"

#include "engine/parts/bvh_cache.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

namespace gk::testing {
using engine::AuditObject;
using engine::BvhCache;
namespace {

constexpr double kBayMm = 10000.0;

// Where BVHs come from: built, or through the disk cache when the options name one.
BvhCache* g_cache = nullptr;

std::shared_ptr<const MeshBvh> bvh_of(TriangleMesh mesh) {
  auto shared = share(std::move(mesh));
  return g_cache ? g_cache->get_or_build(shared).value() : MeshBvh::build(shared).value();
}

// A shared mesh from ../shared/data, scaled (robot meshes are in metres) and moved so its box
// starts at z = 0 and is centred in x and y.
std::shared_ptr<const MeshBvh> shared_mesh(const std::string& relative, double scale) {
  auto read = mesh_io::read_mesh_file(shared_data(relative));
  if (!read.ok()) throw std::runtime_error(read.error().to_string());
  TriangleMesh mesh = std::move(read).value();
  std::vector<Vec3> v = mesh.vertices();
  Aabb box;
  for (Vec3& p : v) {
    p *= scale;
    box.extend(p);
  }
  const Vec3 shift(-box.center().x(), -box.center().y(), -box.min.z());
  for (Vec3& p : v) p += shift;
  (void)mesh.set_vertices(std::move(v));
  return bvh_of(std::move(mesh));
}

class Builder {
 public:
  explicit Builder(FactoryScene& scene) : scene_(scene) {}
  std::uint32_t add(const std::string& name, const std::string& category, const std::string& group,
                    const std::shared_ptr<const MeshBvh>& mesh, const RigidTransform& pose) {
    scene_.objects.push_back({name, category, group, mesh, pose});
    scene_.triangles += mesh->mesh().triangle_count();
    return static_cast<std::uint32_t>(scene_.objects.size() - 1);
  }

 private:
  FactoryScene& scene_;
};

}  // namespace

FactoryScene generate_factory_scene(const FactorySceneOptions& options) {
  std::unique_ptr<BvhCache> cache;
  if (!options.bvh_cache_dir.empty()) cache = std::make_unique<BvhCache>(options.bvh_cache_dir);
  g_cache = cache.get();
  FactoryScene scene;
  Builder b(scene);
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> jitter(-500.0, 500.0);
  std::uniform_real_distribution<double> turn(0.0, 2.0 * kPi);

  // The catalogue: every mesh once.
  const auto column = bvh_of(box_mesh(Vec3(-200, -200, 0), Vec3(200, 200, 8000)));
  const auto rack = bvh_of(box_mesh(Vec3(-1350, -550, 0), Vec3(1350, 550, 5000)));
  const auto conveyor = bvh_of(box_mesh(Vec3(-4500, -400, 0), Vec3(4500, 400, 900)));
  const auto bolt = bvh_of(cylinder_mesh(5.0, 20.0, 12));
  const auto crate = bvh_of(box_mesh(Vec3(-500, -500, 0), Vec3(500, 500, 1000)));
  std::vector<std::shared_ptr<const MeshBvh>> robot;
  for (const char* link : {"base_link", "link_1", "link_2", "link_3", "link_4", "link_5", "link_6"})
    robot.push_back(shared_mesh(std::string("meshes/robots/kuka_kr10r1420/visual/") + link + ".stl", 1000.0));
  const std::vector<std::shared_ptr<const MeshBvh>> machines = {
      shared_mesh("meshes/occt/TR12J_OCC64K.stl", 1.0), shared_mesh("meshes/occt/motor.stl", 10.0),
      shared_mesh("meshes/cgal/turbine.off", 10.0), shared_mesh("meshes/cgal/fandisk_large.off", 50.0)};
  std::size_t robot_triangles = 0;
  Aabb robot_box;
  for (const auto& m : robot) {
    robot_triangles += m->mesh().triangle_count();
    robot_box.extend(m->root_bounds());
  }
  // Two robots of a cell stand so their boxes (turned anyhow) just overlap; the conveyor passes
  // 20 mm beyond the robots' reach box.
  const double robot_radius = std::hypot(robot_box.half_extent().x(), robot_box.half_extent().y());
  const double robot_spacing = 1.1 * robot_radius;
  const double conveyor_offset = robot_radius + 400.0 + 20.0;

  // Bays: about twelve objects each; heavy bays (robot cells, machines) until the triangle target.
  const std::size_t bays = std::max<std::size_t>(4, options.objects / 12);
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(bays))));
  const double hall_x = static_cast<double>(side) * kBayMm, hall_y = static_cast<double>((bays + side - 1) / side) * kBayMm;
  for (std::size_t i = 0; i < bays; ++i) {
    const double x0 = static_cast<double>(i % side) * kBayMm, y0 = static_cast<double>(i / side) * kBayMm;
    const std::string bay = "bay" + std::to_string(i);
    b.add(bay + "/column", "column", "", column, RigidTransform::from_translation(Vec3(x0, y0, 0)));
    const Vec3 centre(x0 + 5000 + jitter(rng), y0 + 4000 + jitter(rng), 0);
    const bool heavy = scene.triangles + 2 * robot_triangles <= options.triangles;
    if (heavy && i % 4 != 3) {
      // A robot cell: two robots working close together (each one group of links), with a
      // conveyor feeding them: boxes overlap, meshes mostly do not, so the narrow phase decides.
      for (int r = 0; r < 2; ++r) {
        const std::string group = bay + "/robot" + std::to_string(r);
        const RigidTransform base = RigidTransform::from_axis_angle(Vec3::UnitZ(), turn(rng), centre + Vec3(r * robot_spacing, 0, 0));
        for (std::size_t k = 0; k < robot.size(); ++k) b.add(group + "/link" + std::to_string(k), "robot", group, robot[k], base);
      }
      b.add(bay + "/conveyor", "conveyor", "", conveyor, RigidTransform::from_translation(centre + Vec3(0, conveyor_offset, 0)));
    } else if (heavy) {
      const auto& m = machines[i % machines.size()];
      b.add(bay + "/machine", "machine", "", m, RigidTransform::from_axis_angle(Vec3::UnitZ(), turn(rng), centre));
      for (int k = 0; k < 6; ++k)  // bolts on the floor around it
        b.add(bay + "/bolt" + std::to_string(k), "bolt", "", bolt,
              RigidTransform::from_translation(centre + Vec3(-3000 + 1000 * k, -3500, 0)));
    } else if (i % 2 == 0) {
      for (int k = 0; k < 2; ++k)
        b.add(bay + "/rack" + std::to_string(k), "rack", "", rack, RigidTransform::from_translation(Vec3(x0 + 3000 + 3000 * k, y0 + 5000, 0)));
      for (int k = 0; k < 7; ++k)  // bolts resting on top of the racks: intended contacts
        b.add(bay + "/bolt" + std::to_string(k), "bolt", "", bolt,
              RigidTransform::from_translation(Vec3(x0 + 2000 + 600 * k, y0 + 5000, 5000)));
    } else {
      b.add(bay + "/conveyor", "conveyor", "", conveyor, RigidTransform::from_translation(Vec3(x0 + 5000, y0 + 5000, 0)));
      for (int k = 0; k < 8; ++k)  // bolts lying on the belt
        b.add(bay + "/bolt" + std::to_string(k), "bolt", "", bolt,
              RigidTransform::from_translation(Vec3(x0 + 1000 + 1000 * k, y0 + 5000, 900)));
    }
  }
  // Pipes crossing the whole hall at 6 m, between the column lines; walls around it.
  const auto pipe = bvh_of(cylinder_mesh(100.0, hall_x, 48));
  for (double y = 2500; y < hall_y; y += 3 * kBayMm)
    b.add("pipe@" + std::to_string(static_cast<int>(y)), "pipe", "", pipe,
          RigidTransform::from_axis_angle(Vec3::UnitY(), kPi / 2, Vec3(0, y, 6000)));
  const auto wall_x = bvh_of(box_mesh(Vec3(0, -200, 0), Vec3(hall_x, 0, 9000)));
  const auto wall_y = bvh_of(box_mesh(Vec3(-200, 0, 0), Vec3(0, hall_y, 9000)));
  b.add("wall/south", "wall", "", wall_x, RigidTransform::from_translation(Vec3(-300, -300, 0)));
  b.add("wall/north", "wall", "", wall_x, RigidTransform::from_translation(Vec3(-300, hall_y + 300, 0)));
  b.add("wall/west", "wall", "", wall_y, RigidTransform::from_translation(Vec3(-300, -300, 0)));
  b.add("wall/east", "wall", "", wall_y, RigidTransform::from_translation(Vec3(hall_x + 300, -300, 0)));
  // Known answers south of the hall: crates overlapping along x, or apart by the gap.
  for (int k = 0; k < options.deliberate_clashes + options.near_misses; ++k) {
    const bool clash = k < options.deliberate_clashes;
    const Vec3 at(3000.0 * k, -6000.0, 0.0);
    const double offset = 1000.0 + (clash ? -options.clash_depth_mm : options.near_miss_gap_mm);
    const std::string name = (clash ? "clash" : "near-miss") + std::to_string(k);
    const std::uint32_t first = b.add(name + "/crate-a", "crate", "", crate, RigidTransform::from_translation(at));
    const std::uint32_t second = b.add(name + "/crate-b", "crate", "", crate, RigidTransform::from_translation(at + Vec3(offset, 0, 0)));
    scene.known.push_back({first, second, clash, clash ? 0.0 : options.near_miss_gap_mm});
  }
  // Intended contacts: the links of one robot, bolts resting on racks, conveyors or the floor's machines.
  scene.rules = {{"robot links of one robot", "robot", "robot", true},
                 {"bolts resting on racks", "bolt", "rack", false},
                 {"bolts lying on conveyors", "bolt", "conveyor", false}};
  // Robot links and machines share the catalogue's meshes above; with distinct_meshes each gets
  // its own copy, built on every core.
  if (options.distinct_meshes) {
    std::vector<std::size_t> copies;
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
      if (scene.objects[i].category == "robot" || scene.objects[i].category == "machine") copies.push_back(i);
    std::atomic<std::size_t> next{0};
    auto work = [&] {
      for (std::size_t k = next++; k < copies.size(); k = next++) {
        AuditObject& o = scene.objects[copies[k]];
        o.mesh = bvh_of(o.mesh->mesh());
      }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < std::max(1u, std::thread::hardware_concurrency()); ++t) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
  }
  std::map<const MeshBvh*, int> unique;
  for (const AuditObject& o : scene.objects) unique[o.mesh.get()] = 1;
  scene.unique_meshes = unique.size();
  g_cache = nullptr;
  return scene;
}

}  // namespace gk::testing
