// End to end: the real gatekeeperd on a loopback port, real channels. Every RPC, the bad-input
// list, deadlines, overload, restarts (SIGTERM and kill -9) that keep acknowledged uploads, and
// many concurrent clients.
#include "grpc/health/v1/health.grpc.pb.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"
#include "occt_adapters/exact_measures.h"
#include "occt_adapters/shape_builders.h"
#include "occt_adapters/shape_import.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/random_meshes.h"
#include "kernel/core/units.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <cmath>
#include <thread>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;
using testing::bend_request;



grpc::Status call(pb::Gatekeeper::Stub& stub, const pb::ValidateStepRequest& r, pb::ValidateStepResponse* out) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  return stub.ValidateStep(&ctx, r, out);
}

double vec_x(const pb::Vec3& v) { return v.x_mm(); }

grpc::Status upload(pb::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format, pb::PartInfo* info,
                    const std::string& declared_sha = "", std::size_t chunk = 1u << 20) {
  return testing::upload_part(stub, bytes, format, info, declared_sha, chunk);
}

// One daemon per data directory: a second one started on it refuses, naming the directory,
// instead of resuming the first one's audits and writing its databases.
TEST(GatekeeperdE2E, ASecondDaemonOnTheSameDataDirectoryRefusesToStart) {
  const std::string dir = testing::temp_dir("one-daemon");
  Daemon first(dir);
  std::string out;
  FILE* pipe = popen(("timeout 30 " + std::string(GATEKEEPERD_PATH) + " --listen 127.0.0.1:0 --data-dir " + dir +
                      " 2>&1; echo \"exit=$?\"").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  pclose(pipe);
  EXPECT_NE(out.find("another gatekeeperd is using"), std::string::npos) << out;
  EXPECT_NE(out.find("exit=1"), std::string::npos) << out;
  // The first one still answers.
  grpc::ClientContext ctx;
  pb::ListMachinesResponse machines;
  EXPECT_TRUE(first.stub()->ListMachines(&ctx, pb::ListMachinesRequest(), &machines).ok());
}

TEST(GatekeeperdE2E, ValidateStepAnswersClearAndCollisionWithItsStageAndTimes) {
  Daemon daemon(testing::temp_dir("validate"));
  auto stub = daemon.stub();
  pb::ValidateStepResponse low, tall;
  ASSERT_TRUE(call(*stub, bend_request(150.0, 90.0), &low).ok());
  EXPECT_EQ(low.verdict(), pb::CLEAR);
  EXPECT_FALSE(low.decided_by().empty());
  EXPECT_GT(low.times().total_us(), 0.0);
  ASSERT_TRUE(call(*stub, bend_request(300.0, 90.0), &tall).ok());  // a collision is an OK reply
  ASSERT_EQ(tall.verdict(), pb::COLLISION);
  ASSERT_GT(tall.collisions_size(), 0);
  EXPECT_EQ(tall.collisions(0).organ(), "upper_beam");
  EXPECT_NEAR(tall.collisions(0).first_contact_deg(), std::asin((203.0 - 0.1) / 300.0) * 180.0 / kPi, 0.01);
  // The same question again comes from the memo.
  pb::ValidateStepResponse again;
  ASSERT_TRUE(call(*stub, bend_request(300.0, 90.0), &again).ok());
  EXPECT_EQ(again.decided_by(), "cache");
}

TEST(GatekeeperdE2E, ValidateStepsStopsAtTheFirstFailureWhenAsked) {
  Daemon daemon(testing::temp_dir("steps"));
  auto stub = daemon.stub();
  pb::ValidateStepsRequest req;
  *req.add_steps() = bend_request(100.0, 90.0);
  *req.add_steps() = bend_request(300.0, 90.0);
  *req.add_steps() = bend_request(120.0, 90.0);
  req.set_stop_at_first_failure(true);
  pb::ValidateStepsResponse resp;
  grpc::ClientContext ctx;
  ASSERT_TRUE(stub->ValidateSteps(&ctx, req, &resp).ok());
  EXPECT_EQ(resp.first_failure(), 1);
  EXPECT_EQ(resp.results_size(), 2);
  req.set_stop_at_first_failure(false);
  grpc::ClientContext ctx2;
  ASSERT_TRUE(stub->ValidateSteps(&ctx2, req, &resp).ok());
  EXPECT_EQ(resp.results_size(), 3);
}

TEST(GatekeeperdE2E, BadInputGetsInvalidArgumentOrNotFoundNamingTheField) {
  Daemon daemon(testing::temp_dir("bad"));
  auto stub = daemon.stub();
  pb::ValidateStepResponse out;
  struct Case {
    pb::ValidateStepRequest request;
    grpc::StatusCode code;
    std::string field;
  };
  std::vector<Case> cases;
  auto nan_angle = bend_request(100.0, std::nan(""));
  cases.push_back({nan_angle, grpc::StatusCode::INVALID_ARGUMENT, "target_angle_deg"});
  auto not_a_bend = bend_request(100.0, 190.0);
  cases.push_back({not_a_bend, grpc::StatusCode::INVALID_ARGUMENT, "step.target_angle_deg"});
  auto huge_travel = bend_request(100.0, 90.0);
  huge_travel.mutable_step()->set_kind(pb::APPROACH);
  huge_travel.mutable_step()->mutable_travel()->set_x_mm(1e308);
  cases.push_back({huge_travel, grpc::StatusCode::INVALID_ARGUMENT, "step.travel"});
  auto huge_part = bend_request(100.0, 90.0);
  huge_part.mutable_part()->set_width_mm(1e8);
  cases.push_back({huge_part, grpc::StatusCode::INVALID_ARGUMENT, "part.width_mm"});
  auto no_kind = bend_request(100.0, 90.0);
  no_kind.mutable_step()->set_kind(pb::STEP_KIND_UNSPECIFIED);
  cases.push_back({no_kind, grpc::StatusCode::INVALID_ARGUMENT, "step.kind"});
  auto zero_line = bend_request(100.0, 90.0);
  zero_line.mutable_step()->mutable_bend_direction()->set_x_mm(0.0);
  cases.push_back({zero_line, grpc::StatusCode::INVALID_ARGUMENT, "step.bend_direction"});
  auto bad_state = bend_request(100.0, 90.0);
  bad_state.mutable_state()->add_engaged_segments(true);
  cases.push_back({bad_state, grpc::StatusCode::INVALID_ARGUMENT, "state.engaged_segments"});
  auto bad_part = bend_request(100.0, 90.0);
  bad_part.mutable_part()->set_thickness_mm(-1.0);
  cases.push_back({bad_part, grpc::StatusCode::INVALID_ARGUMENT, "part.thickness_mm"});
  auto unknown_machine = bend_request(100.0, 90.0);
  unknown_machine.set_machine_id("p9");
  cases.push_back({unknown_machine, grpc::StatusCode::NOT_FOUND, "machine_id"});
  auto unknown_part = bend_request(100.0, 90.0);
  unknown_part.mutable_part()->set_part_id(std::string(64, 'a'));
  cases.push_back({unknown_part, grpc::StatusCode::NOT_FOUND, "part.part_id"});
  for (const Case& c : cases) {
    const grpc::Status s = call(*stub, c.request, &out);
    EXPECT_EQ(s.error_code(), c.code) << s.error_message();
    EXPECT_NE(s.error_message().find(c.field), std::string::npos) << s.error_message();
  }
  // A bend the machine cannot make is an answer, not an error: denied with the limit named.
  ASSERT_TRUE(call(*stub, bend_request(100.0, 170.0), &out).ok());
  EXPECT_EQ(out.verdict(), pb::INCONCLUSIVE);
  EXPECT_EQ(out.inconclusive_reason(), pb::MACHINE_LIMIT);
  EXPECT_EQ(out.limit(), pb::BEND_ANGLE);
  // An oversize message (over gRPC's 4 MiB receive limit) is refused; the daemon keeps serving.
  auto huge = bend_request(100.0, 90.0);
  huge.set_machine_id(std::string(5u << 20, 'x'));
  EXPECT_EQ(call(*stub, huge, &out).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  // Still serving.
  EXPECT_TRUE(call(*stub, bend_request(100.0, 90.0), &out).ok());
}

TEST(GatekeeperdE2E, UploadsAreCheckedStoredAndSurviveRestartsAndKill9) {
  const std::string dir = testing::temp_dir("upload");
  const std::string stl = testing::read_file(testing::shared_data("meshes/occt/TR12J_OCC64K.stl"));
  const std::string obj = testing::read_file(testing::shared_data("meshes/fcl/rob.obj"));
  pb::PartInfo big, small;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    ASSERT_TRUE(upload(*stub, stl, "stl", &big).ok());  // 3.4 MB in four chunks
    EXPECT_EQ(big.triangles(), 67498u);
    EXPECT_EQ(big.part_id(), testing::sha256_hex(stl));
    // A wrong sha, a chunk over 1 MiB, a broken STEP file, an unknown format: refused, not stored.
    pb::PartInfo ignored;
    grpc::Status s = upload(*stub, obj, "obj", &ignored, std::string(64, '0'));
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("sha256"), std::string::npos) << s.error_message();
    s = upload(*stub, stl, "stl", &ignored, "", (1u << 20) + 1);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    s = upload(*stub, "ISO-10303-21;\nHEADER;\nnot really\n", "step", &ignored);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    s = upload(*stub, obj, "xyz", &ignored);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("format"), std::string::npos);
    // A client that goes away mid-upload leaves nothing behind and the daemon serving.
    {
      grpc::ClientContext ctx;
      pb::PartInfo partial;
      auto writer = stub->UploadPart(&ctx, &partial);
      pb::UploadPartChunk header;
      header.mutable_header()->set_format("stl");
      header.mutable_header()->set_size_bytes(stl.size());
      header.mutable_header()->set_sha256(testing::sha256_hex(stl));
      writer->Write(header);
      pb::UploadPartChunk data;
      data.set_data(stl.substr(0, 1000));
      writer->Write(data);
      ctx.TryCancel();
    }
    ASSERT_TRUE(upload(*stub, obj, "obj", &small).ok());
    EXPECT_EQ(daemon.stop(SIGTERM), 0);  // graceful
  }
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    for (const pb::PartInfo* p : {&big, &small}) {
      grpc::ClientContext ctx;
      pb::GetPartInfoRequest req;
      req.set_part_id(p->part_id());
      pb::PartInfo got;
      ASSERT_TRUE(stub->GetPartInfo(&ctx, req, &got).ok());
      EXPECT_EQ(got.triangles(), p->triangles());
    }
    grpc::ClientContext ctx;
    pb::ServerInfo info;
    ASSERT_TRUE(stub->GetServerInfo(&ctx, pb::GetServerInfoRequest(), &info).ok());
    EXPECT_EQ(info.parts_stored(), 2u);  // nothing from the refused or abandoned uploads
    // Acknowledged, then killed without warning: still there after the restart.
    pb::PartInfo fandisk;
    const std::string off = testing::read_file(testing::shared_data("meshes/cgal/turbine.off"));
    ASSERT_TRUE(upload(*stub, off, "off", &fandisk).ok());
    EXPECT_EQ(daemon.stop(SIGKILL), -SIGKILL);
    Daemon again(dir);
    grpc::ClientContext ctx2;
    pb::GetPartInfoRequest req;
    req.set_part_id(fandisk.part_id());
    pb::PartInfo got;
    ASSERT_TRUE(again.stub()->GetPartInfo(&ctx2, req, &got).ok());
    EXPECT_EQ(got.triangles(), 18460u);
  }
}

