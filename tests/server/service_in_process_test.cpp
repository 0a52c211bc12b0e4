// The service without a socket: GatekeeperService over a real engine (stores in a temporary
// directory), served on gRPC's in-process channel. Every RPC is called here with inputs whose
// answers are known independently (closed-form distances and contact angles, counts); the same
// service is also tested through the real daemon on loopback (gatekeeperd_e2e_tests).
#include "engine/gatekeeper_engine.h"
#include "server/audit_archive.h"
#include "server/audit_report.h"
#include "server/gatekeeper_service.h"
#include "tests/server/daemon_fixture.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace gk::server {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::bend_request;

// Stores, engine and service in process; the stub talks to it through an in-process channel.
class InProcessService {
 public:
  explicit InProcessService(const std::string& tag) : dir_(testing::temp_dir("inproc-" + tag)) {
    store_ = engine::PartStore::open(dir_).value();
    parts_ = std::make_unique<engine::PartRegistry>(*store_, dir_ + "/bvh-cache");
    machines_ = engine::MachineRegistry::create(dir_ + "/machines").value();
    scenes_ = engine::SceneStore::open(dir_).value();
    archive_ = AuditArchive::open(dir_).value();
    engine_ = std::make_unique<engine::Engine>(*machines_, *parts_, *scenes_, archive_.get());
    service_ = std::make_unique<GatekeeperService>(*engine_, ServiceOptions{});
    grpc::ServerBuilder builder;
    builder.RegisterService(service_.get());
    server_ = builder.BuildAndStart();
    stub_ = pb::Gatekeeper::NewStub(server_->InProcessChannel(grpc::ChannelArguments()));
  }
  ~InProcessService() {
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
    service_->stop_work();
  }
  pb::Gatekeeper::Stub& stub() { return *stub_; }

 private:
  std::string dir_;
  std::unique_ptr<engine::PartStore> store_;
  std::unique_ptr<engine::PartRegistry> parts_;
  std::unique_ptr<engine::MachineRegistry> machines_;
  std::unique_ptr<engine::SceneStore> scenes_;
  std::unique_ptr<AuditArchive> archive_;
  std::unique_ptr<engine::Engine> engine_;
  std::unique_ptr<GatekeeperService> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<pb::Gatekeeper::Stub> stub_;
};

std::unique_ptr<grpc::ClientContext> context() {
  auto ctx = std::make_unique<grpc::ClientContext>();
  ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  return ctx;
}


pb::Pose at(double x, double y, double z) {
  pb::Pose p;
  p.mutable_translation()->set_x_mm(x);
  p.mutable_translation()->set_y_mm(y);
  p.mutable_translation()->set_z_mm(z);
  return p;
}

TEST(ServiceInProcess, ValidateStepAndValidateStepsAnswerTheBeamAtItsClosedFormAngle) {
  InProcessService s("validate");
  pb::ValidateStepResponse low, tall, again;
  ASSERT_TRUE(s.stub().ValidateStep(context().get(), bend_request(150.0, 90.0), &low).ok());
  EXPECT_EQ(low.verdict(), pb::CLEAR);
  ASSERT_TRUE(s.stub().ValidateStep(context().get(), bend_request(300.0, 90.0), &tall).ok());
  ASSERT_EQ(tall.verdict(), pb::COLLISION);
  ASSERT_GT(tall.collisions_size(), 0);
  // A 300 mm flange turning up meets the beam's underside 203 mm above the table (0.1 mm clearance).
  EXPECT_NEAR(tall.collisions(0).first_contact_deg(), std::asin((203.0 - 0.1) / 300.0) * 180.0 / kPi, 0.01);
  ASSERT_TRUE(s.stub().ValidateStep(context().get(), bend_request(300.0, 90.0), &again).ok());
  EXPECT_EQ(again.decided_by(), "cache");
  EXPECT_EQ(again.deciding_stage(), pb::DECIDING_STAGE_CACHE);
  EXPECT_NE(tall.deciding_stage(), pb::DECIDING_STAGE_UNSPECIFIED);
  EXPECT_EQ(again.verdict(), pb::COLLISION);
  pb::ValidateStepsRequest batch;
  *batch.add_steps() = bend_request(100.0, 90.0);
  *batch.add_steps() = bend_request(300.0, 90.0);
  *batch.add_steps() = bend_request(120.0, 90.0);
  batch.set_stop_at_first_failure(true);
  pb::ValidateStepsResponse steps;
  ASSERT_TRUE(s.stub().ValidateSteps(context().get(), batch, &steps).ok());
  EXPECT_EQ(steps.first_failure(), 1);
  EXPECT_EQ(steps.results_size(), 2);
  pb::ValidateStepResponse bad;
  const grpc::Status refused = s.stub().ValidateStep(context().get(), bend_request(100.0, std::nan("")), &bad);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("target_angle_deg"), std::string::npos) << refused.error_message();
}

