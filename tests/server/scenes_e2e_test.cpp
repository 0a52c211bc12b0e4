// End to end on the real daemon: scenes (put, move, drag stream, delete, persistence), audits as
// jobs (watch, report against an in-process brute-force answer, cancel), and machine model upload.
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <cmath>
#include <set>
#include <thread>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

std::string upload_file(pb::Gatekeeper::Stub& stub, const std::string& relative, const std::string& format) {
  return testing::upload_part_id(stub, testing::read_file(testing::shared_data(relative)), format);
}

pb::Pose at_x(double x) {
  pb::Pose p;
  p.mutable_translation()->set_x_mm(x);
  return p;
}

pb::MoveResult put(pb::Gatekeeper::Stub& stub, const std::string& scene, const std::string& part, const std::string& name,
                   double x, std::string* id) {
  grpc::ClientContext ctx;
  pb::PutObjectRequest req;
  req.set_scene_id(scene);
  req.mutable_object()->set_part_id(part);
  req.mutable_object()->set_name(name);
  req.mutable_object()->set_category("robot");
  *req.mutable_object()->mutable_pose() = at_x(x);
  req.set_clearance_mm(10.0);
  pb::MoveResult result;
  EXPECT_TRUE(stub.PutObject(&ctx, req, &result).ok());
  *id = result.object_id();
  return result;
}

TEST(ScenesE2E, PutMoveDragDeleteAndTheSceneSurvivesARestart) {
  const std::string dir = testing::temp_dir("scenes");
  std::string scene_id, a, b;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    const std::string rob = upload_file(*stub, "meshes/fcl/rob.obj", "obj");  // 1000 x 1210 x 850 mm
    grpc::ClientContext cctx;
    pb::CreateSceneRequest create;
    create.set_name("cell 1");
    pb::SceneInfo scene;
    ASSERT_TRUE(stub->CreateScene(&cctx, create, &scene).ok());
    scene_id = scene.scene_id();
    EXPECT_EQ(put(*stub, scene_id, rob, "left", 0.0, &a).verdict(), pb::CLEAR);
    const pb::MoveResult far = put(*stub, scene_id, rob, "right", 3000.0, &b);
    EXPECT_EQ(far.verdict(), pb::CLEAR);
    EXPECT_EQ(far.contacts_size(), 0);
    // Moved into the other robot: a collision naming it.
    grpc::ClientContext mctx;
    pb::MoveObjectRequest move;
    move.set_scene_id(scene_id);
    move.set_object_id(b);
    *move.mutable_pose() = at_x(400.0);
    pb::MoveResult hit;
    ASSERT_TRUE(stub->MoveObject(&mctx, move, &hit).ok());
    EXPECT_EQ(hit.verdict(), pb::COLLISION);
    ASSERT_EQ(hit.contacts_size(), 1);
    EXPECT_EQ(hit.contacts(0).other_object_id(), a);
    // Dragging back out: every move is answered, in order.
    grpc::ClientContext dctx;
    auto drag = stub->DragObject(&dctx);
    std::vector<pb::Verdict> verdicts;
    for (double x : {600.0, 900.0, 1500.0, 2500.0}) {
      *move.mutable_pose() = at_x(x);
      ASSERT_TRUE(drag->Write(move));
      pb::MoveResult r;
      ASSERT_TRUE(drag->Read(&r));
      verdicts.push_back(r.verdict());
    }
    drag->WritesDone();
    EXPECT_TRUE(drag->Finish().ok());
    EXPECT_EQ(verdicts.front(), pb::COLLISION);
    EXPECT_EQ(verdicts.back(), pb::CLEAR);
    // Bad input: unknown object, NaN pose.
    grpc::ClientContext bctx;
    move.set_object_id("nope");
    pb::MoveResult ignored;
    EXPECT_EQ(stub->MoveObject(&bctx, move, &ignored).error_code(), grpc::StatusCode::NOT_FOUND);
    grpc::ClientContext nctx;
    move.set_object_id(b);
    move.mutable_pose()->mutable_translation()->set_y_mm(std::nan(""));
    const grpc::Status nan = stub->MoveObject(&nctx, move, &ignored);
    EXPECT_EQ(nan.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(nan.error_message().find("pose.translation"), std::string::npos);
    EXPECT_EQ(daemon.stop(SIGKILL), -SIGKILL);  // nothing acknowledged may be lost
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  grpc::ClientContext gctx;
  pb::GetSceneRequest get;
  get.set_scene_id(scene_id);
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->GetScene(&gctx, get, &scene).ok());
  ASSERT_EQ(scene.objects_size(), 2);
  bool found_b = false;
  for (const auto& o : scene.objects()) {
    if (o.object_id() == b) {
      found_b = true;
      EXPECT_DOUBLE_EQ(o.pose().translation().x_mm(), 2500.0);
    }
  }
  EXPECT_TRUE(found_b);
  grpc::ClientContext xctx;
  pb::DeleteObjectRequest del;
  del.set_scene_id(scene_id);
  del.set_object_id(a);
  ASSERT_TRUE(stub->DeleteObject(&xctx, del, &scene).ok());
  EXPECT_EQ(scene.objects_size(), 1);
}

