// One object against its neighbours, the one path of every move (PutObject, MoveObject, drag
// frames: engine/scenes/drag_session), against an all-pairs oracle that involves no tree, grid,
// box or cache: every triangle pair of the moved object and each other object (tests/support's
// brute force). Scenes of non-convex blobs packed so that many pairs collide, touch or sit within
// the clearance; every object is moved, and a drag's frames (with the session's caches) must
// answer exactly what a fresh one-frame session answers at the same pose.
#include "engine/gatekeeper_engine.h"
#include "tests/support/brute_force.h"
#include "tests/support/file_text.h"
#include "tests/support/random_meshes.h"
#include "tests/support/sanitized_build.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <atomic>

namespace gk::engine {
namespace {

class Stores {
 public:
  explicit Stores(const std::string& tag)
      : dir_((std::filesystem::temp_directory_path() / ("gk-neighbours-" + tag + "-" + std::to_string(::getpid()))).string()) {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    store_ = PartStore::open(dir_).value();
    parts_ = std::make_unique<PartRegistry>(*store_, dir_ + "/bvh-cache");
    machines_ = MachineRegistry::create(dir_ + "/machines").value();
    scenes_ = SceneStore::open(dir_).value();
    engine_ = std::make_unique<Engine>(*machines_, *parts_, *scenes_, nullptr);
  }
  ~Stores() {
    engine_.reset();
    std::filesystem::remove_all(dir_);
  }
  Engine& engine() { return *engine_; }
  PartRegistry& parts() { return *parts_; }
  std::string upload(const TriangleMesh& mesh, const std::string& name) {
    const std::string bytes = testing::obj_text(mesh);
    auto upload = engine_->begin_upload(name, "obj", bytes.size(), testing::sha256_hex(bytes));
    EXPECT_TRUE(upload.ok()) << upload.error().to_string();
    EXPECT_TRUE(upload.value()->append(bytes).ok());
    auto record = engine_->finish_upload(std::move(upload).value());
    EXPECT_TRUE(record.ok()) << record.error().to_string();
    return record.value().id;
  }

