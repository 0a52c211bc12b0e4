// The checkpoint store of running audits: a tile's clashes come back bit for bit (every field,
// empty boxes and unit directions included), an empty or cut tile record is refused, jobs come
// back with their snapshot, options and cancel in the order they began, forget() removes a job
// and its tiles, and damage never costs other jobs: a damaged tile is left out (computed again),
// a damaged job record comes back unreadable (it ends FAILED), a row without an id is skipped.
#include "server/audit_checkpoint_store.h"

#include "tests/server/daemon_fixture.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstring>
#include <random>

namespace gk::server {
namespace {

template <typename T>
bool same_bits(const T& l, const T& r) {
  return std::memcmp(&l, &r, sizeof(T)) == 0;
}
bool same_bits(const Vec3& l, const Vec3& r) { return same_bits(l.x(), r.x()) && same_bits(l.y(), r.y()) && same_bits(l.z(), r.z()); }

void expect_identical(const PairClash& l, const PairClash& r) {
  EXPECT_EQ(l.a, r.a);
  EXPECT_EQ(l.b, r.b);
  EXPECT_EQ(l.verdict, r.verdict);
  EXPECT_EQ(l.inconclusive_reason, r.inconclusive_reason);
  EXPECT_TRUE(same_bits(l.distance_mm, r.distance_mm));
  EXPECT_EQ(l.clearance_violation, r.clearance_violation);
  EXPECT_TRUE(same_bits(l.point_a, r.point_a));
  EXPECT_TRUE(same_bits(l.point_b, r.point_b));
  ASSERT_EQ(l.regions.size(), r.regions.size());
  for (std::size_t i = 0; i < l.regions.size(); ++i) {
    EXPECT_TRUE(same_bits(l.regions[i].min_distance_mm, r.regions[i].min_distance_mm));
    EXPECT_TRUE(same_bits(l.regions[i].point_a, r.regions[i].point_a));
    EXPECT_TRUE(same_bits(l.regions[i].point_b, r.regions[i].point_b));
    EXPECT_EQ(l.regions[i].triangle_pairs, r.regions[i].triangle_pairs);
    EXPECT_TRUE(same_bits(l.regions[i].bounds.min, r.regions[i].bounds.min));
    EXPECT_TRUE(same_bits(l.regions[i].bounds.max, r.regions[i].bounds.max));
    EXPECT_EQ(l.regions[i].faces_a, r.regions[i].faces_a);
    EXPECT_EQ(l.regions[i].faces_b, r.regions[i].faces_b);
  }
  EXPECT_EQ(l.contacts, r.contacts);
  EXPECT_EQ(l.contacts_truncated, r.contacts_truncated);
  EXPECT_TRUE(same_bits(l.depth_mm, r.depth_mm));
  ASSERT_EQ(l.depth_direction.has_value(), r.depth_direction.has_value());
  if (l.depth_direction) {
    EXPECT_TRUE(same_bits(l.depth_direction->vector(), r.depth_direction->vector()));
  }
  EXPECT_TRUE(same_bits(l.volume_mm3, r.volume_mm3));
  EXPECT_TRUE(same_bits(l.volume_error_bound_mm3, r.volume_error_bound_mm3));
  EXPECT_EQ(l.error, r.error);
}

std::vector<PairClash> random_clashes(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-3.0e4, 3.0e4);
  auto v = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  std::vector<PairClash> out;
  for (int i = 0; i < n; ++i) {
    PairClash c;
    c.a = static_cast<std::uint32_t>(rng() % 1000);
    c.b = c.a + 1 + static_cast<std::uint32_t>(rng() % 1000);
    c.verdict = static_cast<Verdict>(rng() % 4);
    c.inconclusive_reason = static_cast<InconclusiveReason>(rng() % 5);
    c.distance_mm = std::fabs(u(rng)) * 1e-7;
    c.clearance_violation = rng() % 2;
    c.point_a = v();
    c.point_b = v();
    for (int k = 0; k < static_cast<int>(rng() % 4); ++k) {
      engine::ContactPlace p;
      p.min_distance_mm = std::fabs(u(rng));
      p.point_a = v();
      p.point_b = v();
      p.triangle_pairs = static_cast<std::uint32_t>(rng());
      if (k != 1) p.bounds = Aabb{p.point_a, p.point_a + Vec3(1e-9, 3.0, 7.0)};  // k == 1: the empty box (infinities)
      for (int f = 0; f < k; ++f) p.faces_a.push_back(static_cast<int>(rng() % 50) + 1);
      p.faces_b = {k + 1};
      c.regions.push_back(p);
    }
    c.contacts = static_cast<unsigned>(rng());
    c.contacts_truncated = rng() % 2;
    c.depth_mm = i % 3 ? u(rng) : -1.0;
    if (i % 3) c.depth_direction = Direction::of(v());
    c.volume_mm3 = u(rng);
    c.volume_error_bound_mm3 = std::fabs(u(rng)) * 1e-3;
    if (i % 5 == 0) c.error = "pair " + std::to_string(i) + " failed: \xce\xbb";
    out.push_back(c);
  }
  return out;
}

TEST(AuditCheckpointStore, ATilesClashesComeBackBitForBit) {
  std::mt19937_64 rng(3);
  for (int n : {0, 1, 40}) {
    const std::vector<PairClash> clashes = random_clashes(rng, n);
    auto back = decode_tile(encode_tile(clashes));
    ASSERT_TRUE(back.ok()) << back.error().to_string();
    ASSERT_EQ(back.value().size(), clashes.size());
    for (std::size_t i = 0; i < clashes.size(); ++i) expect_identical(clashes[i], back.value()[i]);
  }
  EXPECT_FALSE(decode_tile("\xff\xff\xff not a tile").ok());
  EXPECT_FALSE(decode_tile("").ok());  // an empty tile is not zero bytes
  const std::string some = encode_tile(random_clashes(rng, 5));
  for (std::size_t cut = 0; cut < some.size(); cut += 7) {
    auto cut_short = decode_tile(some.substr(0, cut));
    EXPECT_TRUE(!cut_short.ok() || cut_short.value().size() == 5) << "cut at " << cut;
  }
}

TEST(AuditCheckpointStore, JobsComeBackWithTheirSnapshotOptionsAndTilesUntilForgotten) {
  const std::string dir = testing::temp_dir("checkpoint-store");
  std::mt19937_64 rng(5);
  const auto tile3 = random_clashes(rng, 7), tile9 = random_clashes(rng, 2);
  SceneRecord scene;
  scene.id = "scene-1";
  scene.name = "hall";
  engine::SceneObjectRecord o;
  o.id = "obj-1";
  o.name = "press";
  o.category = "machine";
  o.part_id = "part-1";
  o.pose.translation = Vec3(25000.125, -3.5, 0.0);
  scene.objects[o.id] = o;
  AuditOptions options;
  options.clearance_mm = 2.5;
  options.tile_mm = 12000.0;
  options.threads = 3;
  options.compute_depth = true;
  options.region_merge_mm = 77.0;
  options.max_contacts_per_pair = 123;
  options.rules = {{"bolted", "frame", "*", true}};
  {
    auto store = AuditCheckpointStore::open(dir).value();
    ASSERT_TRUE(store->begin("audit-1", scene, options, "").ok());
    ASSERT_TRUE(store->begin("audit-2", scene, AuditOptions{}, "audit-0").ok());
    ASSERT_TRUE(store->tile_done("audit-1", 9, tile9).ok());
    ASSERT_TRUE(store->tile_done("audit-1", 3, tile3).ok());
    ASSERT_TRUE(store->tile_done("audit-1", 4, {}).ok());
  }
  auto store = AuditCheckpointStore::open(dir).value();  // as a restarted daemon reads it
  auto unfinished = store->unfinished();
  ASSERT_TRUE(unfinished.ok());
  ASSERT_EQ(unfinished.value().size(), 2u);
  const engine::UnfinishedAudit& first = unfinished.value()[0];
  EXPECT_EQ(first.job_id, "audit-1");
  EXPECT_EQ(first.scene.name, "hall");
  ASSERT_EQ(first.scene.objects.count("obj-1"), 1u);
  EXPECT_EQ(first.scene.objects.at("obj-1").pose.translation, o.pose.translation);
  EXPECT_EQ(first.options.clearance_mm, 2.5);
  EXPECT_EQ(first.options.tile_mm, 12000.0);
  EXPECT_EQ(first.options.threads, 3);
  EXPECT_TRUE(first.options.compute_depth);
  EXPECT_EQ(first.options.region_merge_mm, 77.0);
  EXPECT_EQ(first.options.max_contacts_per_pair, 123u);
  ASSERT_EQ(first.options.rules.size(), 1u);
  EXPECT_TRUE(first.options.rules[0].same_group_only);
  ASSERT_EQ(first.tiles.size(), 3u);
  ASSERT_EQ(first.tiles.at(3).size(), tile3.size());
  for (std::size_t i = 0; i < tile3.size(); ++i) expect_identical(tile3[i], first.tiles.at(3)[i]);
  EXPECT_TRUE(first.tiles.at(4).empty());
  EXPECT_EQ(unfinished.value()[1].baseline_job_id, "audit-0");
  EXPECT_FALSE(first.cancelled);
  ASSERT_TRUE(store->cancelled("audit-2").ok());
  ASSERT_TRUE(store->forget("audit-1").ok());
  ASSERT_EQ(store->unfinished().value().size(), 1u);
  EXPECT_TRUE(store->unfinished().value()[0].cancelled);

  // Damage: a tile of audit-2 cut to nothing, a third job's record garbage, a row without an id.
  ASSERT_TRUE(store->tile_done("audit-2", 5, tile3).ok());
  ASSERT_TRUE(store->tile_done("audit-2", 6, tile9).ok());
  ASSERT_TRUE(store->begin("audit-3", scene, options, "").ok());
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir + "/gatekeeper.sqlite").c_str(), &db), SQLITE_OK);
  for (const char* damage : {"UPDATE audit_tiles SET data = x'' WHERE job_id = 'audit-2' AND tile = 5",
                             "UPDATE running_audits SET data = x'ffffffff' WHERE id = 'audit-3'",
                             "INSERT INTO running_audits (id, begun, data) VALUES (NULL, 1, x'00')"})
    ASSERT_EQ(sqlite3_exec(db, damage, nullptr, nullptr, nullptr), SQLITE_OK) << damage;
  sqlite3_close(db);
  auto damaged = store->unfinished();
  ASSERT_TRUE(damaged.ok());
  ASSERT_EQ(damaged.value().size(), 2u);
  const engine::UnfinishedAudit& second = damaged.value()[0];
  EXPECT_EQ(second.job_id, "audit-2");
  EXPECT_TRUE(second.unreadable.empty());
  EXPECT_EQ(second.tiles.count(5), 0u);  // left out: computed again
  ASSERT_EQ(second.tiles.count(6), 1u);
  EXPECT_EQ(second.tiles.at(6).size(), tile9.size());
  EXPECT_EQ(damaged.value()[1].job_id, "audit-3");
  EXPECT_FALSE(damaged.value()[1].unreadable.empty());
}

}  // namespace
}  // namespace gk::server
