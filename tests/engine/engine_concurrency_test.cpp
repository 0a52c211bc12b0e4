// The server's shared structures under concurrent use, in process. ThreadSanitizer cannot look
// through Debian's gRPC (it is not instrumented: a TSan build of the daemon reports thousands of
// races inside gRPC's own call machinery), so this suite is what scripts/test.sh runs under TSan
// for the server and a drag session's second thread; in the Release suite it checks that every
// answer is still right.
#include "engine/machines/machine_registry.h"
#include "engine/scenes/layout_session.h"
#include "engine/parts/part_registry.h"
#include "engine/parts/part_store.h"
#include "engine/steps/step_answers.h"
#include "engine/work_pool.h"
#include "tests/support/file_text.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <optional>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>
#include <vector>

namespace gk::engine {
namespace {

std::string temp_dir(const std::string& tag) {
  const auto dir = std::filesystem::temp_directory_path() / ("gk-concurrency-" + tag + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// A flat grid of n x n squares (2 n^2 triangles) as OBJ text: parts of different sizes.
std::string grid_obj(int n) {
  std::string obj;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  auto at = [&](int i, int j) { return std::to_string(j * (n + 1) + i + 1); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      obj += "f " + at(i, j) + " " + at(i + 1, j) + " " + at(i + 1, j + 1) + "\n";
      obj += "f " + at(i, j) + " " + at(i + 1, j + 1) + " " + at(i, j + 1) + "\n";
    }
  return obj;
}

TEST(EngineConcurrency, PartLoadsRacingEvictionEachAnswerTheirOwnPart) {
  const std::string dir = temp_dir("parts");
  auto store = PartStore::open(dir).value();
  // About two of the four parts fit: loads keep evicting each other.
  PartRegistry registry(*store, dir + "/bvh-cache", 2 * 2 * 20 * 20 * PartRegistry::kBytesPerTriangle);
  std::map<std::string, std::uint32_t> triangles;
  for (int n : {10, 20, 30, 40}) {
    const std::string bytes = grid_obj(n);
    auto upload = store->begin("grid" + std::to_string(n), "obj", bytes.size(), testing::sha256_hex(bytes)).value();
    ASSERT_TRUE(upload->append(bytes).ok());
    auto record = store->finish(std::move(upload), [](const std::string& path, PartRecord r) -> Result<PartRecord> {
      auto mesh = PartRegistry::read_any(path, "obj", 0.05);
      if (!mesh.ok()) return mesh.error();
      r.triangles = static_cast<std::uint32_t>(mesh.value().triangle_count());
      return r;
    });
    ASSERT_TRUE(record.ok()) << record.error().to_string();
    triangles[record.value().id] = static_cast<std::uint32_t>(2 * n * n);
  }
  std::vector<std::string> ids;
  for (const auto& [id, count] : triangles) ids.push_back(id);
  std::atomic<int> wrong{0}, failed{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 150; ++i) {
        const std::string& id = ids[static_cast<std::size_t>(t * 7 + i) % ids.size()];
        auto part = registry.load(id, 0.05);
        if (!part.ok()) {
          ++failed;
          continue;
        }
        if (part.value()->mesh->triangle_count() != triangles[id] || part.value()->bvh->mesh().triangle_count() != triangles[id])
          ++wrong;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(failed.load(), 0);
  EXPECT_EQ(wrong.load(), 0);
  const auto memory = registry.memory_stats();
  EXPECT_GT(memory.evicted, 0u);
  EXPECT_TRUE(memory.parts == 1 || memory.bytes <= 2 * 2 * 20 * 20 * PartRegistry::kBytesPerTriangle) << memory.parts << " " << memory.bytes;
  std::filesystem::remove_all(dir);
}

TEST(EngineConcurrency, AWorkPoolRunsEveryAcceptedJobOnceEvenWhileStopping) {
  WorkPool pool(3, 50);
  std::atomic<int> accepted{0}, ran{0};
  std::vector<std::thread> submitters;
  for (int t = 0; t < 4; ++t)
    submitters.emplace_back([&] {
      for (int i = 0; i < 2000; ++i)
        if (pool.try_submit([&] { ++ran; })) ++accepted;
    });
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    pool.stop();
  });
  for (auto& t : submitters) t.join();
  stopper.join();
  pool.stop();
  EXPECT_EQ(ran.load(), accepted.load());
  EXPECT_FALSE(pool.try_submit([] {})) << "a stopped pool accepts nothing";
}

// A part store, its registry and the machines (the embedded default), in a temporary directory.
struct StepStores {
  explicit StepStores(const std::string& tag)
      : store(PartStore::open(temp_dir(tag)).value()), parts(*store, temp_dir(tag + "-bvh")),
        machines(MachineRegistry::create().value()) {}
  std::unique_ptr<PartStore> store;
  PartRegistry parts;
  std::unique_ptr<MachineRegistry> machines;
};

// The one ValidateStep answer cache, shared by every thread, kept small so that writers clear it
// under the readers: every answer, from the cache or validated, equals the one computed alone.
TEST(EngineConcurrency, StepAnswersFromManyThreadsEqualTheAnswersComputedAlone) {
  StepStores stores("steps");
  PartRegistry& parts = stores.parts;
  MachineRegistry& machine_registry = *stores.machines;
  std::vector<StepQuestion> questions;
  for (int i = 0; i < 12; ++i) {
    StepQuestion q;
    q.part.spec = {1000.0, 800.0, 1.5, {}, {}};
    q.step.kind = i % 2 == 0 ? p4::StepKind::kBendUp : p4::StepKind::kBendDown;
    q.step.bend_point_mm = Vec2(0.0, 650.0 + 10.0 * i);
    q.step.bend_direction = Vec2(1.0, 0.0);
    q.step.target_angle_deg = 30.0 + 10.0 * i;
    q.with_corrections = false;
    questions.push_back(q);
  }
  std::vector<p4::StepAnswer> alone;
  {
    StepAnswers fresh(machine_registry, parts);
    for (const StepQuestion& q : questions) {
      auto a = fresh.validate(q);
      ASSERT_TRUE(a.ok()) << a.error().to_string();
      alone.push_back(a.value().answer);
    }
  }
  StepAnswers shared(machine_registry, parts, 4);
  std::atomic<int> wrong{0}, cached{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < 60; ++i) {
        const std::size_t k = static_cast<std::size_t>(i * 5 + t) % questions.size();
        std::optional<StepReply> reply;
        if (t % 2 == 1) reply = shared.cached(questions[k]);
        if (reply) ++cached;
        else if (auto v = shared.validate(questions[k]); v.ok()) reply = v.value();
        if (!reply || reply->answer.verdict != alone[k].verdict || reply->answer.collisions.size() != alone[k].collisions.size() ||
            reply->answer.min_clearance_mm != alone[k].min_clearance_mm)
          ++wrong;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(wrong.load(), 0);
  // How often a reader found its answer depends on the threads' timing (the writers keep clearing
  // the cache): recorded, not asserted. That a cached answer is found at all is tested below.
  RecordProperty("answered_from_cache", cached.load());
}

// A question differing from a cached one in a single bit of one field is not answered from the
// cache (the key is the question's bytes, not a hash).
TEST(EngineConcurrency, AQuestionOneBitAwayIsNotAnsweredFromTheCache) {
  StepStores stores("bit");
  PartRegistry& parts = stores.parts;
  MachineRegistry& machine_registry = *stores.machines;
  StepAnswers answers(machine_registry, parts);
  StepQuestion q;
  q.part.spec = {1000.0, 800.0, 1.5, {}, {}};
  q.step.kind = p4::StepKind::kBendUp;
  q.step.bend_point_mm = Vec2(0.0, 700.0);
  q.step.target_angle_deg = 90.0;
  ASSERT_TRUE(answers.validate(q).ok());
  ASSERT_TRUE(answers.cached(q).has_value());
  StepQuestion other = q;
  other.step.target_angle_deg = std::nextafter(90.0, 91.0);
  EXPECT_FALSE(answers.cached(other).has_value());
  other = q;
  other.part.spec.thickness_mm = std::nextafter(1.5, 2.0);
  EXPECT_FALSE(answers.cached(other).has_value());
  other = q;
  other.state = p4::MachineState{};
  other.state->engaged_segments.assign(machine_registry.get("").value().model.aba.segment_widths_mm.size(), true);
  other.state->engaged_segments[0] = false;
  EXPECT_FALSE(answers.cached(other).has_value());
  other = q;
  other.with_corrections = !q.with_corrections;
  EXPECT_FALSE(answers.cached(other).has_value());
}

// A question without a state of its own is asked in the machine's current state while another
// thread keeps changing it: every cached answer must be the one for the state it is filed under.
// (The state was once read twice, for the key and for the validator: a change between the reads
// filed a CLEAR under a state in which the step collides.)
TEST(EngineConcurrency, AnswersFiledUnderTheCurrentStateAreThatStatesWhileItChanges) {
  StepStores stores("state-race");
  MachineRegistry& machines = *stores.machines;
  const std::size_t segments = machines.get("").value().model.aba.segment_widths_mm.size();
  p4::MachineState clear_state, colliding_state;
  clear_state.engaged_segments.assign(segments, true);
  clear_state.clamp_z_mm = 1.0;
  clear_state.manipulator_y_mm = -400.0;
  colliding_state = clear_state;
  colliding_state.manipulator_y_mm = -300.0;  // the manipulator 100 mm nearer the bend line
  StepQuestion q;
  q.part.spec = {1000.0, 600.0, 1.0, {}, {}};
  q.step.kind = p4::StepKind::kBendUp;
  q.step.bend_point_mm = Vec2(0.0, 450.0);  // a 150 mm flange
  q.step.bend_direction = Vec2(1.0, 0.0);
  q.step.target_angle_deg = 90.0;
  q.with_corrections = false;
  // The oracle: each state asked explicitly, alone.
  std::map<int, Verdict> truth;
  {
    StepAnswers alone(machines, stores.parts);
    for (int k = 0; k < 2; ++k) {
      StepQuestion explicit_q = q;
      explicit_q.state = k == 0 ? clear_state : colliding_state;
      truth[k] = alone.validate(explicit_q).value().answer.verdict;
    }
  }
  ASSERT_NE(truth[0], truth[1]) << "the two states must answer differently for this test to mean anything";
  StepAnswers shared(machines, stores.parts, 1);  // one answer kept: most asks validate
  std::atomic<bool> done{false};
  std::thread toggler([&] {
    for (int i = 0; !done; ++i) ASSERT_TRUE(machines.set_state("", i % 2 == 0 ? clear_state : colliding_state).ok());
  });
  int wrong = 0;
  for (int i = 0; i < 5000; ++i) {
    auto reply = shared.validate(q);
    ASSERT_TRUE(reply.ok());
    // Whatever state it was asked in, the answer now filed under each state must be that state's.
    for (int k = 0; k < 2 && i % 50 == 0; ++k) {
      StepQuestion explicit_state = q;
      explicit_state.state = k == 0 ? clear_state : colliding_state;
      if (auto hit = shared.cached(explicit_state); hit && hit->answer.verdict != truth[k]) ++wrong;
    }
  }
  done = true;
  toggler.join();
  for (int k = 0; k < 2; ++k) {
    ASSERT_TRUE(machines.set_state("", k == 0 ? clear_state : colliding_state).ok());
    if (auto hit = shared.cached(q); hit && hit->answer.verdict != truth[k]) ++wrong;
  }
  EXPECT_EQ(wrong, 0);
}

}  // namespace
}  // namespace gk::engine

namespace gk::engine {
namespace {

// A drag session's frames use its second thread (engine/scenes/second_hand.h): with two pairs
// left for the exact verdict each thread takes one; with one, its distance query is finished on
// both (kernel/core/spare_thread.h). Every frame's contacts must equal the verdicts assessed one
// by one on this thread (under ThreadSanitizer in scripts/test.sh's thread stage).
TEST(EngineConcurrency, AFramesExactChecksOnTwoThreadsEqualThemAssessedAlone) {
  testing::Rng rng(606);
  const auto blob = MeshBvh::build(testing::share(testing::random_closed_blob(rng, 5, 60.0, 0.6, Vec3::Zero()))).value();
  ASSERT_GE(blob->mesh().triangle_count(), 4096u);  // slabs and a frontier large enough to be dealt out
  std::vector<AuditObject> objects;
  objects.push_back({"left", "blob", "", blob, RigidTransform::from_translation(Vec3(-140, 0, 0)), 0.0, std::nullopt});
  objects.push_back({"right", "blob", "", blob, RigidTransform::from_translation(Vec3(140, 0, 0)), 0.0, std::nullopt});
  objects.push_back({"moving", "blob", "", blob, RigidTransform::from_translation(Vec3(0, 300, 0)), 0.0, std::nullopt});
  const double clearance = 30.0;
  auto session = LayoutSession::create(objects, 2, clearance);
  ASSERT_TRUE(session.ok());
  int two_pairs = 0, one_pair = 0;
  for (int f = 0; f < 120; ++f) {
    // Down between the two, swinging: near both, then near one, then into them.
    const RigidTransform pose = RigidTransform::from_axis_angle(Vec3(0.2, 0.1, 1.0), 0.01 * f,
                                                                Vec3(60.0 * std::sin(0.1 * f), 300.0 - 2.5 * f, 0.0));
    auto frame = session.value()->move_to(pose);
    ASSERT_TRUE(frame.ok()) << frame.error().to_string();
    std::map<std::uint32_t, Verdict> got;
    for (const FrameContact& c : frame.value().contacts) got[c.other] = c.verdict;
    std::map<std::uint32_t, Verdict> alone;
    for (std::uint32_t k = 0; k < 2; ++k) {
      VerdictOptions options;
      options.distance_upper_bound_mm = clearance;
      const VerdictResult v = assess(*blob, pose, *blob, objects[k].pose, options).value();
      if (v.verdict != Verdict::kClear || v.distance_mm < clearance) alone[k] = v.verdict;
      if (v.verdict == Verdict::kClear && v.distance_mm < clearance) {
        for (const FrameContact& c : frame.value().contacts)
          if (c.other == k) {
            EXPECT_EQ(c.distance_mm, v.distance_mm) << "frame " << f;
          }
      }
    }
    EXPECT_EQ(got, alone) << "frame " << f;
    two_pairs += frame.value().exact_checks >= 2 ? 1 : 0;
    one_pair += frame.value().exact_checks == 1 ? 1 : 0;
  }
  EXPECT_GT(two_pairs, 5);
  EXPECT_GT(one_pair, 5);
}

}  // namespace
}  // namespace gk::engine
