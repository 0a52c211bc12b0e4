// The audit out of core: meshes read from packs tile by tile within a memory budget give the same
// clashes as the audit with every mesh in memory (itself checked against assessing every pair in
// scene_audit_test), each mesh is read once, and what is held never exceeds the budget unless a
// tile alone does. A damaged pack makes its pairs INCONCLUSIVE, naming the file, never CLEAR.
#include "engine/audits/scene_audit.h"
#include "engine/audits/tile_scheduler.h"
#include "tests/support/factory_scene.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <thread>

namespace gk::engine {
namespace {

std::string fresh_dir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/gk_" + name + "_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(TileScheduler, EveryMeshIsReadOnceAndHeldOnlyWhileItsTilesRunWithinTheBudget) {
  const auto mesh = MeshBvh::build(testing::share(testing::box_mesh(Vec3::Zero(), Vec3::Ones()))).value();
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 40; ++trial) {
    const std::uint32_t objects = 60;
    const std::size_t tiles = 1 + rng() % 25;
    // Pairs in tiles; objects recur across tiles (ghosts), some objects are in memory.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> work;
    std::vector<TileScheduler::Tile> plan(tiles);
    for (std::size_t t = 0; t < tiles; ++t) {
      plan[t].id = 100 + t;
      const std::size_t n = rng() % 12;  // some tiles have no pair
      for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t a = static_cast<std::uint32_t>(rng() % objects), b = static_cast<std::uint32_t>(rng() % objects);
        if (a == b) continue;
        plan[t].pairs.push_back(work.size());
        work.emplace_back(std::min(a, b), std::max(a, b));
      }
    }
    TileScheduler::Setup setup;
    setup.tiles = plan;
    setup.work = &work;
    std::uint64_t largest_tile = 0;
    for (std::uint32_t o = 0; o < objects; ++o) {
      setup.in_memory.push_back(o % 7 == 0 ? mesh : nullptr);
      setup.bytes.push_back(o % 7 == 0 ? 0 : 10 + rng() % 90);
    }
    for (const auto& t : plan) {
      std::set<std::uint32_t> used;
      for (std::size_t i : t.pairs) used.insert({work[i].first, work[i].second});
      std::uint64_t bytes = 0;
      for (std::uint32_t o : used) bytes += setup.bytes[o];
      largest_tile = std::max(largest_tile, bytes);
    }
    setup.budget_bytes = trial % 4 == 0 ? 0 : 1 + rng() % 600;
    const std::vector<std::uint64_t> sizes = setup.bytes;  // setup is moved into the scheduler
    std::mutex m;
    std::map<std::uint32_t, int> reads;
    std::uint64_t live = 0, most_live = 0;
    setup.loader = [&](std::uint32_t o) -> Result<std::shared_ptr<const MeshBvh>> {
      if (o == 13) return invalid_argument("objects[13]", "unreadable");
      std::lock_guard<std::mutex> lock(m);
      ++reads[o];
      live += sizes[o];
      most_live = std::max(most_live, live);
      const std::uint64_t bytes = sizes[o];
      // Counts the release: the scheduler drops its last reference when no later tile needs it.
      return std::shared_ptr<const MeshBvh>(mesh.get(), [&, bytes, keep = mesh](const MeshBvh*) {
        std::lock_guard<std::mutex> release(m);
        live -= bytes;
      });
    };
    const std::uint64_t budget = setup.budget_bytes;
    TileScheduler scheduler(std::move(setup));
    std::vector<int> done(work.size(), 0);
    std::set<std::size_t> finished_tiles;
    std::mutex done_mutex;
    auto worker = [&] {
      while (auto s = scheduler.next(nullptr)) {
        const auto [a, b] = work[s->work_index];
        if (a == 13 || b == 13) {
          EXPECT_NE(s->error.find("unreadable"), std::string::npos);
        } else {
          EXPECT_TRUE(s->error.empty());
          EXPECT_TRUE(s->a && s->b);
        }
        std::lock_guard<std::mutex> lock(done_mutex);
        ++done[s->work_index];
        if (auto t = scheduler.finish(s->work_index)) {
          EXPECT_TRUE(finished_tiles.insert(*t).second);
        }
      }
    };
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) threads.emplace_back(worker);
    for (auto& t : threads) t.join();
    for (int d : done) EXPECT_EQ(d, 1);  // every pair handed out once
    for (const auto& [o, n] : reads) EXPECT_EQ(n, 1) << "object " << o << " read " << n << " times";
    EXPECT_EQ(live, 0u);  // everything read was released
    const auto stats = scheduler.stats();
    if (budget != 0 && stats.tiles_over_budget == 0) {
      EXPECT_LE(most_live, budget) << "trial " << trial;
    }
    if (budget != 0 && largest_tile <= budget) {
      EXPECT_EQ(stats.tiles_over_budget, 0u);
    }
    std::size_t tiles_with_pairs = 0;
    for (const auto& t : plan) tiles_with_pairs += t.pairs.empty() ? 0 : 1;
    EXPECT_EQ(finished_tiles.size(), tiles_with_pairs);
  }
}

bool same_clash(const PairClash& l, const PairClash& r) {
  return l.a == r.a && l.b == r.b && l.verdict == r.verdict && l.distance_mm == r.distance_mm &&
         l.clearance_violation == r.clearance_violation && (l.contacts_truncated || l.contacts == r.contacts) &&
         l.error == r.error;
}

testing::FactorySceneOptions deformed_factory(const std::string& pack_dir) {
  testing::FactorySceneOptions o;
  o.objects = 160;
  o.triangles = 800'000;
  o.distinct_meshes = true;
  o.deformed = true;
  o.pack_dir = pack_dir;
  return o;
}

