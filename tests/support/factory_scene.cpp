#include "tests/support/factory_scene.h"

#include "engine/parts/bvh_cache.h"
#include "engine/parts/packed_mesh_file.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
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

// A smooth displacement of up to `amplitude` mm on each axis, its own for each seed: a copy that is
// its own content (a content-hash cache cannot share it), the same shape to the eye.
TriangleMesh deformed(const TriangleMesh& mesh, std::uint64_t seed, double amplitude) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * kPi), frequency(1.0 / 400.0, 1.0 / 40.0);
  const Vec3 f(frequency(rng), frequency(rng), frequency(rng)), p0(phase(rng), phase(rng), phase(rng));
  std::vector<Vec3> v = mesh.vertices();
  for (Vec3& p : v)
    p += amplitude * Vec3(std::sin(f.x() * p.y() + p0.x()), std::sin(f.y() * p.z() + p0.y()), std::sin(f.z() * p.x() + p0.z()));
  // The same topology: the copy's analysis holds, only bounds and degeneracy are computed again.
  TriangleMesh copy = mesh;
  auto moved = copy.set_vertices(std::move(v));
  if (!moved.ok()) throw std::runtime_error(moved.error().to_string());
  return copy;
}

engine::PackedMeshFile pack(const MeshBvh& bvh, const std::string& dir) {
  auto file = engine::write_packed_mesh(bvh, dir);
  if (!file.ok()) throw std::runtime_error(file.error().to_string());
  return file.value();
}

constexpr const char* kIndexName = "scene.index";
constexpr const char* kIndexHeader = "gatekeeper-factory-index 2";

// The scene's objects (every one packed) and rules, as text with round-trip doubles.
void write_index(const FactoryScene& scene, const std::string& dir) {
  const std::string path = dir + "/" + kIndexName, tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    char number[32];
    auto put = [&](double v) {
      std::snprintf(number, sizeof number, "%.17g", v);
      out << '\t' << number;
    };
    out << kIndexHeader << "\nrules " << scene.rules.size() << "\n";
    for (const engine::ContactRule& r : scene.rules)
      out << r.name << '\t' << r.category_a << '\t' << r.category_b << '\t' << (r.same_group_only ? 1 : 0) << "\n";
    out << "objects " << scene.objects.size() << "\n";
    for (const AuditObject& o : scene.objects) {
      out << o.name << '\t' << o.category << '\t' << (o.group.empty() ? "-" : o.group);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) put(o.pose.rotation(i, j));
      for (int i = 0; i < 3; ++i) put(o.pose.translation[i]);
      put(o.surface_deviation_mm);
      out << '\t' << std::filesystem::path(o.packed->path).filename().string();
      for (int i = 0; i < 3; ++i) put(o.packed->bounds.min[i]);
      for (int i = 0; i < 3; ++i) put(o.packed->bounds.max[i]);
      char sum[40];
      std::snprintf(sum, sizeof sum, "%016llx:%016llx", static_cast<unsigned long long>(o.packed->checksum.low),
                    static_cast<unsigned long long>(o.packed->checksum.high));
      out << '\t' << o.packed->triangles << '\t' << o.packed->bytes << '\t' << sum << "\n";
    }
    out << "end\n";
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
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
  // With pack_dir, each copy is written and released as soon as it is built.
  if (options.distinct_meshes) {
    std::vector<std::size_t> copies;
    for (std::size_t i = 0; i < scene.objects.size(); ++i)
      if (scene.objects[i].category == "robot" || scene.objects[i].category == "machine") copies.push_back(i);
    std::atomic<std::size_t> next{0};
    auto work = [&] {
      for (std::size_t k = next++; k < copies.size(); k = next++) {
        AuditObject& o = scene.objects[copies[k]];
        o.mesh = bvh_of(options.deformed ? deformed(o.mesh->mesh(), options.seed * 1000003ull + copies[k], options.deform_mm)
                                         : o.mesh->mesh());
        if (!options.pack_dir.empty()) {
          o.packed = pack(*o.mesh, options.pack_dir);
          o.mesh.reset();
        }
      }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < std::max(1u, std::thread::hardware_concurrency()); ++t) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
  }
  if (!options.pack_dir.empty()) {
    std::map<const MeshBvh*, engine::PackedMeshFile> shared_packs;
    for (AuditObject& o : scene.objects) {
      if (!o.mesh) continue;
      auto known = shared_packs.find(o.mesh.get());
      if (known == shared_packs.end()) known = shared_packs.emplace(o.mesh.get(), pack(*o.mesh, options.pack_dir)).first;
      o.packed = known->second;
      o.mesh.reset();
    }
    write_index(scene, options.pack_dir);
  }
  std::map<std::string, int> unique;
  for (const AuditObject& o : scene.objects) {
    char pointer[32];
    std::snprintf(pointer, sizeof pointer, "%p", static_cast<const void*>(o.mesh.get()));
    unique[o.mesh ? pointer : o.packed->path] = 1;
  }
  scene.unique_meshes = unique.size();
  g_cache = nullptr;
  return scene;
}

