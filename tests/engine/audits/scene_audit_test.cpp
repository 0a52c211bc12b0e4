// The scene audit against brute force: broad phases against all-pairs box tests on mixed scales;
// the audit against assessing every pair; tiled against untiled, parallel against serial;
// cancellation, incremental re-audit, rules and the generator's known answers.
#include "kernel/broadphase/broad_phase.h"
#include "engine/scenes/layout_session.h"
#include "engine/audits/scene_audit.h"
#include "tests/support/factory_scene.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <tuple>

namespace gk::engine {
namespace {

std::vector<Aabb> mixed_scale_boxes(unsigned seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> pos(0.0, 100000.0);
  std::uniform_real_distribution<double> exponent(0.0, 4.5);  // 1 mm to 30 m
  std::vector<Aabb> boxes;
  for (int i = 0; i < n; ++i) {
    const Vec3 lo(pos(rng), pos(rng), pos(rng) * 0.05);
    const Vec3 size(std::pow(10.0, exponent(rng)), std::pow(10.0, exponent(rng)), std::pow(10.0, exponent(rng)));
    boxes.push_back({lo, lo + size});
  }
  boxes.push_back({Vec3(0, 50000, 0), Vec3(100000, 50100, 9000)});  // a wall across everything
  boxes.push_back(Aabb{});                                           // an empty box never pairs
  return boxes;
}

TEST(BroadPhase, SweepAndPruneAndHashGridEqualAllPairsOnMixedScales) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const std::vector<Aabb> boxes = mixed_scale_boxes(seed, 3000);
    for (double margin : {0.0, 50.0}) {
      const auto expected = all_overlapping_pairs(boxes, margin);
      ASSERT_GT(expected.size(), 100u);
      EXPECT_EQ(sweep_and_prune(boxes, margin), expected) << "seed " << seed;
      HashGridStats stats;
      EXPECT_EQ(hash_grid_pairs(boxes, margin, &stats), expected) << "seed " << seed;
      EXPECT_GT(stats.oversized, 0u);  // the wall and the 30 m boxes stay out of the grid
      EXPECT_LT(stats.cell_entries, 20 * boxes.size());
    }
  }
}

bool same_clash(const PairClash& l, const PairClash& r) {
  return l.a == r.a && l.b == r.b && l.verdict == r.verdict && l.distance_mm == r.distance_mm &&
         l.contacts == r.contacts && l.regions.size() == r.regions.size();
}

void expect_same_clashes(const AuditResult& l, const AuditResult& r) {
  ASSERT_EQ(l.clashes.size(), r.clashes.size());
  for (std::size_t i = 0; i < l.clashes.size(); ++i)
    EXPECT_TRUE(same_clash(l.clashes[i], r.clashes[i])) << l.clashes[i].a << "-" << l.clashes[i].b;
}

const testing::FactoryScene& small_factory() {
  static const testing::FactoryScene scene = [] {
    testing::FactorySceneOptions o;
    o.objects = 160;
    o.triangles = 1'200'000;
    return testing::generate_factory_scene(o);
  }();
  return scene;
}

TEST(SceneAudit, EqualsAssessingEveryPairOfASmallFactory) {
  const auto& scene = small_factory();
  ASSERT_GT(scene.objects.size(), 150u);
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = scene.rules;
  const AuditResult audit = audit_scene(scene.objects, options).value();
  EXPECT_FALSE(audit.cancelled);
  EXPECT_GT(audit.excluded_by_rules, 0u);
  // The oracle: every pair, no broad phase.
  std::vector<std::tuple<std::uint32_t, std::uint32_t, Verdict, double>> expected;
  for (std::uint32_t i = 0; i < scene.objects.size(); ++i)
    for (std::uint32_t j = i + 1; j < scene.objects.size(); ++j) {
      const AuditObject& a = scene.objects[i];
      const AuditObject& b = scene.objects[j];
      if (matching_rule(scene.rules, a, b) >= 0) continue;
      const VerdictResult v = assess(*a.mesh, a.pose, *b.mesh, b.pose).value();
      if (v.verdict == Verdict::kClear && v.distance_mm >= options.clearance_mm) continue;
      expected.emplace_back(i, j, v.verdict, v.distance_mm);
    }
  ASSERT_EQ(audit.clashes.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(audit.clashes[k].a, std::get<0>(expected[k]));
    EXPECT_EQ(audit.clashes[k].b, std::get<1>(expected[k]));
    EXPECT_EQ(audit.clashes[k].verdict, std::get<2>(expected[k]));
    EXPECT_NEAR(audit.clashes[k].distance_mm, std::get<3>(expected[k]), 1e-9);
  }
  // The known answers are among them.
  for (const testing::KnownPair& known : scene.known) {
    auto it = std::find_if(audit.clashes.begin(), audit.clashes.end(),
                           [&](const PairClash& c) { return c.a == known.a && c.b == known.b; });
    ASSERT_NE(it, audit.clashes.end()) << scene.objects[known.a].name;
    if (known.clash) {
      EXPECT_EQ(it->verdict, Verdict::kCollision);
      EXPECT_FALSE(it->regions.empty());
    } else {
      EXPECT_TRUE(it->clearance_violation);
      EXPECT_NEAR(it->distance_mm, known.gap_mm, 1e-9);
    }
  }
}

