// The audit out of core: meshes read from packs tile by tile within a memory budget give the same
// clashes as the audit with every mesh in memory (itself checked against assessing every pair in
// scene_audit_test), each mesh is read once, and what is held never exceeds the budget unless a
// tile alone does. A damaged pack makes its pairs INCONCLUSIVE, naming the file, never CLEAR.
#include "engine/audits/scene_audit.h"
#include "engine/audits/tile_scheduler.h"
#include "tests/support/factory_scene.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
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

// A loader handing out one shared mesh as every object's, counting the readings and the bytes
// alive (a reading's bytes end when the scheduler drops its last reference to it).
struct CountingLoader {
  std::shared_ptr<const MeshBvh> mesh;
  std::vector<std::uint64_t> sizes;
  std::uint32_t unreadable = 0xffffffffu;  // this object's reading fails
  std::mutex m;
  std::map<std::uint32_t, int> reads;
  std::uint64_t live = 0, most_live = 0;

  TileScheduler::Loader loader() {
    return [this](std::uint32_t o) -> Result<std::shared_ptr<const MeshBvh>> {
      if (o == unreadable) return invalid_argument("objects[" + std::to_string(o) + "]", "unreadable");
      std::lock_guard<std::mutex> lock(m);
      ++reads[o];
      live += sizes[o];
      most_live = std::max(most_live, live);
      const std::uint64_t bytes = sizes[o];
      return std::shared_ptr<const MeshBvh>(mesh.get(), [this, bytes, keep = mesh](const MeshBvh*) {
        std::lock_guard<std::mutex> release(m);
        live -= bytes;
      });
    };
  }
  std::size_t total_reads() const {
    std::size_t total = 0;
    for (const auto& [o, n] : reads) total += static_cast<std::size_t>(n);
    return total;
  }
};

TEST(TileScheduler, EveryMeshIsHeldOnlyWhileNeededWithinTheBudgetAndReadAgainOnlyWhenLetGo) {
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
    CountingLoader counting;
    counting.mesh = mesh;
    counting.sizes = setup.bytes;  // setup is moved into the scheduler
    counting.unreadable = 13;
    setup.loader = counting.loader();
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
        s->a.reset();  // the pair is done with its meshes before its tile may finish
        s->b.reset();
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
    EXPECT_EQ(counting.live, 0u);  // everything read was released
    const auto stats = scheduler.stats();
    // Read once, unless let go to fit the budget (then once more for each letting go).
    EXPECT_EQ(counting.total_reads(), counting.reads.size() + stats.meshes_let_go) << "trial " << trial;
    if (budget == 0) {
      EXPECT_EQ(stats.meshes_let_go, 0u);
    }
    if (budget != 0 && stats.tiles_over_budget == 0) {
      EXPECT_LE(counting.most_live, budget) << "trial " << trial;
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
  o.packed = PackedMeshFile{"/nonexistent.pack", Aabb{Vec3::Zero(), Vec3::Ones()}, 12, 1000, Hash128{}};
  EXPECT_TRUE(check_objects({o}, true).ok());
  const auto refused = check_objects({o}, false);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().to_string().find("objects[0].mesh"), std::string::npos);
  o.packed->triangles = 0;
  EXPECT_FALSE(check_objects({o}, true).ok());
}