Result<FactoryScene> read_factory_scene_index(const std::string& pack_dir) {
  const std::string path = pack_dir + "/" + kIndexName;
  std::ifstream in(path);
  std::string line;
  auto bad = [&](const std::string& why) { return invalid_argument(path, why); };
  if (!in || !std::getline(in, line) || line != kIndexHeader) return bad("is not a factory scene index");
  auto fields = [](const std::string& text) {
    std::vector<std::string> out;
    std::stringstream s(text);
    for (std::string f; std::getline(s, f, '\t');) out.push_back(f);
    return out;
  };
  FactoryScene scene;
  std::size_t count = 0;
  if (!std::getline(in, line) || std::sscanf(line.c_str(), "rules %zu", &count) != 1) return bad("has no rule count");
  for (std::size_t k = 0; k < count; ++k) {
    if (!std::getline(in, line)) return bad("ends inside the rules");
    const auto f = fields(line);
    if (f.size() != 4) return bad("has a malformed rule");
    scene.rules.push_back({f[0], f[1], f[2], f[3] == "1"});
  }
  if (!std::getline(in, line) || std::sscanf(line.c_str(), "objects %zu", &count) != 1) return bad("has no object count");
  for (std::size_t k = 0; k < count; ++k) {
    if (!std::getline(in, line)) return bad("ends inside the objects");
    const auto f = fields(line);
    if (f.size() != 3 + 12 + 1 + 1 + 6 + 3) return bad("has a malformed object line " + std::to_string(k));
    AuditObject o;
    o.name = f[0];
    o.category = f[1];
    o.group = f[2] == "-" ? "" : f[2];
    std::size_t at = 3;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) o.pose.rotation(i, j) = std::stod(f[at++]);
    for (int i = 0; i < 3; ++i) o.pose.translation[i] = std::stod(f[at++]);
    o.surface_deviation_mm = std::stod(f[at++]);
    engine::PackedMeshFile file;
    file.path = pack_dir + "/" + f[at++];
    Vec3 lo, hi;
    for (int i = 0; i < 3; ++i) lo[i] = std::stod(f[at++]);
    for (int i = 0; i < 3; ++i) hi[i] = std::stod(f[at++]);
    file.bounds.extend(lo);
    file.bounds.extend(hi);
    file.triangles = std::stoull(f[at++]);
    file.bytes = std::stoull(f[at++]);
    unsigned long long low = 0, high = 0;
    if (std::sscanf(f[at++].c_str(), "%llx:%llx", &low, &high) != 2) return bad("has a malformed checksum on object line " + std::to_string(k));
    file.checksum.low = low;
    file.checksum.high = high;
    scene.triangles += file.triangles;
    o.packed = std::move(file);
    scene.objects.push_back(std::move(o));
  }
  if (!std::getline(in, line) || line != "end") return bad("is incomplete");
  std::map<std::string, int> unique;
  for (const AuditObject& o : scene.objects) unique[o.packed->path] = 1;
  scene.unique_meshes = unique.size();
  return scene;
}

}  // namespace gk::testing