TEST(SceneAudit, TiledEqualsUntiledAndParallelEqualsSerialInTheSameOrder) {
  const auto& scene = small_factory();
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = scene.rules;
  const AuditResult serial = audit_scene(scene.objects, options).value();
  options.tile_mm = 15000.0;
  const AuditResult tiled = audit_scene(scene.objects, options).value();
  EXPECT_GT(tiled.tiles, 4u);
  EXPECT_GT(tiled.ghost_entries, 0u);  // the pipes and walls cross tiles
  EXPECT_EQ(tiled.candidate_pairs, serial.candidate_pairs);
  expect_same_clashes(serial, tiled);
  options.threads = 4;
  const AuditResult parallel = audit_scene(scene.objects, options).value();
  expect_same_clashes(serial, parallel);
  // Without the rules the robot links of one cell clash with each other.
  options.rules.clear();
  EXPECT_GT(audit_scene(scene.objects, options).value().clashes.size(), serial.clashes.size());
}

TEST(SceneAudit, ACancelledAuditKeepsConsistentPartialResults) {
  const auto& scene = small_factory();
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.threads = 2;
  const AuditResult full = audit_scene(scene.objects, options).value();
  std::atomic<bool> cancel{false};
  options.cancel = &cancel;
  options.progress_interval_s = 0.0;
  std::size_t reports = 0;
  options.on_progress = [&](const AuditProgress& p) {
    ++reports;
    if (p.pairs_done >= p.pairs_total / 3) cancel = true;
  };
  const AuditResult partial = audit_scene(scene.objects, options).value();
  EXPECT_TRUE(partial.cancelled);
  EXPECT_GT(reports, 2u);
  EXPECT_LT(partial.pairs_done, full.pairs_done);
  EXPECT_LT(partial.clashes.size(), full.clashes.size());
  EXPECT_GT(partial.clashes.size(), 0u);  // the subset check below has something to check
  // Every partial clash is exactly the full audit's answer for that pair.
  for (const PairClash& c : partial.clashes) {
    auto it = std::find_if(full.clashes.begin(), full.clashes.end(), [&](const PairClash& f) { return f.a == c.a && f.b == c.b; });
    ASSERT_NE(it, full.clashes.end());
    EXPECT_TRUE(same_clash(*it, c));
  }
}