// Objects sharing one mesh share its reading; long objects held for later tiles are let go when
// the budget needs the room (read again later): what is held stays within the budget whenever
// every tile alone fits it (the reviewer's rows of long objects, 8 rows).
TEST(TileScheduler, SharedMeshesAreReadOnceAndLongObjectsAreLetGoToKeepTheBudget) {
  const auto mesh = MeshBvh::build(testing::share(testing::box_mesh(Vec3::Zero(), Vec3::Ones()))).value();
  for (int threads : {1, 4}) {
    // Rows r = 0..7: a long object L_r in tiles (0, r) and (1, r); small ones S_r0 in (0, r), S_r1 in (1, r).
    // Tiles are admitted x-major: every row's tile (0, r) before any (1, r).
    const int rows = 8;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> work;
    std::vector<TileScheduler::Tile> plan;
    auto L = [](int r) { return static_cast<std::uint32_t>(3 * r); };
    auto S = [](int r, int x) { return static_cast<std::uint32_t>(3 * r + 1 + x); };
    for (int x = 0; x < 2; ++x)
      for (int r = 0; r < rows; ++r) {
        TileScheduler::Tile t;
        t.id = static_cast<std::size_t>(x * rows + r);
        t.pairs.push_back(work.size());
        work.emplace_back(std::min(L(r), S(r, x)), std::max(L(r), S(r, x)));
        plan.push_back(t);
      }
    TileScheduler::Setup setup;
    setup.tiles = plan;
    setup.work = &work;
    for (int o = 0; o < 3 * rows; ++o) {
      setup.in_memory.push_back(nullptr);
      setup.bytes.push_back(o % 3 == 0 ? 100 : 10);  // a long object is large
    }
    setup.budget_bytes = 250;  // two rows' long objects fit, not eight
    CountingLoader counting;
    counting.mesh = mesh;
    counting.sizes = setup.bytes;
    setup.loader = counting.loader();
    TileScheduler scheduler(std::move(setup));
    std::mutex done_mutex;
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
      pool.emplace_back([&] {
        while (auto s = scheduler.next(nullptr)) {
          EXPECT_TRUE(s->error.empty());
          s->a.reset();  // the pair is done with its meshes before its tile may finish
          s->b.reset();
          std::lock_guard<std::mutex> lock(done_mutex);
          scheduler.finish(s->work_index);
        }
      });
    for (auto& t : pool) t.join();
    const auto stats = scheduler.stats();
    EXPECT_EQ(stats.tiles_over_budget, 0u);
    EXPECT_LE(stats.peak_held_bytes, 250u);
    EXPECT_LE(counting.most_live, 250u) << threads << " threads";
    EXPECT_GT(stats.meshes_let_go, 0u);  // some long objects were read twice ...
    EXPECT_EQ(counting.total_reads(), counting.reads.size() + stats.meshes_let_go);  // ... exactly those let go
    EXPECT_EQ(counting.live, 0u);
  }
  // Ten objects on one mesh: one reading.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> work;
  TileScheduler::Tile tile;
  for (std::uint32_t o = 1; o < 10; ++o) {
    tile.pairs.push_back(work.size());
    work.emplace_back(0, o);
  }
  TileScheduler::Setup setup;
  setup.tiles = {tile};
  setup.work = &work;
  setup.mesh_of.assign(10, 0);
  setup.in_memory = {nullptr};
  setup.bytes = {1000};
  setup.file_bytes = {900};
  int loads = 0;
  setup.loader = [&](std::uint32_t) -> Result<std::shared_ptr<const MeshBvh>> {
    ++loads;
    return std::shared_ptr<const MeshBvh>(mesh);
  };
  TileScheduler scheduler(std::move(setup));
  while (auto s = scheduler.next(nullptr)) scheduler.finish(s->work_index);
  EXPECT_EQ(loads, 1);
  EXPECT_EQ(scheduler.stats().bytes_read, 900u);
}

// Another valid pack put in the place of an object's (same size, triangle count and bounds: the
// reviewer's cube with its top's centre moved down) is refused by its checksum: INCONCLUSIVE, not
// the other mesh's answer; and a FIFO there is refused at once, never waited on.
TEST(SceneAudit, AnotherValidPackInAnObjectsPlaceOrAFifoIsRefusedNeverTrusted) {
  const std::string dir = fresh_dir("swapped");
  auto topped = [](double centre_z) {
    // A 100 mm cube whose top is four triangles around a centre vertex.
    std::vector<Vec3> v = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}, {0, 0, 100}, {100, 0, 100}, {100, 100, 100}, {0, 100, 100}, {50, 50, centre_z}};
    std::vector<TriangleMesh::Face> f = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6},
                                         {3, 0, 4}, {3, 4, 7}, {4, 5, 8}, {5, 6, 8}, {6, 7, 8}, {7, 4, 8}};
    return MeshBvh::build(testing::share(TriangleMesh::create(v, f).value())).value();
  };
  const auto real = topped(100.0), sunk = topped(55.0);
  const auto poker = MeshBvh::build(testing::share(testing::box_mesh(Vec3(40, 40, 90), Vec3(60, 60, 150)))).value();
  const PackedMeshFile real_file = write_packed_mesh(*real, dir).value();
  const PackedMeshFile sunk_file = write_packed_mesh(*sunk, dir).value();
  ASSERT_EQ(real_file.bytes, sunk_file.bytes);
  ASSERT_EQ(real_file.triangles, sunk_file.triangles);
  std::vector<AuditObject> objects(2);
  objects[0].packed = real_file;
  objects[1].mesh = poker;
  AuditOptions options;
  options.memory_budget_bytes = 1 << 20;
  ASSERT_EQ(audit_scene(objects, options).value().clashes.at(0).verdict, Verdict::kCollision);
  std::filesystem::copy_file(sunk_file.path, real_file.path, std::filesystem::copy_options::overwrite_existing);
  const AuditResult swapped = audit_scene(objects, options).value();
  ASSERT_EQ(swapped.clashes.size(), 1u);
  EXPECT_EQ(swapped.clashes[0].verdict, Verdict::kInconclusive);
  EXPECT_NE(swapped.clashes[0].error.find("not the pack written for this object"), std::string::npos) << swapped.clashes[0].error;
  // Writing the pack again replaces the wrong file (same size, other checksum).
  ASSERT_TRUE(write_packed_mesh(*real, dir).ok());
  EXPECT_EQ(audit_scene(objects, options).value().clashes.at(0).verdict, Verdict::kCollision);
  std::filesystem::remove(real_file.path);
  ASSERT_EQ(::mkfifo(real_file.path.c_str(), 0644), 0);
  const AuditResult fifo = audit_scene(objects, options).value();  // returns: never blocks on the FIFO
  ASSERT_EQ(fifo.clashes.size(), 1u);
  EXPECT_EQ(fifo.clashes[0].verdict, Verdict::kInconclusive);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace gk::engine