TEST(ServiceInProcess, UploadPartGetPartInfoAndClearanceQueryAgreeWithTheBoxesDistance) {
  InProcessService s("clearance");
  const std::string box = testing::box_obj(0, 0, 0, 100, 100, 100);
  pb::PartInfo info;
  ASSERT_TRUE(testing::upload_part(s.stub(), box, "obj", &info).ok());
  EXPECT_EQ(info.triangles(), 12u);
  pb::GetPartInfoRequest get;
  get.set_part_id(info.part_id());
  pb::PartInfo again;
  ASSERT_TRUE(s.stub().GetPartInfo(context().get(), get, &again).ok());
  EXPECT_EQ(again.part_id(), info.part_id());
  EXPECT_TRUE(again.closed());
  // Two unit-100 cubes 3 mm apart along x and 4 mm along y (edges parallel): 5 mm, exactly.
  pb::ClearanceQueryRequest q;
  q.mutable_a()->set_part_id(info.part_id());
  *q.mutable_a()->mutable_pose() = at(50000.0, 0.0, 0.0);
  q.mutable_b()->set_part_id(info.part_id());
  *q.mutable_b()->mutable_pose() = at(50103.0, 104.0, 0.0);
  q.set_safety_gap_mm(10.0);
  pb::ClearanceQueryResponse apart;
  ASSERT_TRUE(s.stub().ClearanceQuery(context().get(), q, &apart).ok());
  EXPECT_EQ(apart.verdict(), pb::CLEAR);
  EXPECT_NEAR(apart.distance_mm(), 5.0, 1e-9);
  EXPECT_TRUE(apart.gap_violated());
  EXPECT_EQ(apart.depth_method_kind(), pb::DEPTH_METHOD_UNSPECIFIED);
  EXPECT_GT(apart.regions_size(), 0);
  // Overlapping by 2 mm in x: COLLISION, the depth along -x is 2 mm and the shared volume 2*100*100.
  *q.mutable_b()->mutable_pose() = at(50098.0, 0.0, 0.0);
  q.set_compute_depth(true);
  q.mutable_depth_along()->set_x_mm(1.0);
  q.set_compute_volume(true);
  pb::ClearanceQueryResponse crossing;
  ASSERT_TRUE(s.stub().ClearanceQuery(context().get(), q, &crossing).ok());
  EXPECT_EQ(crossing.verdict(), pb::COLLISION);
  EXPECT_NEAR(crossing.depth_mm(), 2.0, 1e-3);
  EXPECT_EQ(crossing.depth_method_kind(), pb::DEPTH_METHOD_ALONG_REQUESTED);
  EXPECT_TRUE(crossing.volume_method_kind() == pb::VOLUME_METHOD_MESH_RAY_CAST ||
              crossing.volume_method_kind() == pb::VOLUME_METHOD_MESH_EXACT_COREFINEMENT)
      << crossing.volume_method();
  EXPECT_LE(std::abs(crossing.interference_volume_mm3() - 20000.0), crossing.volume_error_bound_mm3() + 1e-6);
  // A bad field is named.
  q.set_safety_gap_mm(-1.0);
  pb::ClearanceQueryResponse refused_answer;
  const grpc::Status refused = s.stub().ClearanceQuery(context().get(), q, &refused_answer);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("safety_gap_mm"), std::string::npos);
}