// Checkpoints: every tile with pairs is handed over once, its clashes together are the audit's;
// an audit cancelled part way hands over only whole tiles; and an audit resumed from any set of
// finished tiles (their clashes added back) equals the uninterrupted one, clash for clash.
TEST(SceneAudit, TileCheckpointsResumeToTheUninterruptedResult) {
  const auto& scene = small_factory();
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = scene.rules;
  options.tile_mm = 12000.0;
  options.threads = 2;
  std::map<std::size_t, std::vector<PairClash>> tiles;
  std::size_t handed = 0;
  options.on_tile_done = [&](std::size_t tile, const std::vector<PairClash>& clashes) {
    ++handed;
    EXPECT_TRUE(tiles.emplace(tile, clashes).second) << "tile " << tile << " handed over twice";
  };
  const AuditResult full = audit_scene(scene.objects, options).value();
  ASSERT_GT(tiles.size(), 4u);
  std::vector<PairClash> joined;
  for (const auto& [tile, clashes] : tiles) joined.insert(joined.end(), clashes.begin(), clashes.end());
  sort_in_pair_order(joined);
  AuditResult from_tiles = full;
  from_tiles.clashes = joined;
  expect_same_clashes(full, from_tiles);

  // Cancelled after a third of the pairs: only tiles whose every pair was done, each exactly as
  // in the full run.
  std::map<std::size_t, std::vector<PairClash>> partial_tiles;
  AuditOptions cut = options;
  std::atomic<bool> cancel{false};
  cut.cancel = &cancel;
  cut.progress_interval_s = 0.0;
  cut.on_progress = [&](const AuditProgress& p) {
    if (p.pairs_done >= p.pairs_total / 3) cancel = true;
  };
  cut.on_tile_done = [&](std::size_t tile, const std::vector<PairClash>& clashes) { partial_tiles.emplace(tile, clashes); };
  EXPECT_TRUE(audit_scene(scene.objects, cut).value().cancelled);
  ASSERT_FALSE(partial_tiles.empty());
  EXPECT_LT(partial_tiles.size(), tiles.size());
  for (const auto& [tile, clashes] : partial_tiles) {
    ASSERT_EQ(tiles.count(tile), 1u);
    ASSERT_EQ(clashes.size(), tiles[tile].size()) << "tile " << tile;
    for (std::size_t i = 0; i < clashes.size(); ++i) EXPECT_TRUE(same_clash(clashes[i], tiles[tile][i]));
  }

  // Resumed from random sets of finished tiles (the cancelled run's among them).
  std::mt19937_64 rng(17);
  std::vector<std::map<std::size_t, std::vector<PairClash>>> resumptions = {partial_tiles};
  for (int round = 0; round < 4; ++round) {
    std::map<std::size_t, std::vector<PairClash>> some;
    for (const auto& [tile, clashes] : tiles)
      if (rng() % 2) some.emplace(tile, clashes);
    resumptions.push_back(some);
  }
  for (const auto& finished : resumptions) {
    AuditOptions resume = options;
    resume.on_tile_done = [&](std::size_t tile, const std::vector<PairClash>&) {
      EXPECT_EQ(finished.count(tile), 0u) << "a finished tile computed again: " << tile;
    };
    for (const auto& [tile, clashes] : finished) resume.skip_tiles.push_back(tile);
    AuditResult resumed = audit_scene(scene.objects, resume).value();
    EXPECT_FALSE(resumed.cancelled);
    EXPECT_EQ(resumed.pairs_done, full.pairs_done);
    EXPECT_EQ(resumed.candidate_pairs, full.candidate_pairs);
    for (const auto& [tile, clashes] : finished) resumed.clashes.insert(resumed.clashes.end(), clashes.begin(), clashes.end());
    sort_in_pair_order(resumed.clashes);
    expect_same_clashes(full, resumed);
  }
}

TEST(SceneAudit, AReauditAfterMovingObjectsEqualsAFullAudit) {
  testing::FactoryScene scene = small_factory();
  AuditOptions options;
  options.clearance_mm = 5.0;
  options.rules = scene.rules;
  const AuditResult before = audit_scene(scene.objects, options).value();
  // Move a crate of a deliberate clash away, and a column into a conveyor's path.
  const std::uint32_t crate = scene.known.front().b;
  scene.objects[crate].pose.translation += Vec3(0, 5000, 0);
  std::uint32_t column = 0;
  while (scene.objects[column].category != "column") ++column;
  scene.objects[column].pose.translation += Vec3(4000, 5000, 0);
  const AuditResult incremental = reaudit_scene(scene.objects, before, {crate, column}, options).value();
  const AuditResult full = audit_scene(scene.objects, options).value();
  expect_same_clashes(full, incremental);
  auto has_pair = [](const AuditResult& r, std::uint32_t a, std::uint32_t b) {
    return std::any_of(r.clashes.begin(), r.clashes.end(), [&](const PairClash& c) { return c.a == a && c.b == b; });
  };
  EXPECT_TRUE(has_pair(before, scene.known.front().a, crate));
  EXPECT_FALSE(has_pair(full, scene.known.front().a, crate));
}

struct DragStats {
  unsigned cache_hits = 0, exact = 0, frames_with_contacts = 0;
};

// Drags object `moving` through `poses`; every frame must equal assessing every static object.
DragStats drag_and_compare(const testing::FactoryScene& scene, std::uint32_t moving, double clearance,
                           const std::vector<RigidTransform>& poses) {
  DragStats stats;
  auto session = LayoutSession::create(scene.objects, moving, clearance).value();
  for (std::size_t frame = 0; frame < poses.size(); ++frame) {
    const RigidTransform& pose = poses[frame];
    const FrameAnswer answer = session->move_to(pose).value();
    std::vector<FrameContact> expected;
    for (std::uint32_t i = 0; i < scene.objects.size(); ++i) {
      if (i == moving) continue;
      const VerdictResult v = assess(*scene.objects[moving].mesh, pose, *scene.objects[i].mesh, scene.objects[i].pose).value();
      if (v.verdict == Verdict::kClear && v.distance_mm >= clearance) continue;
      expected.push_back({i, v.verdict, v.distance_mm, v.point_a, v.point_b});
    }
    EXPECT_EQ(answer.contacts.size(), expected.size()) << "frame " << frame;
    if (answer.contacts.size() != expected.size()) return stats;
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_EQ(answer.contacts[k].other, expected[k].other);
      EXPECT_EQ(answer.contacts[k].verdict, expected[k].verdict);
      EXPECT_NEAR(answer.contacts[k].distance_mm, expected[k].distance_mm, 1e-9);
    }
    stats.cache_hits += answer.axis_cache_hits;
    stats.exact += answer.exact_checks;
    stats.frames_with_contacts += expected.empty() ? 0 : 1;
  }
  return stats;
}