// A drag's frames are logged rather than synced one by one: every frame answered must still be
// stored when the daemon is killed in the middle of the drag (the stream never ended, so the end's
// sync never ran), and a drag that ends is answered OK after its sync.
TEST(ScenesE2E, ADragsAnsweredFramesSurviveAKillInTheMiddleOfTheDrag) {
  const std::string dir = testing::temp_dir("drag-kill");
  std::string scene_id, a, b;
  const int frames = 300;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    const std::string box = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 100, 100, 100), "obj");
    grpc::ClientContext cctx;
    pb::CreateSceneRequest create;
    create.set_name("drag");
    pb::SceneInfo scene;
    ASSERT_TRUE(stub->CreateScene(&cctx, create, &scene).ok());
    scene_id = scene.scene_id();
    put(*stub, scene_id, box, "still", 0.0, &a);
    put(*stub, scene_id, box, "dragged", 5000.0, &b);
    pb::MoveObjectRequest move;
    move.set_scene_id(scene_id);
    move.set_object_id(b);
    {  // a finished drag: OK once synced
      grpc::ClientContext dctx;
      auto drag = stub->DragObject(&dctx);
      for (int i = 0; i < 20; ++i) {
        *move.mutable_pose() = at_x(4000.0 + i);
        ASSERT_TRUE(drag->Write(move));
        pb::MoveResult r;
        ASSERT_TRUE(drag->Read(&r));
      }
      drag->WritesDone();
      EXPECT_TRUE(drag->Finish().ok());
    }
    grpc::ClientContext dctx;
    auto drag = stub->DragObject(&dctx);
    for (int i = 0; i < frames; ++i) {
      const double x = 3000.0 - 10.0 * i;  // into the still box (x in [0, 100]) at the end
      *move.mutable_pose() = at_x(x);
      ASSERT_TRUE(drag->Write(move));
      pb::MoveResult r;
      ASSERT_TRUE(drag->Read(&r));
      EXPECT_EQ(r.verdict(), x < 100.0 ? pb::COLLISION : x == 100.0 ? pb::TOUCHING : pb::CLEAR) << "frame " << i;
    }
    EXPECT_EQ(daemon.stop(SIGKILL), -SIGKILL);  // mid-drag: the stream is still open
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  const pb::SceneInfo scene = testing::get_scene(*stub, scene_id);
  bool found = false;
  for (const auto& o : scene.objects())
    if (o.object_id() == b) {
      found = true;
      EXPECT_DOUBLE_EQ(o.pose().translation().x_mm(), 3000.0 - 10.0 * (frames - 1));  // the last frame answered
    }
  EXPECT_TRUE(found);
}