TEST(ServiceInProcess, MachinesAreListedReadStateSetAndModelsPut) {
  InProcessService s("machines");
  pb::ListMachinesResponse list;
  ASSERT_TRUE(s.stub().ListMachines(context().get(), pb::ListMachinesRequest(), &list).ok());
  ASSERT_EQ(list.machines_size(), 1);
  EXPECT_EQ(list.machines(0).machine_id(), "p4-default");
  const pb::MachineInfo& m = list.machines(0);
  pb::GetMachineRequest get;
  get.set_machine_id("p4-default");
  pb::MachineInfo info;
  ASSERT_TRUE(s.stub().GetMachine(context().get(), get, &info).ok());
  EXPECT_EQ(info.aba_segments(), m.aba_segments());
  // One segment disengaged: the state reads back as set.
  pb::SetMachineStateRequest set;
  set.set_machine_id("p4-default");
  for (std::uint32_t i = 0; i < info.aba_segments(); ++i) set.mutable_state()->add_engaged_segments(i != 3);
  set.mutable_state()->set_clamp_z_mm(1.5);
  set.mutable_state()->set_manipulator_y_mm(-400.0);
  pb::MachineInfo after;
  ASSERT_TRUE(s.stub().SetMachineState(context().get(), set, &after).ok());
  ASSERT_EQ(after.state().engaged_segments_size(), static_cast<int>(info.aba_segments()));
  EXPECT_FALSE(after.state().engaged_segments(3));
  // A state with the wrong number of segments is refused, naming the field.
  set.mutable_state()->add_engaged_segments(true);
  pb::MachineInfo refused_info;
  const grpc::Status refused = s.stub().SetMachineState(context().get(), set, &refused_info);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("state."), std::string::npos) << refused.error_message();
  // The default model stored again under another id: a second machine, with the same segments.
  pb::PutMachineModelRequest put;
  put.set_machine_id("p4-copy");
  put.set_model_toml(info.model_toml());
  pb::MachineInfo copy;
  ASSERT_TRUE(s.stub().PutMachineModel(context().get(), put, &copy).ok());
  EXPECT_EQ(copy.aba_segments(), info.aba_segments());
  put.set_machine_id("bad id with spaces");
  const grpc::Status bad_id = s.stub().PutMachineModel(context().get(), put, &copy);
  EXPECT_EQ(bad_id.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad_id.error_message().find("machine_id"), std::string::npos);
}