 private:
  std::string dir_;
  std::unique_ptr<PartStore> store_;
  std::unique_ptr<PartRegistry> parts_;
  std::unique_ptr<MachineRegistry> machines_;
  std::unique_ptr<SceneStore> scenes_;
  std::unique_ptr<Engine> engine_;
};

struct Placed {
  std::string id;
  const TriangleMesh* mesh;
  StoredPose pose;
};

StoredPose random_stored_pose(std::mt19937_64& rng, double range) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  StoredPose p;
  p.translation = Vec3(u(rng), u(rng), u(rng)) * range;
  Vec3 axis(u(rng), u(rng), u(rng));
  if (axis.norm() < 1e-3) axis = Vec3::UnitZ();
  p.axis = axis.normalized();
  p.angle_deg = 180.0 * u(rng);
  return p;
}

// What the oracle says of one pair: the distance between the surfaces, and whether any two
// triangles meet (no nesting is possible among blobs of these sizes: a contact is a meeting).
struct OraclePair {
  double distance_mm;
  bool meet;
};

OraclePair oracle(const Placed& a, const Placed& b) {
  const RigidTransform pa = a.pose.transform(), pb = b.pose.transform();
  const bool meet = !testing::brute_force_contacts(*a.mesh, pa, *b.mesh, pb).empty();
  return {meet ? 0.0 : testing::brute_force_distance(*a.mesh, pa, *b.mesh, pb), meet};
}

// Checks one move's answer against the oracle over every other object.
void expect_matches_oracle(const MoveOutcome& got, const Placed& moved, const std::vector<Placed>& scene, double clearance_mm,
                           int* listed_total, int* colliding_total) {
  std::map<std::string, const ObjectContactResult*> listed;
  for (const ObjectContactResult& c : got.contacts) listed[c.other] = &c;
  Verdict worst = Verdict::kClear;
  for (const Placed& other : scene) {
    if (other.id == moved.id) continue;
    const OraclePair truth = oracle(moved, other);
    const auto it = listed.find(other.id);
    // A margin for the kernel's contact tolerance and rounding: pairs this close to the clearance
    // may go either way; beyond it the answer is fixed.
    const double margin = 1e-6;
    if (truth.meet) {
      ASSERT_NE(it, listed.end()) << moved.id << " meets " << other.id << " but the move does not list it";
      EXPECT_NE(it->second->verdict, Verdict::kClear) << moved.id << " meets " << other.id;
      ++*colliding_total;
    } else if (truth.distance_mm < clearance_mm - margin) {
      ASSERT_NE(it, listed.end()) << moved.id << " is " << truth.distance_mm << " mm from " << other.id
                                  << ", within the clearance " << clearance_mm << ", but not listed";
      if (it->second->verdict == Verdict::kClear) {
        EXPECT_NEAR(it->second->distance_mm, truth.distance_mm, 1e-9);
      }
    } else if (truth.distance_mm > std::max(clearance_mm, 0.0) + margin) {
      if (it != listed.end()) {
        EXPECT_EQ(it->second->verdict, Verdict::kClear) << moved.id << " is " << truth.distance_mm << " mm from " << other.id;
        EXPECT_NEAR(it->second->distance_mm, truth.distance_mm, 1e-9);
      }
      EXPECT_TRUE(it == listed.end() || truth.distance_mm <= clearance_mm + margin)
          << other.id << " at " << truth.distance_mm << " mm is listed beyond the clearance " << clearance_mm;
    }
    if (it != listed.end() && severity(it->second->verdict) > severity(worst)) worst = it->second->verdict;
  }
  EXPECT_EQ(got.verdict, worst);
  *listed_total += static_cast<int>(got.contacts.size());
}

TEST(ObjectNeighbours, EveryMoveListsExactlyTheNeighboursTheAllPairsOracleFinds) {
  Stores stores("oracle");
  Engine& engine = stores.engine();
  std::mt19937_64 rng(20261126);
  std::vector<TriangleMesh> meshes;
  testing::Rng mesh_rng(7);
  for (int i = 0; i < 4; ++i) meshes.push_back(testing::random_closed_blob(mesh_rng, 2, 20.0 + 4.0 * i, 0.25, Vec3::Zero()));
  std::vector<std::string> part_ids;
  for (std::size_t i = 0; i < meshes.size(); ++i) part_ids.push_back(stores.upload(meshes[i], "blob" + std::to_string(i)));

  int listed_total = 0, colliding_total = 0, moves = 0;
  const int scenes = 3;  // one per clearance
  for (int s = 0; s < scenes; ++s) {
    auto scene = engine.create_scene("packed").value();
    std::vector<SceneObjectRecord> objects;
    std::vector<Placed> placed;
    const int n = 24;
    for (int i = 0; i < n; ++i) {
      SceneObjectRecord o;
      o.id = "o" + std::to_string(i);
      const std::size_t m = static_cast<std::size_t>(rng() % meshes.size());
      o.part_id = part_ids[m];
      o.pose = random_stored_pose(rng, 90.0);
      objects.push_back(o);
      placed.push_back({o.id, &meshes[m], o.pose});
    }
    ASSERT_TRUE(engine.put_objects(scene.id, objects).ok());
    const double clearance = std::vector<double>{0.0, 1.5, 8.0}[static_cast<std::size_t>(s) % 3];
    for (int i = 0; i < n; ++i) {
      // A small move of each object, so that the stored scene is what the oracle sees.
      StoredPose pose = placed[static_cast<std::size_t>(i)].pose;
      pose.translation += Vec3(0.5, -0.25, 0.125);
      placed[static_cast<std::size_t>(i)].pose = pose;
      auto got = engine.move_object(scene.id, placed[static_cast<std::size_t>(i)].id, pose, clearance);
      ASSERT_TRUE(got.ok()) << got.error().to_string();
      expect_matches_oracle(got.value(), placed[static_cast<std::size_t>(i)], placed, clearance, &listed_total, &colliding_total);
      ++moves;
    }
  }
  std::printf("%d moves, %d neighbours listed, %d meeting\n", moves, listed_total, colliding_total);
  // The scenes are packed: the comparison covered contacts, not only empty answers.
  EXPECT_GT(colliding_total, moves / 2);
  EXPECT_GT(listed_total, colliding_total);
}

TEST(ObjectNeighbours, ADragsFramesAnswerWhatAFreshMoveAnswersAtTheSamePose) {
  Stores stores("drag");
  Engine& engine = stores.engine();
  testing::Rng mesh_rng(11);
  const TriangleMesh blob = testing::random_closed_blob(mesh_rng, 2, 25.0, 0.3, Vec3::Zero());
  const std::string part = stores.upload(blob, "blob");
  auto scene = engine.create_scene("row").value();
  std::vector<SceneObjectRecord> objects;
  std::vector<Placed> placed;
  for (int i = 0; i < 12; ++i) {
    SceneObjectRecord o;
    o.id = "o" + std::to_string(10 + i);
    o.part_id = part;
    o.pose.translation = Vec3(60.0 * i, 0.0, 0.0);
    objects.push_back(o);
    placed.push_back({o.id, &blob, o.pose});
  }
  SceneObjectRecord dragged;
  dragged.id = "dragged";
  dragged.part_id = part;
  dragged.pose.translation = Vec3(-100.0, 30.0, 0.0);
  objects.push_back(dragged);
  placed.push_back({dragged.id, &blob, dragged.pose});
  ASSERT_TRUE(engine.put_objects(scene.id, objects).ok());

  DragSession drag;
  int listed_total = 0, colliding_total = 0;
  const int frames = testing::samples(240);
  for (int f = 0; f < frames; ++f) {
    StoredPose pose;
    pose.translation = Vec3(-100.0 + 3.5 * f, 30.0 - 0.3 * f, 2.0 * std::sin(0.1 * f));
    pose.axis = Vec3(0.3, 0.2, 1.0).normalized();
    pose.angle_deg = 1.5 * f;
    placed.back().pose = pose;
    auto framed = engine.move_object(scene.id, "dragged", pose, 2.0, &drag);
    ASSERT_TRUE(framed.ok()) << framed.error().to_string();
    // The stored scene at this pose, answered by a fresh one-frame session (nothing stored: the
    // drag's session stays valid for its next frame).
    auto fresh = DragSession::once(engine.scene(scene.id).value(), "dragged", 2.0, stores.parts());
    ASSERT_TRUE(fresh.ok());
    ASSERT_EQ(framed.value().contacts.size(), fresh.value().contacts.size()) << "frame " << f;
    EXPECT_EQ(framed.value().verdict, fresh.value().verdict) << "frame " << f;
    for (std::size_t c = 0; c < fresh.value().contacts.size(); ++c) {
      EXPECT_EQ(framed.value().contacts[c].other, fresh.value().contacts[c].other);
      EXPECT_EQ(framed.value().contacts[c].verdict, fresh.value().contacts[c].verdict);
      if (fresh.value().contacts[c].verdict == Verdict::kClear) {
        EXPECT_DOUBLE_EQ(framed.value().contacts[c].distance_mm, fresh.value().contacts[c].distance_mm);
      }
    }
    if (f % 8 == 0) expect_matches_oracle(framed.value(), placed.back(), placed, 2.0, &listed_total, &colliding_total);
  }
  EXPECT_GT(colliding_total, 0);
}

// Two clients moving (or putting) the same object at once, one into a neighbour and one clear of
// it: each answer is for its own pose (an answer once described the other client's pose: a
// false CLEAR for the colliding move).
TEST(ObjectNeighbours, ConcurrentMovesOfOneObjectAreEachAnsweredForTheirOwnPose) {
  Stores stores("race");
  Engine& engine = stores.engine();
  const std::string big = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(100, 100, 100)), "big");
  const std::string small = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)), "small");
  auto scene = engine.create_scene("race").value();
  SceneObjectRecord wall, mover;
  wall.id = "wall";
  wall.part_id = big;
  mover.id = "mover";
  mover.part_id = small;
  mover.pose.translation = Vec3(500, 0, 0);
  ASSERT_TRUE(engine.put_objects(scene.id, {wall, mover}).ok());
  StoredPose inside, apart;
  inside.translation = Vec3(45, 45, 45);
  apart.translation = Vec3(500, 0, 0);
  std::atomic<int> wrong{0}, answered{0};
  const auto client = [&](const StoredPose& pose, Verdict expected, bool put) {
    for (int i = 0; i < testing::samples(400); ++i) {
      Result<MoveOutcome> got = Error{};
      if (put) {
        SceneObjectRecord again = mover;
        again.pose = pose;
        auto placed = engine.put_object(scene.id, again, 0.0);
        got = placed.ok() ? Result<MoveOutcome>(placed.value().outcome) : Result<MoveOutcome>(placed.error());
      } else {
        got = engine.move_object(scene.id, "mover", pose, 0.0);
      }
      if (!got.ok() || got.value().verdict != expected) ++wrong;
      ++answered;
    }
  };
  for (bool put : {false, true}) {
    std::thread a(client, inside, Verdict::kCollision, put), b(client, apart, Verdict::kClear, put);
    a.join();
    b.join();
  }
  EXPECT_EQ(wrong.load(), 0) << "of " << answered.load();
}