TEST(SceneAudit, OutOfCoreWithinAnyBudgetEqualsTheAuditInMemory) {
  const std::string dir = fresh_dir("packs");
  const testing::FactoryScene in_memory = testing::generate_factory_scene(deformed_factory(""));
  const testing::FactoryScene packed = testing::generate_factory_scene(deformed_factory(dir));
  const auto indexed = testing::read_factory_scene_index(dir);
  ASSERT_TRUE(indexed.ok()) << indexed.error().to_string();
  ASSERT_EQ(indexed.value().objects.size(), in_memory.objects.size());
  // Every copy its own content: distinct packs for the robot links and machines.
  EXPECT_GT(indexed.value().unique_meshes, 40u);
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < in_memory.objects.size(); ++i) {
    const AuditObject& o = indexed.value().objects[i];
    ASSERT_FALSE(o.mesh);
    ASSERT_TRUE(o.packed);
    EXPECT_EQ(o.name, in_memory.objects[i].name);
    EXPECT_EQ(o.pose.rotation, in_memory.objects[i].pose.rotation);
    EXPECT_EQ(o.pose.translation, in_memory.objects[i].pose.translation);
    EXPECT_EQ(o.packed->triangles, in_memory.objects[i].mesh->mesh().triangle_count());
    total += o.packed->bytes;
  }
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = in_memory.rules;
  options.tile_mm = 12000.0;
  const AuditResult expected = audit_scene(in_memory.objects, options).value();
  ASSERT_GT(expected.clashes.size(), 20u);
  ASSERT_GT(expected.tiles, 4u);
  const std::vector<std::pair<std::uint64_t, int>> runs = {{0, 2}, {1, 1}, {total / 8, 2}, {total / 30, 3}};
  for (const auto& [budget, threads] : runs) {
      options.memory_budget_bytes = budget;
      options.threads = threads;
      const AuditResult got = audit_scene(indexed.value().objects, options).value();
      ASSERT_EQ(got.clashes.size(), expected.clashes.size()) << "budget " << budget;
      for (std::size_t k = 0; k < got.clashes.size(); ++k) {
        EXPECT_TRUE(same_clash(got.clashes[k], expected.clashes[k])) << got.clashes[k].a << "-" << got.clashes[k].b;
      }
      EXPECT_GT(got.meshes_read, 0u);
      EXPECT_LE(got.meshes_read, got.objects);  // each at most once
      if (budget > 1 && got.tiles_over_budget == 0) {
        EXPECT_LE(got.peak_held_bytes, budget);
      }
      if (budget == 1) {
        EXPECT_GT(got.tiles_over_budget, 0u);  // one tile at a time, still complete
      }
    }
  // The generator's packed objects (before the index) audit the same.
  options.memory_budget_bytes = total / 10;
  const AuditResult from_generator = audit_scene(packed.objects, options).value();
  ASSERT_EQ(from_generator.clashes.size(), expected.clashes.size());
  std::filesystem::remove_all(dir);
}

TEST(SceneAudit, ADamagedPackMakesItsPairsInconclusiveNamingTheFileNeverClear) {
  const std::string dir = fresh_dir("damaged");
  const testing::FactoryScene packed = testing::generate_factory_scene(deformed_factory(dir));
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = packed.rules;
  options.tile_mm = 12000.0;
  const AuditResult before = audit_scene(packed.objects, options).value();
  // Damage the pack of an object in a known collision (a robot link clashing with something).
  std::uint32_t victim = 0;
  for (const PairClash& c : before.clashes)
    if (c.verdict == Verdict::kCollision && packed.objects[c.a].category == "robot") {
      victim = c.a;
      break;
    }
  const std::string path = packed.objects[victim].packed->path;
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    f.put('\x7f');
  }
  const AuditResult after = audit_scene(packed.objects, options).value();
  std::size_t inconclusive = 0;
  for (const PairClash& c : before.clashes) {
    auto it = std::find_if(after.clashes.begin(), after.clashes.end(), [&](const PairClash& x) { return x.a == c.a && x.b == c.b; });
    ASSERT_NE(it, after.clashes.end()) << "a clash disappeared";
    if (c.a == victim || c.b == victim) {
      EXPECT_EQ(it->verdict, Verdict::kInconclusive);
      EXPECT_EQ(it->inconclusive_reason, InconclusiveReason::kPairFailed);
      EXPECT_NE(it->error.find(path), std::string::npos) << it->error;
      EXPECT_NE(it->error.find("checksum"), std::string::npos) << it->error;
      ++inconclusive;
    } else {
      EXPECT_TRUE(same_clash(*it, c));
    }
  }
  EXPECT_GT(inconclusive, 0u);
  // A pack removed, or replaced by another mesh's: the same.
  std::filesystem::remove(path);
  const AuditResult removed = audit_scene(packed.objects, options).value();
  for (const PairClash& c : removed.clashes) {
    if (c.a == victim || c.b == victim) {
      EXPECT_EQ(c.verdict, Verdict::kInconclusive);
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(SceneAudit, PackedObjectsAreRefusedWhereMeshesMustBeInMemory) {
  AuditObject o;
  o.packed = PackedMeshFile{"/nonexistent.pack", Aabb{Vec3::Zero(), Vec3::Ones()}, 12, 1000};
  EXPECT_TRUE(check_objects({o}, true).ok());
  const auto refused = check_objects({o}, false);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().to_string().find("objects[0].mesh"), std::string::npos);
  o.packed->triangles = 0;
  EXPECT_FALSE(check_objects({o}, true).ok());
}

}  // namespace
}  // namespace gk::engine