TEST(ServiceInProcess, SceneObjectsArePutMovedDraggedDeletedAndRead) {
  InProcessService s("scenes");
  pb::PartInfo info;
  ASSERT_TRUE(testing::upload_part(s.stub(), testing::box_obj(0, 0, 0, 100, 100, 100), "obj", &info).ok());
  pb::CreateSceneRequest create;
  create.set_name("cell 7");
  pb::SceneInfo scene;
  ASSERT_TRUE(s.stub().CreateScene(context().get(), create, &scene).ok());
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  for (int i = 0; i < 3; ++i) {
    pb::SceneObject* o = batch.add_objects();
    o->set_object_id("box-" + std::to_string(i));
    o->set_part_id(info.part_id());
    *o->mutable_pose() = at(1000.0 * i, 0.0, 0.0);
  }
  pb::PutObjectsResponse stored;
  ASSERT_TRUE(s.stub().PutObjects(context().get(), batch, &stored).ok());
  EXPECT_EQ(stored.object_ids_size(), 3);
  // A fourth, 0.5 mm beside box-1: CLEAR within the 2 mm clearance, at exactly 0.5 mm.
  pb::PutObjectRequest put;
  put.set_scene_id(scene.scene_id());
  put.mutable_object()->set_object_id("box-new");
  put.mutable_object()->set_part_id(info.part_id());
  *put.mutable_object()->mutable_pose() = at(1100.5, 0.0, 0.0);
  put.set_clearance_mm(2.0);
  pb::MoveResult placed;
  ASSERT_TRUE(s.stub().PutObject(context().get(), put, &placed).ok());
  ASSERT_EQ(placed.contacts_size(), 1);
  EXPECT_EQ(placed.contacts(0).other_object_id(), "box-1");
  EXPECT_NEAR(placed.contacts(0).distance_mm(), 0.5, 1e-9);
  // Moved 10 mm into box-2: COLLISION with box-2 only.
  pb::MoveObjectRequest move;
  move.set_scene_id(scene.scene_id());
  move.set_object_id("box-new");
  *move.mutable_pose() = at(1910.0, 0.0, 0.0);
  pb::MoveResult moved;
  ASSERT_TRUE(s.stub().MoveObject(context().get(), move, &moved).ok());
  EXPECT_EQ(moved.verdict(), pb::COLLISION);
  ASSERT_EQ(moved.contacts_size(), 1);
  EXPECT_EQ(moved.contacts(0).other_object_id(), "box-2");
  // Dragged out along x in three frames: colliding, touching (face on face, side faces flush), then clear.
  auto ctx = context();
  auto drag = s.stub().DragObject(ctx.get());
  const pb::Verdict expected[] = {pb::COLLISION, pb::TOUCHING, pb::CLEAR};
  const double xs[] = {1950.0, 2100.0, 2150.0};
  for (int i = 0; i < 3; ++i) {
    pb::MoveObjectRequest frame = move;
    *frame.mutable_pose() = at(xs[i], 0.0, 0.0);
    ASSERT_TRUE(drag->Write(frame));
    pb::MoveResult answer;
    ASSERT_TRUE(drag->Read(&answer));
    EXPECT_EQ(answer.verdict(), expected[i]) << "frame " << i;
  }
  drag->WritesDone();
  EXPECT_TRUE(drag->Finish().ok());
  pb::DeleteObjectRequest del;
  del.set_scene_id(scene.scene_id());
  del.set_object_id("box-0");
  pb::SceneInfo after_delete;
  ASSERT_TRUE(s.stub().DeleteObject(context().get(), del, &after_delete).ok());
  EXPECT_EQ(after_delete.objects_size(), 3);
  pb::GetSceneRequest get;
  get.set_scene_id(scene.scene_id());
  pb::SceneInfo read;
  ASSERT_TRUE(s.stub().GetScene(context().get(), get, &read).ok());
  EXPECT_EQ(read.objects_size(), 3);
  EXPECT_EQ(read.name(), "cell 7");
  // One id twice in a batch, a clearance beyond 1e7 mm: refused, naming the field.
  pb::PutObjectsRequest twice = batch;
  twice.mutable_objects(1)->set_object_id("box-0");
  grpc::Status refused_twice = s.stub().PutObjects(context().get(), twice, &stored);
  EXPECT_EQ(refused_twice.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused_twice.error_message().find("objects[1].object_id"), std::string::npos) << refused_twice.error_message();
  pb::MoveObjectRequest far = move;
  far.set_clearance_mm(1e300);
  const grpc::Status refused_far = s.stub().MoveObject(context().get(), far, &moved);
  EXPECT_EQ(refused_far.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused_far.error_message().find("clearance_mm"), std::string::npos) << refused_far.error_message();
  // A clearance side naming both a part and a scene object is ambiguous: refused.
  pb::ClearanceQueryRequest both;
  both.mutable_a()->set_part_id(info.part_id());
  both.mutable_a()->set_scene_id(scene.scene_id());
  both.mutable_a()->set_object_id("box-1");
  both.mutable_b()->set_part_id(info.part_id());
  pb::ClearanceQueryResponse unanswered;
  const grpc::Status refused_both = s.stub().ClearanceQuery(context().get(), both, &unanswered);
  EXPECT_EQ(refused_both.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused_both.error_message().find("a.part_id"), std::string::npos) << refused_both.error_message();
  // A label with a NUL is refused, naming the field, and nothing is stored.
  pb::PutObjectsRequest bad = batch;
  bad.mutable_objects(1)->set_name(std::string("a\0b", 3));
  const grpc::Status refused = s.stub().PutObjects(context().get(), bad, &stored);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("objects[1].name"), std::string::npos) << refused.error_message();
}