// Two clients moving (or putting) two different objects to the same place at once: at least
// one of them is told of the other (answering before storing once let both be told CLEAR and both
// be stored overlapping). A dense neighbour near the place makes each answer take a while, as a
// real one does.
TEST(ObjectNeighbours, TwoObjectsMovedTogetherToOnePlaceAreNeverBothToldClear) {
  Stores stores("together");
  Engine& engine = stores.engine();
  testing::Rng rng(3);
  const std::string dense = stores.upload(testing::random_closed_blob(rng, 5, 60.0, 0.05, Vec3::Zero()), "dense");
  const std::string box = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)), "box");
  auto scene = engine.create_scene("together").value();
  SceneObjectRecord neighbour, x, y;
  neighbour.id = "neighbour";
  neighbour.part_id = dense;
  neighbour.pose.translation = Vec3(-68.0, 5.0, 5.0);  // its surface a few mm from the place
  x.id = "x";
  x.part_id = box;
  x.pose.translation = Vec3(1000, 0, 0);
  y = x;
  y.id = "y";
  y.pose.translation = Vec3(-1000, 0, 0);
  ASSERT_TRUE(engine.put_objects(scene.id, {neighbour, x, y}).ok());
  StoredPose place;  // both go here
  int both_clear = 0;
  const int rounds = testing::samples(40);
  for (bool put : {false, true}) {
    for (int round = 0; round < rounds; ++round) {
      StoredPose away_x, away_y;
      away_x.translation = Vec3(1000, 0, 0);
      away_y.translation = Vec3(-1000, 0, 0);
      ASSERT_TRUE(engine.move_object(scene.id, "x", away_x, 0.0).ok());
      ASSERT_TRUE(engine.move_object(scene.id, "y", away_y, 0.0).ok());
      std::atomic<int> ready{0};
      Verdict vx = Verdict::kClear, vy = Verdict::kClear;
      const auto go = [&](const std::string& id, Verdict* verdict) {
        ++ready;
        while (ready.load() < 2) {
        }
        Result<MoveOutcome> got = Error{};
        if (put) {
          SceneObjectRecord o;
          o.id = id;
          o.part_id = box;
          o.pose = place;
          auto placed = engine.put_object(scene.id, o, 50.0);
          got = placed.ok() ? Result<MoveOutcome>(placed.value().outcome) : Result<MoveOutcome>(placed.error());
        } else {
          got = engine.move_object(scene.id, id, place, 50.0);
        }
        ASSERT_TRUE(got.ok());
        *verdict = Verdict::kClear;
        for (const ObjectContactResult& c : got.value().contacts)
          if (c.other == (id == "x" ? "y" : "x")) *verdict = c.verdict;
      };
      std::thread a(go, "x", &vx), b(go, "y", &vy);
      a.join();
      b.join();
      if (vx == Verdict::kClear && vy == Verdict::kClear) ++both_clear;
    }
  }
  EXPECT_EQ(both_clear, 0);
}