// Drag frames are answered on gRPC's own threads when no other drag frame is (one at a time), on
// the scene workers otherwise: streams running at once must each get the answers for their own
// frames, in order, whichever way each frame went, and other calls are still served meanwhile.
// The oracle is the boxes' arithmetic: the 100 mm cube dragged along x overlaps its row's still
// cube at [0, 100] exactly when -100 < x < 100 (the steps never land on a touching position).
TEST(ScenesE2E, DragsRunningAtOnceAreEachAnsweredForTheirOwnFrames) {
  Daemon daemon(testing::temp_dir("drags-at-once"));
  auto stub = daemon.stub();
  const std::string box = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 100, 100, 100), "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  constexpr int kStreams = 4, kFrames = 220;
  std::vector<std::string> still(kStreams), dragged(kStreams);
  for (int k = 0; k < kStreams; ++k) {  // one row per stream, 1 m apart in y: rows never meet
    pb::Pose row = at_x(0.0);
    row.mutable_translation()->set_y_mm(1000.0 * k);
    for (auto [id, x] : {std::pair{&still[k], 0.0}, std::pair{&dragged[k], 5000.0}}) {
      grpc::ClientContext ctx;
      pb::PutObjectRequest req;
      req.set_scene_id(scene.scene_id());
      req.mutable_object()->set_part_id(box);
      *req.mutable_object()->mutable_pose() = row;
      req.mutable_object()->mutable_pose()->mutable_translation()->set_x_mm(x);
      pb::MoveResult r;
      ASSERT_TRUE(stub->PutObject(&ctx, req, &r).ok());
      *id = r.object_id();
    }
  }
  std::atomic<int> streams_left{kStreams};
  std::vector<std::string> failures(kStreams);
  std::vector<std::thread> drags;
  for (int k = 0; k < kStreams; ++k)
    drags.emplace_back([&, k] {
      grpc::ClientContext dctx;
      auto drag = stub->DragObject(&dctx);
      pb::MoveObjectRequest move;
      move.set_scene_id(scene.scene_id());
      move.set_object_id(dragged[k]);
      for (int i = 0; i < kFrames && failures[k].empty(); ++i) {
        const double x = 3000.0 - 17.0 * i;
        *move.mutable_pose() = at_x(x);
        move.mutable_pose()->mutable_translation()->set_y_mm(1000.0 * k);
        pb::MoveResult r;
        if (!drag->Write(move) || !drag->Read(&r)) {
          failures[k] = "stream ended at frame " + std::to_string(i);
          break;
        }
        const bool overlaps = x > -100.0 && x < 100.0;
        const bool right = r.verdict() == (overlaps ? pb::COLLISION : pb::CLEAR) && r.contacts_size() == (overlaps ? 1 : 0) &&
                           (!overlaps || r.contacts(0).other_object_id() == still[k]);
        if (!right) failures[k] = "frame " + std::to_string(i) + " at x " + std::to_string(x) + ": " + r.ShortDebugString();
      }
      drag->WritesDone();
      const grpc::Status end = drag->Finish();
      if (failures[k].empty() && !end.ok()) failures[k] = "Finish: " + end.error_message();
      --streams_left;
    });
  int reads = 0;
  while (streams_left > 0) {  // other calls are served while the drags run
    EXPECT_EQ(testing::get_scene(*stub, scene.scene_id()).objects_size(), 2 * kStreams);
    ++reads;
  }
  for (std::thread& t : drags) t.join();
  for (int k = 0; k < kStreams; ++k) EXPECT_EQ(failures[k], "") << "stream " << k;
  EXPECT_GT(reads, 0);
  // Each dragged cube was stored at its stream's last frame.
  const pb::SceneInfo after = testing::get_scene(*stub, scene.scene_id());
  for (const auto& o : after.objects()) {
    for (int k = 0; k < kStreams; ++k) {
      if (o.object_id() == dragged[k]) {
        EXPECT_DOUBLE_EQ(o.pose().translation().x_mm(), 3000.0 - 17.0 * (kFrames - 1));
      }
    }
  }
}