TEST(ServiceInProcess, AnAuditIsStartedWatchedReportedAndCancelled) {
  InProcessService s("audit");
  pb::PartInfo info;
  ASSERT_TRUE(testing::upload_part(s.stub(), testing::box_obj(0, 0, 0, 100, 100, 100), "obj", &info).ok());
  pb::CreateSceneRequest create;
  pb::SceneInfo scene;
  ASSERT_TRUE(s.stub().CreateScene(context().get(), create, &scene).ok());
  // Ten boxes in a row 90 mm apart (each overlaps the next by 10 mm): 9 colliding pairs, no other.
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  for (int i = 0; i < 10; ++i) {
    pb::SceneObject* o = batch.add_objects();
    o->set_part_id(info.part_id());
    o->set_category(i % 2 == 0 ? "robot" : "fence");
    *o->mutable_pose() = at(90.0 * i, 0.0, 0.0);
  }
  pb::PutObjectsResponse stored;
  ASSERT_TRUE(s.stub().PutObjects(context().get(), batch, &stored).ok());
  pb::StartAuditRequest start;
  start.set_scene_id(scene.scene_id());
  const pb::AuditReport report = testing::run_audit(s.stub(), start, /*html=*/true);
  EXPECT_EQ(report.progress().state(), pb::DONE);
  ASSERT_EQ(report.clashes_size(), 9);
  for (const pb::Clash& c : report.clashes()) EXPECT_EQ(c.verdict(), pb::COLLISION);
  ASSERT_EQ(report.by_category_size(), 1);
  EXPECT_EQ(report.by_category(0).key(), "fence / robot");
  EXPECT_EQ(report.by_category(0).clashes(), 9u);
  EXPECT_NE(report.html().find("<html"), std::string::npos);
  // Read in pages of 4: 4, 4 and 1 clashes, in the report's order; tokens of another job or past
  // the end, and pages beyond the limit, are refused naming the field.
  pb::GetAuditReportRequest paged;
  paged.set_job_id(report.progress().job_id());
  paged.set_page_size(4);
  std::vector<std::string> order;
  int pages = 0;
  for (;;) {
    pb::AuditReport page;
    ASSERT_TRUE(s.stub().GetAuditReport(context().get(), paged, &page).ok());
    ++pages;
    EXPECT_EQ(page.clashes_total(), 9u);
    EXPECT_EQ(page.by_category_size(), 1);
    for (const pb::Clash& c : page.clashes()) order.push_back(c.object_a() + "/" + c.object_b());
    if (page.next_page_token().empty()) break;
    paged.set_page_token(page.next_page_token());
  }
  EXPECT_EQ(pages, 3);
  ASSERT_EQ(order.size(), 9u);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(order[i], report.clashes(i).object_a() + "/" + report.clashes(i).object_b());
  for (const std::string& token : {std::string("audit-other@4"), report.progress().job_id() + "@10", std::string("4")}) {
    paged.set_page_token(token);
    pb::AuditReport refused_page;
    const grpc::Status bad = s.stub().GetAuditReport(context().get(), paged, &refused_page);
    EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << token;
    EXPECT_NE(bad.error_message().find("page_token"), std::string::npos) << bad.error_message();
  }
  paged.clear_page_token();
  paged.set_page_size(100001);
  pb::AuditReport too_large;
  EXPECT_EQ(s.stub().GetAuditReport(context().get(), paged, &too_large).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // Cancelling an ended job leaves it as it ended.
  pb::CancelAuditRequest cancel;
  cancel.set_job_id(report.progress().job_id());
  pb::AuditProgress progress;
  ASSERT_TRUE(s.stub().CancelAudit(context().get(), cancel, &progress).ok());
  EXPECT_EQ(progress.state(), pb::DONE);
  // A re-audit against it with another clearance is refused, naming the option.
  start.set_baseline_job_id(report.progress().job_id());
  start.set_clearance_mm(5.0);
  pb::AuditJob job;
  const grpc::Status refused = s.stub().StartAudit(context().get(), start, &job);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(refused.error_message().find("clearance"), std::string::npos) << refused.error_message();
  pb::WatchAuditRequest watch;
  watch.set_job_id("audit-unknown");
  auto watch_ctx = context();
  auto reader = s.stub().WatchAudit(watch_ctx.get(), watch);
  pb::AuditProgress nothing;
  EXPECT_FALSE(reader->Read(&nothing));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::NOT_FOUND);
}