// The same race through two drag streams, each with its warm session: a drag frame is answered
// while its pose is being stored, and that early answer may only be kept when the store shows no
// other edit came between. Each round, both streams first drag their object along its own lane
// (so each session reflects the scene and answers ahead), then both drag it to the same place.
TEST(ObjectNeighbours, TwoObjectsDraggedTogetherToOnePlaceAreNeverBothToldClear) {
  Stores stores("drag-together");
  Engine& engine = stores.engine();
  testing::Rng rng(5);
  const std::string dense = stores.upload(testing::random_closed_blob(rng, 5, 60.0, 0.05, Vec3::Zero()), "dense");
  const std::string box = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)), "box");
  auto scene = engine.create_scene("drag-together").value();
  SceneObjectRecord neighbour, x, y;
  neighbour.id = "neighbour";
  neighbour.part_id = dense;
  neighbour.pose.translation = Vec3(-68.0, 5.0, 5.0);
  x.id = "x";
  x.part_id = box;
  x.pose.translation = Vec3(1000, 0, 0);
  y = x;
  y.id = "y";
  y.pose.translation = Vec3(-1000, 0, 0);
  ASSERT_TRUE(engine.put_objects(scene.id, {neighbour, x, y}).ok());
  DragSession drag_x, drag_y;
  int both_clear = 0, told = 0;
  const int rounds = testing::samples(60);
  for (int round = 0; round < rounds; ++round) {
    std::atomic<int> ready{0};
    Verdict vx = Verdict::kClear, vy = Verdict::kClear;
    const auto go = [&](const std::string& id, DragSession* drag, double lane, Verdict* verdict) {
      for (int f = 0; f < 4; ++f) {  // along its own lane, far from everything
        StoredPose away;
        away.translation = Vec3(lane, 300.0 + 20.0 * f, 0);
        ASSERT_TRUE(engine.move_object(scene.id, id, away, 50.0, drag).ok());
      }
      ++ready;
      while (ready.load() < 2) {
      }
      auto got = engine.move_object(scene.id, id, StoredPose{}, 50.0, drag);
      ASSERT_TRUE(got.ok()) << got.error().to_string();
      *verdict = Verdict::kClear;
      for (const ObjectContactResult& c : got.value().contacts)
        if (c.other == (id == "x" ? "y" : "x")) *verdict = c.verdict;
    };
    std::thread a(go, "x", &drag_x, 1000.0, &vx), b(go, "y", &drag_y, -1000.0, &vy);
    a.join();
    b.join();
    if (vx == Verdict::kClear && vy == Verdict::kClear) ++both_clear;
    if (vx != Verdict::kClear || vy != Verdict::kClear) ++told;
  }
  EXPECT_EQ(both_clear, 0);
  EXPECT_EQ(told, rounds);
}