TEST(GatekeeperdE2E, ClearanceQueryMatchesTheKernelAndRefusesOverload) {
  const std::string dir = testing::temp_dir("clearance");
  const std::string obj = testing::read_file(testing::shared_data("meshes/fcl/rob.obj"));
  const std::string stl = testing::read_file(testing::shared_data("meshes/occt/TR12J_OCC64K.stl"));
  Daemon daemon(dir, {"--workers", "1", "--queue", "1"});
  auto stub = daemon.stub();
  pb::PartInfo rob, tr12j;
  ASSERT_TRUE(upload(*stub, obj, "obj", &rob).ok());
  ASSERT_TRUE(upload(*stub, stl, "stl", &tr12j).ok());
  pb::ClearanceQueryRequest req;
  req.mutable_a()->set_part_id(rob.part_id());
  req.mutable_b()->set_part_id(rob.part_id());
  req.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(1500.0);
  req.mutable_b()->mutable_pose()->mutable_rotation_axis()->set_z_mm(1.0);
  req.mutable_b()->mutable_pose()->set_rotation_deg(30.0);
  req.set_safety_gap_mm(600.0);
  pb::ClearanceQueryResponse resp;
  grpc::ClientContext ctx;
  ASSERT_TRUE(stub->ClearanceQuery(&ctx, req, &resp).ok());
  // The same query on the kernel in process.
  auto mesh = mesh_io::read_mesh_file(testing::shared_data("meshes/fcl/rob.obj"), {{true}, true}).value();
  auto bvh = MeshBvh::build(testing::share(mesh)).value();
  const RigidTransform pose_b = RigidTransform::from_axis_angle(Vec3::UnitZ(), 30.0 * kPi / 180.0, Vec3(1500, 0, 0));
  const double expected = distance(*bvh, {}, *bvh, pose_b).value().distance_mm;
  EXPECT_NEAR(resp.distance_mm(), expected, 1e-9);
  EXPECT_EQ(resp.verdict(), pb::CLEAR);
  EXPECT_GT(resp.pairs_within_gap(), 0u);
  EXPECT_TRUE(resp.gap_violated());
  // Two closed 10 mm cubes overlapping by 2 mm: regions, depth and volume; an open mesh says why
  // it has no volume.
  const std::string cube_obj = testing::box_obj(0, 0, 0, 10, 10, 10);
  pb::PartInfo cube;
  ASSERT_TRUE(upload(*stub, cube_obj, "obj", &cube).ok());
  EXPECT_TRUE(cube.closed());
  pb::ClearanceQueryRequest overlap;
  overlap.mutable_a()->set_part_id(cube.part_id());
  overlap.mutable_b()->set_part_id(cube.part_id());
  overlap.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(8.0);
  overlap.set_safety_gap_mm(1.0);
  overlap.set_compute_depth(true);
  overlap.set_compute_volume(true);
  pb::ClearanceQueryResponse deep;
  grpc::ClientContext octx;
  ASSERT_TRUE(stub->ClearanceQuery(&octx, overlap, &deep).ok());
  EXPECT_EQ(deep.verdict(), pb::COLLISION);
  EXPECT_NEAR(deep.interference_volume_mm3(), 200.0, 1e-6);  // 2 x 10 x 10, exact for axis-aligned boxes
  EXPECT_NEAR(deep.depth_mm(), 2.0, 1e-3);                  // convex cubes: the exact depth, 2 along +x
  EXPECT_TRUE(deep.depth_exact());
  EXPECT_EQ(deep.depth_method(), "convex-piece or part axis");
  EXPECT_GT(vec_x(deep.depth_direction()), 0.999);
  EXPECT_TRUE(deep.volume_method() == "mesh ray cast" || deep.volume_method() == "mesh exact corefinement")
      << deep.volume_method();
  {
    // A corner overlap no ray grid resolves (0.0114 mm deep, 1.5e-6 mm^3), written at 5e4 mm in
    // the file: the exact corefinement gives it, to the rounding of the exact figure.
    const double c = std::stod("50009.9886"), depth = 50010.0 - c;  // as the file says it; Sterbenz: exact
    pb::PartInfo far_a, far_b;
    ASSERT_TRUE(upload(*stub, testing::box_obj(50000, 50000, 50000, 50010, 50010, 50010), "obj", &far_a).ok());
    ASSERT_TRUE(upload(*stub, testing::box_obj(c, c, c, 50020, 50020, 50020), "obj", &far_b).ok());
    pb::ClearanceQueryRequest corner;
    corner.mutable_a()->set_part_id(far_a.part_id());
    corner.mutable_b()->set_part_id(far_b.part_id());
    corner.set_compute_volume(true);
    pb::ClearanceQueryResponse tiny;
    grpc::ClientContext cctx;
    ASSERT_TRUE(stub->ClearanceQuery(&cctx, corner, &tiny).ok());
    EXPECT_EQ(tiny.verdict(), pb::COLLISION);
    EXPECT_EQ(tiny.volume_method(), "mesh exact corefinement");
    EXPECT_NEAR(tiny.interference_volume_mm3(), depth * depth * depth, 1e-15 * depth * depth * depth);
    EXPECT_LE(tiny.volume_error_bound_mm3(), 1e-15 * depth * depth * depth);
  }
  // Along a requested direction: +y frees B after the cube's full 10 mm.
  overlap.mutable_depth_along()->set_y_mm(3.0);
  grpc::ClientContext actx;
  ASSERT_TRUE(stub->ClearanceQuery(&actx, overlap, &deep).ok());
  EXPECT_NEAR(deep.depth_mm(), 10.0, 1e-3);
  EXPECT_EQ(deep.depth_method(), "along the requested direction");
  overlap.clear_depth_along();
  EXPECT_GE(deep.regions_size(), 1);
  EXPECT_LT(deep.error_bound_mm(), 1e-6);
  overlap.mutable_a()->set_part_id(rob.part_id());
  overlap.mutable_b()->set_part_id(rob.part_id());
  overlap.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(300.0);
  grpc::ClientContext sctx;
  ASSERT_TRUE(stub->ClearanceQuery(&sctx, overlap, &deep).ok());
  EXPECT_EQ(deep.verdict(), pb::COLLISION);
  EXPECT_EQ(deep.interference_volume_mm3(), -1.0);  // requested, not measured
  EXPECT_NE(deep.not_computed().find("volume"), std::string::npos) << deep.not_computed();
  // Two CAD parts: the distance is refined on the exact faces and matches BRepExtrema on the
  // whole shapes to 1e-6 mm.
  const std::string brep = testing::read_file(testing::shared_data("step/occt/Pump_Nut.brep"));
  pb::PartInfo nut;
  ASSERT_TRUE(upload(*stub, brep, "brep", &nut).ok());
  pb::ClearanceQueryRequest cad;
  cad.mutable_a()->set_part_id(nut.part_id());
  cad.mutable_b()->set_part_id(nut.part_id());
  // A copy moved along x by its box diagonal plus 3 mm: apart, with curved faces nearest.
  const double shift = std::hypot(nut.bounds_max().x_mm() - nut.bounds_min().x_mm(), nut.bounds_max().y_mm() - nut.bounds_min().y_mm(),
                                  nut.bounds_max().z_mm() - nut.bounds_min().z_mm()) + 3.0;
  cad.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(shift);
  cad.set_safety_gap_mm(1.0);
  pb::ClearanceQueryResponse refined;
  grpc::ClientContext rctx;
  ASSERT_TRUE(stub->ClearanceQuery(&rctx, cad, &refined).ok());
  ASSERT_TRUE(refined.refined_on_brep()) << refined.verdict() << " d=" << refined.distance_mm() << " pairs=" << refined.pairs_within_gap() << " shift=" << shift;
  auto shape = occt::read_shape_file(testing::shared_data("step/occt/Pump_Nut.brep")).value();
  const RigidTransform pose_nut = RigidTransform::from_translation(Vec3(shift, 0, 0));
  const double exact_d = occt::exact_distance(shape, occt::place(shape, pose_nut).value()).value().distance_mm;
  EXPECT_NEAR(refined.distance_mm(), exact_d, 1e-6);
  EXPECT_LE(refined.error_bound_mm(), 1e-6 + 1e-9);  // OCCT's precision plus rounding
  // Unknown part and NaN pose.
  req.mutable_a()->set_part_id(std::string(64, 'b'));
  grpc::ClientContext ctx2;
  EXPECT_EQ(stub->ClearanceQuery(&ctx2, req, &resp).error_code(), grpc::StatusCode::NOT_FOUND);
  req.mutable_a()->set_part_id(rob.part_id());
  req.mutable_b()->mutable_pose()->mutable_translation()->set_y_mm(std::nan(""));
  grpc::ClientContext ctx3;
  const grpc::Status nan = stub->ClearanceQuery(&ctx3, req, &resp);
  EXPECT_EQ(nan.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(nan.error_message().find("b.pose.translation"), std::string::npos);
  // One worker and a queue of one: a burst of heavy queries is partly refused, never crashes.
  pb::ClearanceQueryRequest heavy;
  heavy.mutable_a()->set_part_id(tr12j.part_id());
  heavy.mutable_b()->set_part_id(tr12j.part_id());
  heavy.mutable_b()->mutable_pose()->mutable_translation()->set_z_mm(1.0);
  heavy.set_safety_gap_mm(5.0);
  std::atomic<int> ok{0}, exhausted{0};
  std::vector<std::thread> burst;
  for (int i = 0; i < 12; ++i)
    burst.emplace_back([&] {
      auto s = daemon.stub();
      grpc::ClientContext c;
      c.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
      pb::ClearanceQueryResponse r;
      const grpc::Status st = s->ClearanceQuery(&c, heavy, &r);
      if (st.ok()) ++ok;
      if (st.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) ++exhausted;
    });
  for (auto& t : burst) t.join();
  EXPECT_GE(ok.load(), 1);
  EXPECT_GE(exhausted.load(), 1);
  EXPECT_EQ(ok.load() + exhausted.load(), 12);
}

TEST(GatekeeperdE2E, DeadlinesHealthMachinesAndConcurrentClients) {
  Daemon daemon(testing::temp_dir("misc"));
  auto stub = daemon.stub();
  // A branch too long for its deadline.
  pb::ValidateStepsRequest many;
  for (int i = 0; i < 400; ++i) *many.add_steps() = bend_request(50.0 + (i % 200), 90.0 - (i % 40));
  grpc::ClientContext short_ctx;
  short_ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(2));
  pb::ValidateStepsResponse ignored;
  EXPECT_EQ(stub->ValidateSteps(&short_ctx, many, &ignored).error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // Health.
  auto health = grpc::health::v1::Health::NewStub(daemon.channel());
  grpc::ClientContext hctx;
  grpc::health::v1::HealthCheckRequest hreq;
  grpc::health::v1::HealthCheckResponse hresp;
  ASSERT_TRUE(health->Check(&hctx, hreq, &hresp).ok());
  EXPECT_EQ(hresp.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  // Machines: list, get, set state (bad and good).
  grpc::ClientContext lctx;
  pb::ListMachinesResponse machines;
  ASSERT_TRUE(stub->ListMachines(&lctx, pb::ListMachinesRequest(), &machines).ok());
  ASSERT_EQ(machines.machines_size(), 1);
  EXPECT_EQ(machines.machines(0).aba_segments(), 50u);
  pb::SetMachineStateRequest set;
  set.mutable_state()->set_clamp_z_mm(2.0);
  set.mutable_state()->set_manipulator_y_mm(-700.0);
  for (int i = 0; i < 50; ++i) set.mutable_state()->add_engaged_segments(i % 2 == 0);
  pb::MachineInfo info;
  grpc::ClientContext sctx;
  ASSERT_TRUE(stub->SetMachineState(&sctx, set, &info).ok());
  EXPECT_EQ(info.state().engaged_segments_size(), 50);
  set.mutable_state()->set_manipulator_y_mm(1e9);
  grpc::ClientContext bctx;
  EXPECT_EQ(stub->SetMachineState(&bctx, set, &info).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // Many concurrent clients get consistent answers.
  std::atomic<int> clear{0}, collide{0}, failed{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 8; ++c)
    clients.emplace_back([&, c] {
      auto s = daemon.stub();
      for (int i = 0; i < 100; ++i) {
        pb::ValidateStepResponse r;
        const bool tall = (i + c) % 2 == 0;
        if (!call(*s, bend_request(tall ? 300.0 : 150.0, 90.0), &r).ok()) {
          ++failed;
          continue;
        }
        (r.verdict() == (tall ? pb::COLLISION : pb::CLEAR) ? (tall ? collide : clear) : failed) += 1;
      }
    });
  for (auto& t : clients) t.join();
  EXPECT_EQ(failed.load(), 0);
  EXPECT_EQ(clear.load() + collide.load(), 800);
  grpc::ClientContext ictx;
  pb::ServerInfo server;
  ASSERT_TRUE(stub->GetServerInfo(&ictx, pb::GetServerInfoRequest(), &server).ok());
  bool saw = false;
  for (const auto& r : server.rpcs())
    if (r.method() == "ValidateStep") {
      saw = true;
      EXPECT_GE(r.calls(), 800u);
      std::uint64_t in_histogram = 0;
      for (std::uint64_t c : r.histogram_counts()) in_histogram += c;
      EXPECT_EQ(in_histogram, r.calls());
    }
  EXPECT_TRUE(saw);
}

}  // namespace
}  // namespace gk