// The 0.2 additions: directions as Direction (unit, beside the older Vec3), one region message
// for clearance queries and audits, and enum values with their enum's prefix.
TEST(ServiceInProcess, DirectionsAndRegionsComeInTheirOwnMessagesBesideTheOlderFields) {
  InProcessService s("directions");
  static_assert(pb::VERDICT_COLLISION == pb::COLLISION && pb::AUDIT_STATE_DONE == pb::DONE, "aliases share values");
  pb::PartInfo info;
  ASSERT_TRUE(testing::upload_part(s.stub(), testing::box_obj(0, 0, 0, 100, 100, 100), "obj", &info).ok());
  // B overlaps A by 2 mm in x and 3 mm in y: freed by 2 mm along +x (the smallest move).
  pb::ClearanceQueryRequest q;
  q.mutable_a()->set_part_id(info.part_id());
  *q.mutable_a()->mutable_pose() = at(0.0, 0.0, 0.0);
  q.mutable_b()->set_part_id(info.part_id());
  *q.mutable_b()->mutable_pose() = at(98.0, 97.0, 0.0);
  q.set_compute_depth(true);
  pb::ClearanceQueryResponse free;
  ASSERT_TRUE(s.stub().ClearanceQuery(context().get(), q, &free).ok());
  ASSERT_EQ(free.verdict(), pb::VERDICT_COLLISION);
  ASSERT_TRUE(free.has_depth_axis());
  const pb::Direction& axis = free.depth_axis();
  EXPECT_NEAR(std::sqrt(axis.x() * axis.x() + axis.y() * axis.y() + axis.z() * axis.z()), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(axis.x(), free.depth_direction().x_mm());
  EXPECT_DOUBLE_EQ(axis.y(), free.depth_direction().y_mm());
  EXPECT_NEAR(free.depth_mm(), 2.0, 1e-3);
  // Along a requested direction, given as a Direction not of unit length: normalised, the same
  // answer as the older Vec3 field.
  q.mutable_depth_along_direction()->set_y(5.0);
  pb::ClearanceQueryResponse along_y;
  ASSERT_TRUE(s.stub().ClearanceQuery(context().get(), q, &along_y).ok());
  EXPECT_NEAR(along_y.depth_mm(), 3.0, 1e-3);
  EXPECT_EQ(along_y.depth_method_kind(), pb::DEPTH_METHOD_ALONG_REQUESTED);
  EXPECT_NEAR(along_y.depth_axis().y(), 1.0, 1e-12);
  q.mutable_depth_along()->set_y_mm(1.0);  // both: refused, naming the new field
  pb::ClearanceQueryResponse refused_answer;
  grpc::Status refused = s.stub().ClearanceQuery(context().get(), q, &refused_answer);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("depth_along_direction"), std::string::npos) << refused.error_message();
  q.clear_depth_along();
  q.mutable_depth_along_direction()->set_y(0.0);
  refused = s.stub().ClearanceQuery(context().get(), q, &refused_answer);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("depth_along_direction"), std::string::npos) << refused.error_message();

  // An audit of the same two boxes: its clash's regions in the ContactRegion message, the same
  // places as the older ClashRegion list, and its depth direction as a Direction.
  pb::SceneInfo scene;
  ASSERT_TRUE(s.stub().CreateScene(context().get(), pb::CreateSceneRequest(), &scene).ok());
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  for (const pb::Pose& pose : {at(0.0, 0.0, 0.0), at(98.0, 97.0, 0.0)}) {
    pb::SceneObject* o = batch.add_objects();
    o->set_part_id(info.part_id());
    *o->mutable_pose() = pose;
  }
  pb::PutObjectsResponse stored;
  ASSERT_TRUE(s.stub().PutObjects(context().get(), batch, &stored).ok());
  pb::StartAuditRequest start;
  start.set_scene_id(scene.scene_id());
  start.set_compute_depth(true);
  const pb::AuditReport report = testing::run_audit(s.stub(), start);
  ASSERT_EQ(report.clashes_size(), 1);
  const pb::Clash& clash = report.clashes(0);
  EXPECT_EQ(clash.verdict(), pb::VERDICT_COLLISION);
  ASSERT_GT(clash.contact_regions_size(), 0);
  ASSERT_EQ(clash.contact_regions_size(), clash.regions_size());
  for (int r = 0; r < clash.regions_size(); ++r) {
    const pb::ContactRegion& place = clash.contact_regions(r);
    EXPECT_EQ(place.triangle_pairs(), clash.regions(r).contact_pairs());
    EXPECT_DOUBLE_EQ(place.point_a().x_mm(), clash.regions(r).point().x_mm());
    // Every witness lies in the 2 x 3 x 100 mm overlap of the boxes (within rounding).
    for (const pb::Vec3& p : {place.point_a(), place.point_b()}) {
      EXPECT_GE(p.x_mm(), 98.0 - 1e-9);
      EXPECT_LE(p.x_mm(), 100.0 + 1e-9);
      EXPECT_GE(p.y_mm(), 97.0 - 1e-9);
      EXPECT_LE(p.y_mm(), 100.0 + 1e-9);
    }
  }
  ASSERT_TRUE(clash.has_depth_axis());
  EXPECT_DOUBLE_EQ(clash.depth_axis().x(), clash.depth_direction().x_mm());
}