TEST(ScenesE2E, AuditJobsReportWhatBruteForceFindsAndCancelKeepsPartialResults) {
  Daemon daemon(testing::temp_dir("audit"));
  auto stub = daemon.stub();
  const std::string rob = upload_file(*stub, "meshes/fcl/rob.obj", "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  // Robots along X: the gaps decide which pairs clash.
  const std::vector<double> xs = {0.0, 700.0, 2000.0, 2990.0, 5000.0, 6005.0};
  std::vector<std::string> ids(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) put(*stub, scene.scene_id(), rob, "r" + std::to_string(i), xs[i], &ids[i]);
  // The answer in process: every pair with the kernel's verdict.
  auto mesh = mesh_io::read_mesh_file(testing::shared_data("meshes/fcl/rob.obj"), {{true}, true}).value();
  auto bvh = MeshBvh::build(testing::share(mesh)).value();
  std::set<std::pair<std::string, std::string>> expected;
  for (std::size_t i = 0; i < xs.size(); ++i)
    for (std::size_t j = i + 1; j < xs.size(); ++j) {
      const auto v = assess(*bvh, RigidTransform::from_translation(Vec3(xs[i], 0, 0)), *bvh,
                            RigidTransform::from_translation(Vec3(xs[j], 0, 0))).value();
      if (v.verdict != Verdict::kClear || v.distance_mm < 20.0) expected.insert(std::minmax(ids[i], ids[j]));
    }
  ASSERT_GE(expected.size(), 2u);
  // Clearance between two scene objects by id equals the kernel's answer at their poses.
  pb::ClearanceQueryRequest cq;
  cq.mutable_a()->set_scene_id(scene.scene_id());
  cq.mutable_a()->set_object_id(ids[2]);
  cq.mutable_b()->set_scene_id(scene.scene_id());
  cq.mutable_b()->set_object_id(ids[3]);
  pb::ClearanceQueryResponse cr;
  grpc::ClientContext qctx;
  ASSERT_TRUE(stub->ClearanceQuery(&qctx, cq, &cr).ok());
  EXPECT_NEAR(cr.distance_mm(), distance(*bvh, RigidTransform::from_translation(Vec3(xs[2], 0, 0)), *bvh,
                                         RigidTransform::from_translation(Vec3(xs[3], 0, 0))).value().distance_mm, 1e-9);
  pb::StartAuditRequest start;
  start.set_scene_id(scene.scene_id());
  start.set_clearance_mm(20.0);
  pb::AuditJob job;
  grpc::ClientContext sctx;
  ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
  // Watch it to the end.
  grpc::ClientContext wctx;
  pb::WatchAuditRequest watch;
  watch.set_job_id(job.job_id());
  auto reader = stub->WatchAudit(&wctx, watch);
  pb::AuditProgress progress, last;
  int updates = 0;
  while (reader->Read(&progress)) {
    last = progress;
    ++updates;
  }
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_GE(updates, 1);
  EXPECT_EQ(last.state(), pb::DONE);
  EXPECT_EQ(last.pairs_done(), last.pairs_total());
  grpc::ClientContext rctx;
  pb::GetAuditReportRequest get;
  get.set_job_id(job.job_id());
  pb::AuditReport report;
  ASSERT_TRUE(stub->GetAuditReport(&rctx, get, &report).ok());
  std::set<std::pair<std::string, std::string>> found;
  for (const pb::Clash& c : report.clashes()) found.insert(std::minmax(c.object_a(), c.object_b()));
  EXPECT_EQ(found, expected);
  // A big audit cancelled at once: whatever it did is kept and consistent.
  for (int i = 0; i < 30; ++i) {
    std::string id;
    put(*stub, scene.scene_id(), rob, "extra", 200.0 * i, &id);
  }
  grpc::ClientContext s2;
  ASSERT_TRUE(stub->StartAudit(&s2, start, &job).ok());
  grpc::ClientContext c2;
  pb::CancelAuditRequest cancel;
  cancel.set_job_id(job.job_id());
  ASSERT_TRUE(stub->CancelAudit(&c2, cancel, &progress).ok());
  for (int i = 0; i < 200; ++i) {
    grpc::ClientContext r2;
    get.set_job_id(job.job_id());
    ASSERT_TRUE(stub->GetAuditReport(&r2, get, &report).ok());
    if (report.progress().state() != pb::RUNNING) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_TRUE(report.progress().state() == pb::CANCELLED || report.progress().state() == pb::DONE);
  EXPECT_LE(report.progress().pairs_done(), report.progress().pairs_total());
  EXPECT_EQ(static_cast<std::uint64_t>(report.clashes_size()), report.progress().clashes());
  grpc::ClientContext u;
  get.set_job_id("audit-999");
  EXPECT_EQ(stub->GetAuditReport(&u, get, &report).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(ScenesE2E, AMachineModelFileCanBeAddedAndBadOnesAreRefused) {
  const std::string dir = testing::temp_dir("model");
  Daemon daemon(dir);
  auto stub = daemon.stub();
  grpc::ClientContext gctx;
  pb::GetMachineRequest get;
  pb::MachineInfo info;
  ASSERT_TRUE(stub->GetMachine(&gctx, get, &info).ok());
  pb::PutMachineModelRequest put;
  put.set_machine_id("p4-copy");
  put.set_model_toml(info.model_toml());
  grpc::ClientContext pctx;
  ASSERT_TRUE(stub->PutMachineModel(&pctx, put, &info).ok());
  EXPECT_EQ(info.machine_id(), "p4-copy");
  grpc::ClientContext lctx;
  pb::ListMachinesResponse list;
  ASSERT_TRUE(stub->ListMachines(&lctx, pb::ListMachinesRequest(), &list).ok());
  EXPECT_EQ(list.machines_size(), 2);
  pb::ValidateStepRequest step;
  step.set_machine_id("p4-copy");
  step.mutable_part()->set_width_mm(1000);
  step.mutable_part()->set_depth_mm(800);
  step.mutable_part()->set_thickness_mm(1.5);
  step.mutable_step()->set_kind(pb::BEND_UP);
  step.mutable_step()->mutable_bend_point()->set_y_mm(700);
  step.mutable_step()->mutable_bend_direction()->set_x_mm(1);
  step.mutable_step()->set_target_angle_deg(90);
  step.mutable_state()->set_clamp_z_mm(1.5);
  step.mutable_state()->set_manipulator_y_mm(-400);
  grpc::ClientContext vctx;
  pb::ValidateStepResponse answer;
  ASSERT_TRUE(stub->ValidateStep(&vctx, step, &answer).ok());
  EXPECT_EQ(answer.verdict(), pb::CLEAR);
  put.set_model_toml("[machine]\nname = 'broken'\n");
  grpc::ClientContext bctx;
  const grpc::Status bad = stub->PutMachineModel(&bctx, put, &info);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad.error_message().find("model_toml"), std::string::npos);
  put.set_machine_id("../escape");
  grpc::ClientContext ectx;
  EXPECT_EQ(stub->PutMachineModel(&ectx, put, &info).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // The stored model is still there after a kill -9.
  daemon.stop(SIGKILL);
  Daemon again(dir);
  grpc::ClientContext actx;
  pb::ListMachinesResponse after;
  ASSERT_TRUE(again.stub()->ListMachines(&actx, pb::ListMachinesRequest(), &after).ok());
  EXPECT_EQ(after.machines_size(), 2);
}

}  // namespace
}  // namespace gk