// A move racing a put that replaces the same object's part: what is stored is what some answer
// described (a move's pose once landed on a part nobody had checked there).
TEST(ObjectNeighbours, AMoveRacingAPartReplacementLeavesAStateThatWasAnswered) {
  Stores stores("replace");
  Engine& engine = stores.engine();
  const std::string small = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)), "small");
  const std::string large = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(200, 200, 200)), "large");
  auto scene = engine.create_scene("replace").value();
  SceneObjectRecord wall, x;
  wall.id = "wall";
  wall.part_id = small;
  wall.pose.translation = Vec3(300, 0, 0);
  x.id = "x";
  x.part_id = small;
  x.pose.translation = Vec3(-5000, 0, 0);
  ASSERT_TRUE(engine.put_objects(scene.id, {wall, x}).ok());
  int unanswered = 0;
  for (int round = 0; round < testing::samples(60); ++round) {
    SceneObjectRecord reset = x;
    ASSERT_TRUE(engine.put_object(scene.id, reset, 0.0).ok());
    StoredPose near_wall;  // the small part is clear of the wall here, the large one is not
    near_wall.translation = Vec3(150, 0, 0);
    SceneObjectRecord replaced = x;  // the large part, far away
    replaced.part_id = large;
    std::atomic<int> ready{0};
    Verdict move_verdict = Verdict::kClear;
    std::thread mover([&] {
      ++ready;
      while (ready.load() < 2) {
      }
      auto got = engine.move_object(scene.id, "x", near_wall, 0.0);
      if (got.ok()) move_verdict = got.value().verdict;
    });
    std::thread putter([&] {
      ++ready;
      while (ready.load() < 2) {
      }
      (void)engine.put_object(scene.id, replaced, 0.0);
    });
    mover.join();
    putter.join();
    const SceneObjectRecord now = engine.scene(scene.id).value().objects.at("x");
    // The large part at the wall was answered only if the move's answer said COLLISION.
    if (now.part_id == large && now.pose.translation.x() == 150.0 && move_verdict == Verdict::kClear) ++unanswered;
  }
  EXPECT_EQ(unanswered, 0);
}

// A move or a put whose answer is stopped (a deadline, a cancel) stores nothing.
TEST(ObjectNeighbours, AMoveOrPutThatIsStoppedStoresNothing) {
  Stores stores("stopped");
  Engine& engine = stores.engine();
  const std::string box = stores.upload(testing::box_mesh(Vec3(0, 0, 0), Vec3(100, 100, 100)), "box");
  auto scene = engine.create_scene("stopped").value();
  SceneObjectRecord a, b;
  a.id = "a";
  a.part_id = box;
  b.id = "b";
  b.part_id = box;
  b.pose.translation = Vec3(50, 0, 0);  // overlapping a: an exact check is needed, where the stop is seen
  ASSERT_TRUE(engine.put_objects(scene.id, {a, b}).ok());
  const StopToken stopped([] { return true; });
  StoredPose elsewhere;
  elsewhere.translation = Vec3(60, 0, 0);
  auto moved = engine.move_object(scene.id, "b", elsewhere, 0.0, nullptr, stopped);
  ASSERT_FALSE(moved.ok());
  EXPECT_EQ(moved.error().code, ErrorCode::kStopped);
  EXPECT_EQ(engine.scene(scene.id).value().objects.at("b").pose.translation.x(), 50.0);
  SceneObjectRecord c = b;
  c.id = "c";
  auto put = engine.put_object(scene.id, c, 0.0, stopped);
  ASSERT_FALSE(put.ok());
  EXPECT_EQ(engine.scene(scene.id).value().objects.count("c"), 0u);
}

}  // namespace
}  // namespace gk::engine