// An audit archived before 0.2 holds its regions only as ClashRegion: read back, each becomes a
// contact place (its point on both sides), and a report written again carries both messages.
TEST(ServiceInProcess, AnArchivedReportOfTheOlderRegionMessageReadsBackAsContactPlaces) {
  pb::AuditReport old;
  pb::Clash* clash = old.add_clashes();
  clash->set_object_a("a");
  clash->set_object_b("b");
  clash->set_verdict(pb::COLLISION);
  pb::ClashRegion* region = clash->add_regions();
  region->mutable_point()->set_x_mm(7.0);
  region->set_contact_pairs(12);
  region->set_min_distance_mm(0.0);
  region->mutable_bounds_max()->set_x_mm(9.0);
  const AuditSnapshot snapshot = snapshot_from_report(old);
  ASSERT_EQ(snapshot.clashes.size(), 1u);
  ASSERT_EQ(snapshot.clashes[0].clash.regions.size(), 1u);
  const engine::ContactPlace& place = snapshot.clashes[0].clash.regions[0];
  EXPECT_EQ(place.triangle_pairs, 12u);
  EXPECT_EQ(place.point_a.x(), 7.0);
  EXPECT_EQ(place.point_b.x(), 7.0);
  EXPECT_EQ(place.bounds.max.x(), 9.0);
  pb::AuditReport again;
  report_to_proto(snapshot, "scene", &again);
  ASSERT_EQ(again.clashes(0).contact_regions_size(), 1);
  ASSERT_EQ(again.clashes(0).regions_size(), 1);
  EXPECT_EQ(again.clashes(0).contact_regions(0).triangle_pairs(), 12u);
  EXPECT_EQ(again.clashes(0).regions(0).point().x_mm(), 7.0);
}

TEST(ServiceInProcess, GetServerInfoCountsTheCallsItServed) {
  InProcessService s("info");
  pb::ListMachinesResponse list;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(s.stub().ListMachines(context().get(), pb::ListMachinesRequest(), &list).ok());
  pb::ServerInfo info;
  ASSERT_TRUE(s.stub().GetServerInfo(context().get(), pb::GetServerInfoRequest(), &info).ok());
  EXPECT_EQ(info.machines_size(), 1);
  EXPECT_EQ(info.parts_stored(), 0u);
  bool found = false;
  for (const pb::RpcStats& r : info.rpcs())
    if (r.method() == "ListMachines") {
      found = true;
      EXPECT_EQ(r.calls(), 3u);
      EXPECT_EQ(r.errors(), 0u);
    }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace gk::server