std::uint32_t first_of(const testing::FactoryScene& scene, const std::string& category) {
  std::uint32_t i = 0;
  while (scene.objects[i].category != category) ++i;
  return i;
}

TEST(LayoutSession, EveryFrameEqualsAssessingEveryStaticObject) {
  const auto& scene = small_factory();
  // A robot link dragged diagonally through its cell and the next bays, turning.
  const std::uint32_t robot = first_of(scene, "robot");
  const RigidTransform start = scene.objects[robot].pose;
  std::vector<RigidTransform> path;
  for (int frame = 0; frame < 40; ++frame)
    path.push_back(RigidTransform::from_axis_angle(Vec3::UnitZ(), 0.02 * frame, start.translation + Vec3(150.0 * frame, 110.0 * frame, 0)));
  const DragStats robot_drag = drag_and_compare(scene, robot, 20.0, path);
  EXPECT_GT(robot_drag.exact, 0u);
  EXPECT_GT(robot_drag.frames_with_contacts, 0u);
  // A crate slid along the first row of columns, 30 mm from their faces and slowly turning: the
  // columns' boxes meet the crate's, the separating axes clear them, and the cached axis is reused
  // frame after frame.
  const std::uint32_t crate = first_of(scene, "crate");
  path.clear();
  for (int frame = 0; frame < 300; ++frame)
    path.push_back(RigidTransform::from_axis_angle(Vec3::UnitZ(), 1e-4 * frame, Vec3(-1000.0 + 50.0 * frame, 730.0, 0)));
  const DragStats slide = drag_and_compare(scene, crate, 20.0, path);
  EXPECT_GT(slide.cache_hits, 10u);
  EXPECT_EQ(LayoutSession::create(scene.objects, 1u << 30, 1.0).error().field, "moving");
  auto session = LayoutSession::create(scene.objects, crate, 1.0).value();
  RigidTransform bad = start;
  bad.rotation(0, 0) = 2.0;
  EXPECT_EQ(session->move_to(bad).error().field, "pose");
}

TEST(SceneAudit, DepthAndVolumeOnRequestMatchTheCratesKnownOverlap) {
  const auto& scene = small_factory();
  std::vector<AuditObject> crates;
  for (const AuditObject& o : scene.objects)
    if (o.category == "crate") crates.push_back(o);
  AuditOptions options;
  options.compute_depth = true;
  options.compute_volume = true;
  const AuditResult r = audit_scene(crates, options).value();
  ASSERT_EQ(r.clashes.size(), 10u);  // the deliberate clashes; near misses are beyond a 0 mm clearance
  for (const PairClash& c : r.clashes) {
    EXPECT_EQ(c.verdict, Verdict::kCollision);
    EXPECT_NEAR(c.depth_mm, 5.0, 2e-3);              // 5 mm along x: exact for convex crates
    EXPECT_NEAR(c.volume_mm3, 5.0 * 1000 * 1000, 1e-3);  // axis-aligned: the ray cast is exact
  }
}

TEST(SceneAudit, BadInputNamesTheField) {
  std::vector<AuditObject> objects(2);
  objects[0].mesh = MeshBvh::build(testing::share(testing::box_mesh(Vec3::Zero(), Vec3::Ones()))).value();
  AuditOptions options;
  EXPECT_EQ(audit_scene(objects, options).error().field, "objects[1].mesh");
  objects[1] = objects[0];
  objects[1].pose.translation.x() = std::nan("");
  EXPECT_EQ(audit_scene(objects, options).error().field, "objects[1].pose");
  objects[1].pose.translation.x() = 0.5;
  options.threads = 0;
  EXPECT_EQ(audit_scene(objects, options).error().field, "threads");
  options.threads = 1;
  options.clearance_mm = -1;
  EXPECT_EQ(audit_scene(objects, options).error().field, "clearance_mm");
  options.clearance_mm = 0;
  EXPECT_EQ(audit_scene(objects, options).value().clashes.size(), 1u);
}

}  // namespace
}  // namespace gk::engine
