// A hostile client against the real daemon (issue: hardened service §1): requests that used to
// kill it. After each, the daemon must still answer.
#include "tests/server/daemon_fixture.h"
#include "tests/support/sanitized_build.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <set>
#include <thread>
#include <vector>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

void expect_alive(pb::Gatekeeper::Stub& stub) {
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  pb::ServerInfo info;
  EXPECT_TRUE(stub.GetServerInfo(&ctx, pb::GetServerInfoRequest(), &info).ok()) << "the daemon stopped answering";
}

// A scene of n robot copies along x, 150 mm apart (neighbours clash), for audits that take a while.
// spacing_mm 0: every copy at one pose (every pair clashes in every tile it spans).
std::string robot_row(pb::Gatekeeper::Stub& stub, int n, double spacing_mm = 150.0) {
  const std::string rob = testing::upload_part_id(stub, testing::read_file(testing::shared_data("meshes/fcl/rob.obj")), "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  EXPECT_TRUE(stub.CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  pb::PutObjectsRequest put;
  put.set_scene_id(scene.scene_id());
  for (int i = 0; i < n; ++i) {
    pb::SceneObject* o = put.add_objects();
    o->set_part_id(rob);
    o->set_name("rob" + std::to_string(i));
    o->set_category("robot");
    o->mutable_pose()->mutable_translation()->set_x_mm(spacing_mm * i);
  }
  grpc::ClientContext pctx;
  pb::PutObjectsResponse ids;
  EXPECT_TRUE(stub.PutObjects(&pctx, put, &ids).ok());
  return scene.scene_id();
}

TEST(HostileClientE2E, ATinyTileIsRefusedNotACrash) {
  Daemon daemon(testing::temp_dir("hostile-tile"));
  auto stub = daemon.stub();
  const std::string scene = robot_row(*stub, 3);
  for (double tile : {1e-17, 1e-300, 5e-324}) {
    pb::StartAuditRequest start;
    start.set_scene_id(scene);
    start.set_tile_mm(tile);
    pb::AuditJob job;
    grpc::ClientContext ctx;
    const grpc::Status s = stub->StartAudit(&ctx, start, &job);
    if (s.ok()) {  // refused when the job runs: the job fails naming tile_mm
      grpc::ClientContext gctx;
      pb::GetAuditReportRequest get;
      get.set_job_id(job.job_id());
      pb::AuditReport report;
      for (int i = 0; i < 100 && report.progress().state() != pb::FAILED; ++i) {
        report.Clear();
        grpc::ClientContext c;
        ASSERT_TRUE(stub->GetAuditReport(&c, get, &report).ok());
        if (report.progress().state() == pb::RUNNING) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        else break;
      }
      EXPECT_EQ(report.progress().state(), pb::FAILED) << tile;
      EXPECT_NE(report.progress().message().find("tile_mm"), std::string::npos) << report.progress().message();
    } else {
      EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    }
    expect_alive(*stub);
  }
}

// A 341-byte STEP file, found by tests/fuzz/shape_file_fuzzer, on which OCCT's STEP translator
// dereferences a null pointer (StepGeom_CartesianPoint::NbCoordinates): uploaded, it killed the
// daemon. CAD files are now read in a child process first.
const char* const kStepThatCrashesOcct = R"step(ISO-13-21;
HEADER;'')ENDSEC;
DATA;

#6 = SHAPE_DEFINITION_REPRESENTATION(#7,#11);
#7 = PRODUCT_DEFINITION_SHAPE('void','void',#8)
#8 = PRODUCT_DEFINITION('von');
#11 = ADVANCED_BREP_SHAPE_REPRESENTATION('',(#12),CARTE);
#12 =ADVANCED_FACE('',(#15),#49.);2;
#49 = PLANE('',#50);
#50 = AXIS2_PLACEMENT_3D(lue','usi');
ENDSEC;
END-ISO-10303-1;
)step";

TEST(HostileClientE2E, ACadFileThatCrashesOcctsReaderIsRefusedAndTheDaemonServesOn) {
  const std::string dir = testing::temp_dir("hostile-cad-crash");
  Daemon daemon(dir);
  auto stub = daemon.stub();
  for (int round = 0; round < 3; ++round) {
    pb::PartInfo info;
    const grpc::Status s = testing::upload_part(*stub, kStepThatCrashesOcct, "step", &info);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << s.error_message();
    // "crashed" (a signal); a sanitizer build turns the crash into an exit status: "failed".
    EXPECT_NE(s.error_message().find("refused"), std::string::npos) << s.error_message();
    expect_alive(*stub);
  }
  // Nothing of the refused uploads is left behind (the crashed child's link with the format's
  // extension was, once per upload).
  EXPECT_TRUE(std::filesystem::is_empty(dir + "/tmp")) << std::filesystem::begin(std::filesystem::directory_iterator(dir + "/tmp"))->path();
  // A sound CAD file still goes through the child and is stored.
  const std::string screw = testing::upload_part_id(*stub, testing::read_file(testing::shared_data("step/occt/screw.step")), "step");
  EXPECT_FALSE(screw.empty());
  expect_alive(*stub);
}

TEST(HostileClientE2E, LoadedPartsStayWithinTheMemoryBudgetAndAreReadAgainFromDisk) {
  // 0.0003 GB = 322 KB: FCL's env mesh alone (2,180 triangles and 6,540 vertices, about 484 KB
  // estimated) is over it, so every query between env and rob drops one of them and reads it again.
  Daemon daemon(testing::temp_dir("hostile-part-memory"), {"--part-memory-gb", "0.0003"});
  auto stub = daemon.stub();
  const std::string env = testing::upload_part_id(*stub, testing::read_file(testing::shared_data("meshes/fcl/env.obj")), "obj");
  const std::string rob = testing::upload_part_id(*stub, testing::read_file(testing::shared_data("meshes/fcl/rob.obj")), "obj");
  ASSERT_FALSE(env.empty());
  ASSERT_FALSE(rob.empty());
  pb::ClearanceQueryRequest request;
  request.mutable_a()->set_part_id(env);
  request.mutable_b()->set_part_id(rob);
  request.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(1200.0);
  double first = -1.0;
  for (int round = 0; round < 4; ++round) {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    pb::ClearanceQueryResponse response;
    const grpc::Status status = stub->ClearanceQuery(&ctx, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    if (round == 0) first = response.distance_mm();
    EXPECT_EQ(response.distance_mm(), first) << "a part read again must answer the same";
    std::swap(*request.mutable_a(), *request.mutable_b());  // the other load order
  }
  grpc::ClientContext ctx;
  pb::ServerInfo info;
  ASSERT_TRUE(stub->GetServerInfo(&ctx, pb::GetServerInfoRequest(), &info).ok());
  EXPECT_GE(info.parts_evicted(), 3u);
  EXPECT_EQ(info.parts_in_memory(), 1u) << "over budget, only the part loaded last is kept";
  expect_alive(*stub);
}

TEST(HostileClientE2E, EndedAuditsBeyondTheMemoryLimitAreReadBackFromTheDatabase) {
  Daemon daemon(testing::temp_dir("hostile-audit-memory"), {"--audits-in-memory", "1"});
  auto stub = daemon.stub();
  const std::string scene = robot_row(*stub, 4);
  std::vector<pb::AuditReport> finished;
  for (int i = 0; i < 3; ++i) {
    pb::StartAuditRequest start;
    start.set_scene_id(scene);
    finished.push_back(testing::run_audit(*stub, start));
  }
  // Two of the three were dropped from memory; each is read back whole, twice over.
  for (int pass = 0; pass < 2; ++pass)
    for (const pb::AuditReport& then : finished) {
      pb::GetAuditReportRequest get;
      get.set_job_id(then.progress().job_id());
      pb::AuditReport now;
      grpc::ClientContext ctx;
      ASSERT_TRUE(stub->GetAuditReport(&ctx, get, &now).ok()) << then.progress().job_id();
      EXPECT_EQ(now.progress().state(), pb::DONE);
      ASSERT_EQ(now.clashes_size(), then.clashes_size());
      EXPECT_GT(now.clashes_size(), 0);
      for (int k = 0; k < now.clashes_size(); ++k) {
        EXPECT_EQ(now.clashes(k).object_a(), then.clashes(k).object_a());
        EXPECT_EQ(now.clashes(k).object_b(), then.clashes(k).object_b());
      }
    }
  // A re-audit against a baseline that is no longer in memory.
  pb::StartAuditRequest again;
  again.set_scene_id(scene);
  again.set_baseline_job_id(finished.front().progress().job_id());
  const pb::AuditReport re = testing::run_audit(*stub, again);
  EXPECT_EQ(re.clashes_size(), finished.front().clashes_size());
  grpc::ClientContext ictx;
  pb::ServerInfo info;
  ASSERT_TRUE(stub->GetServerInfo(&ictx, pb::GetServerInfoRequest(), &info).ok());
  EXPECT_EQ(info.audits_in_memory(), 1u) << "four ended audits, one kept in memory";
}

TEST(HostileClientE2E, ThreeHundredWatchersOfARunningAuditNeitherKillItNorGoUnanswered) {
  Daemon daemon(testing::temp_dir("hostile-watch"));
  auto stub = daemon.stub();
  const std::string scene = robot_row(*stub, 60);
  pb::StartAuditRequest start;
  start.set_scene_id(scene);
  start.set_clearance_mm(20.0);
  pb::AuditJob job;
  grpc::ClientContext sctx;
  ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
  std::atomic<int> done{0}, refused{0}, other{0};
  std::vector<std::thread> watchers;
  for (int i = 0; i < 300; ++i)
    watchers.emplace_back([&] {
      grpc::ClientContext ctx;
      ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
      pb::WatchAuditRequest watch;
      watch.set_job_id(job.job_id());
      auto reader = stub->WatchAudit(&ctx, watch);
      pb::AuditProgress p, last;
      while (reader->Read(&p)) last = p;
      const grpc::Status s = reader->Finish();
      if (s.ok() && last.state() == pb::DONE) ++done;
      else if (s.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) ++refused;
      else ++other;
    });
  for (std::thread& t : watchers) t.join();
  EXPECT_EQ(done + refused, 300) << other << " watchers ended otherwise";
  EXPECT_GE(done.load(), 64);
  expect_alive(*stub);
}

// Ids that storage would truncate or cannot hold are refused naming the field, and a refused call
// stores nothing (issue: hardened service §2).
TEST(HostileClientE2E, MalformedIdsAndPosesAreRefusedAndNothingIsStored) {
  const std::string dir = testing::temp_dir("hostile-ids");
  std::string scene_id;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    const std::string box = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 10, 10, 10), "obj");
    grpc::ClientContext cctx;
    pb::SceneInfo scene;
    ASSERT_TRUE(stub->CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
    scene_id = scene.scene_id();
    auto put = [&](const std::string& id, double axis_x, const std::string& name = "box") {
      pb::PutObjectRequest req;
      req.set_scene_id(scene_id);
      req.mutable_object()->set_object_id(id);
      req.mutable_object()->set_part_id(box);
      req.mutable_object()->set_name(name);
      req.mutable_object()->mutable_pose()->mutable_rotation_axis()->set_x_mm(axis_x);
      req.mutable_object()->mutable_pose()->mutable_rotation_axis()->set_z_mm(1.0);
      req.mutable_object()->mutable_pose()->set_rotation_deg(30.0);
      grpc::ClientContext ctx;
      pb::MoveResult result;
      return stub->PutObject(&ctx, req, &result);
    };
    for (const std::string& bad : {std::string("nul\0a", 5), std::string(200, 'x'), std::string("a/b"), std::string("../x")}) {
      const grpc::Status s = put(bad, 0.0);
      EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad.size();
      EXPECT_NE(s.error_message().find("object_id"), std::string::npos) << s.error_message();
    }
    const grpc::Status huge_axis = put("tilted", 1e200);
    EXPECT_EQ(huge_axis.error_code(), grpc::StatusCode::OK) << huge_axis.error_message();  // a valid axis, scaled safely
    const grpc::Status name = put("named", 0.0, std::string("a\0b", 3));
    EXPECT_EQ(name.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    const grpc::Status good = put("good-id_1.2:3", 0.0);
    EXPECT_TRUE(good.ok()) << good.error_message();
    pb::PutMachineModelRequest model;
    model.set_machine_id(std::string(250, 'm'));
    model.set_model_toml("name = 'x'");
    grpc::ClientContext mctx;
    pb::MachineInfo info;
    const grpc::Status long_id = stub->PutMachineModel(&mctx, model, &info);
    EXPECT_EQ(long_id.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(long_id.error_message().find("machine_id"), std::string::npos) << long_id.error_message();
    expect_alive(*stub);
  }
  // After a restart exactly the accepted objects are there, and an audit of them runs.
  Daemon daemon(dir);
  auto stub = daemon.stub();
  grpc::ClientContext gctx;
  pb::GetSceneRequest get;
  get.set_scene_id(scene_id);
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->GetScene(&gctx, get, &scene).ok());
  std::set<std::string> ids;
  for (const pb::SceneObject& o : scene.objects()) ids.insert(o.object_id());
  EXPECT_EQ(ids, (std::set<std::string>{"good-id_1.2:3", "tilted"}));
}

// Audits run on their own threads: two long audits do not hold up a clearance query (they made a
// 1 ms query time out at 5 s when all work shared one pool).
TEST(HostileClientE2E, RunningAuditsDoNotDelayAClearanceQuery) {
  Daemon daemon(testing::temp_dir("hostile-pools"));
  auto stub = daemon.stub();
  const std::string scene = robot_row(*stub, 80);
  std::vector<std::string> jobs;
  for (int k = 0; k < 2; ++k) {
    pb::StartAuditRequest start;
    start.set_scene_id(scene);
    start.set_clearance_mm(50.0);
    start.set_compute_depth(true);  // slow on purpose
    pb::AuditJob job;
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->StartAudit(&ctx, start, &job).ok());
    jobs.push_back(job.job_id());
  }
  const std::string box = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 10, 10, 10), "obj");
  pb::ClearanceQueryRequest q;
  q.mutable_a()->set_part_id(box);
  q.mutable_b()->set_part_id(box);
  q.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(20.0);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  pb::ClearanceQueryResponse r;
  const grpc::Status s = stub->ClearanceQuery(&ctx, q, &r);
  EXPECT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(r.verdict(), pb::CLEAR);
  for (const std::string& id : jobs) {
    pb::CancelAuditRequest cancel;
    cancel.set_job_id(id);
    pb::AuditProgress p;
    grpc::ClientContext c;
    EXPECT_TRUE(stub->CancelAudit(&c, cancel, &p).ok());
  }
}

// Upload streams are bounded in number and in idle time (1,100 idle header-only streams exhausted
// the descriptors): beyond the cap they are refused, an idle one is cancelled, health answers.
// A deadline stops the work it paid for: a depth query between two large meshes pushed deep into
// each other (seconds of conservative advancement) is abandoned when its 200 ms deadline passes,
// and the single worker is free for the next query at once.
TEST(HostileClientE2E, ADeadlineStopsTheDepthSearch) {
  Daemon daemon(testing::temp_dir("deadline"), {"--workers", "1"});
  auto stub = daemon.stub();
  const std::string a = testing::upload_part_id(*stub, testing::read_file(testing::shared_data("meshes/occt/TR12J_OCC64K.stl")), "stl");
  pb::ClearanceQueryRequest deep;
  deep.mutable_a()->set_part_id(a);
  deep.mutable_b()->set_part_id(a);  // the part against itself, shifted: deep in each other everywhere
  deep.mutable_b()->mutable_pose()->mutable_translation()->set_x_mm(3.0);
  deep.mutable_b()->mutable_pose()->mutable_translation()->set_y_mm(2.0);
  deep.set_compute_depth(true);
  deep.set_compute_volume(true);
  {
    grpc::ClientContext ctx;
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(200));
    pb::ClearanceQueryResponse out;
    const grpc::Status status = stub->ClearanceQuery(&ctx, deep, &out);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << status.error_message();
  }
  // The worker gave it up: a plain query right after is answered well within its own deadline.
  pb::ClearanceQueryRequest plain = deep;
  plain.set_compute_depth(false);
  plain.set_compute_volume(false);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1500 * testing::kTimeScale));
  pb::ClearanceQueryResponse out;
  const grpc::Status status = stub->ClearanceQuery(&ctx, plain, &out);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(out.verdict(), pb::COLLISION);
  // Without a deadline the same depth query completes (what the deadline cut short was real work).
  grpc::ClientContext full_ctx;
  pb::ClearanceQueryResponse full;
  ASSERT_TRUE(stub->ClearanceQuery(&full_ctx, deep, &full).ok());
  EXPECT_GT(full.depth_mm(), 0.0);
  EXPECT_GT(full.elapsed_us(), 200000.0) << "the depth query is too quick to show that a deadline stops it";
}

TEST(HostileClientE2E, IdleUploadStreamsAreCappedAndReaped) {
  Daemon daemon(testing::temp_dir("hostile-uploads"), {"--max-uploads", "8", "--upload-idle-seconds", "1"});
  auto stub = daemon.stub();
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientWriter<pb::UploadPartChunk>>> streams;
  std::vector<pb::PartInfo> infos(12);
  for (int i = 0; i < 12; ++i) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    streams.push_back(stub->UploadPart(contexts.back().get(), &infos[static_cast<std::size_t>(i)]));
    pb::UploadPartChunk header;
    header.mutable_header()->set_name("idle.obj");
    header.mutable_header()->set_format("obj");
    header.mutable_header()->set_size_bytes(100);
    header.mutable_header()->set_sha256(std::string(64, 'a'));
    streams.back()->Write(header);
  }
  expect_alive(*stub);  // while they hang
  int exhausted = 0, cancelled = 0;
  for (auto& s : streams) {
    const grpc::Status status = s->Finish();  // waits: the idle ones are reaped after about 1 s
    if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) ++exhausted;
    if (status.error_code() == grpc::StatusCode::CANCELLED) ++cancelled;
  }
  EXPECT_EQ(exhausted, 4);
  EXPECT_EQ(cancelled, 8);
  // The slots are free again.
  EXPECT_FALSE(testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 1, 1, 1), "obj").empty());
  expect_alive(*stub);
}

// A job id never names two jobs, even across a restart that lost a running job.
TEST(HostileClientE2E, AuditIdsAreUniqueAcrossRestarts) {
  const std::string dir = testing::temp_dir("hostile-audit-ids");
  std::set<std::string> seen;
  std::string scene;
  for (int run = 0; run < 2; ++run) {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    if (scene.empty()) scene = robot_row(*stub, 4);
    for (int k = 0; k < 2; ++k) {
      pb::StartAuditRequest start;
      start.set_scene_id(scene);
      pb::AuditJob job;
      grpc::ClientContext ctx;
      ASSERT_TRUE(stub->StartAudit(&ctx, start, &job).ok());
      EXPECT_TRUE(seen.insert(job.job_id()).second) << job.job_id() << " given twice";
    }
    daemon.stop(SIGKILL);  // running jobs are lost, not archived
  }
}

// Validations of uploaded parts (each cold one prepares a large surface mesh) run on their own
// workers: a parametric step asked after them is answered while they are still being worked on,
// not queued behind them.
TEST(HostileClientE2E, SlowUploadedPartValidationsDoNotQueueParametricOnes) {
  Daemon daemon(testing::temp_dir("hostile-validation-pools"), {"--part-validation-workers", "1"});
  auto stub = daemon.stub();
  std::vector<std::string> parts;
  for (const char* name : {"refined_elephant", "diplodocus", "man", "fandisk_large", "mannequin-devil", "camel"})
    parts.push_back(testing::upload_part_id(*stub, testing::read_file(testing::shared_data(std::string("meshes/cgal/") + name + ".off")), "off"));
  auto clamp_of = [](const std::string& part_id) {
    pb::ValidateStepRequest r;
    if (!part_id.empty()) r.mutable_part()->set_part_id(part_id);
    else {
      r.mutable_part()->set_width_mm(1000.0);
      r.mutable_part()->set_depth_mm(800.0);
    }
    r.mutable_part()->set_thickness_mm(1.5);
    r.mutable_step()->set_kind(pb::CLAMP);
    r.mutable_state()->set_clamp_z_mm(1.5);
    r.mutable_state()->set_manipulator_y_mm(-400.0);
    return r;
  };
  const std::size_t n = parts.size();
  std::vector<pb::ValidateStepRequest> requests;
  std::vector<pb::ValidateStepResponse> answers(n);
  std::vector<grpc::Status> statuses(n);
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::atomic<std::size_t> finished{0};
  for (const std::string& id : parts) requests.push_back(clamp_of(id));
  for (std::size_t i = 0; i < n; ++i) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    stub->async()->ValidateStep(contexts[i].get(), &requests[i], &answers[i], [&, i](grpc::Status s) {
      statuses[i] = std::move(s);
      ++finished;
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let them reach the daemon first
  pb::ValidateStepResponse parametric;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  const grpc::Status s = stub->ValidateStep(&ctx, clamp_of(""), &parametric);
  const std::size_t uploaded_done_then = finished.load();
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_NE(parametric.verdict(), pb::VERDICT_UNSPECIFIED);
  EXPECT_LT(uploaded_done_then, n) << "the parametric step was answered only after every uploaded-part validation: it queued behind them";
  while (finished.load() < n) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_TRUE(statuses[i].ok()) << i << ": " << statuses[i].error_message();
    EXPECT_NE(answers[i].verdict(), pb::VERDICT_UNSPECIFIED) << i;
  }
  expect_alive(*stub);
}

// Bytes that read as two formats (found by a review: 134 bytes that are a binary STL triangle at
// z = 5 and an OBJ triangle at z = 0) keep one geometry under their id: the second format is
// refused, and the part stays what it was, also after a restart.
TEST(HostileClientE2E, TheSameBytesAsAnotherFormatAreRefusedAndThePartKeepsItsGeometry) {
  std::string bytes = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n#";
  bytes.resize(80, ' ');
  const std::uint32_t count = 1;
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  const float triangle[12] = {0, 0, 1, 0, 0, 5, 1, 0, 5, 0, 1, 5};
  bytes.append(reinterpret_cast<const char*>(triangle), sizeof triangle);
  bytes.append(2, '\0');
  ASSERT_EQ(bytes.size(), 134u);
  const std::string dir = testing::temp_dir("hostile-two-formats");
  std::string id;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    pb::PartInfo stl, obj;
    ASSERT_TRUE(testing::upload_part(*stub, bytes, "stl", &stl).ok());
    EXPECT_EQ(stl.bounds_min().z_mm(), 5.0);
    const grpc::Status again = testing::upload_part(*stub, bytes, "obj", &obj);
    EXPECT_EQ(again.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << again.error_message();
    EXPECT_NE(again.error_message().find("header.format"), std::string::npos) << again.error_message();
    pb::PartInfo same;
    ASSERT_TRUE(testing::upload_part(*stub, bytes, "stl", &same).ok());  // the same format again: the same part
    EXPECT_EQ(same.part_id(), stl.part_id());
    id = stl.part_id();
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  grpc::ClientContext ctx;
  pb::GetPartInfoRequest get;
  get.set_part_id(id);
  pb::PartInfo info;
  ASSERT_TRUE(stub->GetPartInfo(&ctx, get, &info).ok());
  EXPECT_EQ(info.format(), "stl");
  EXPECT_EQ(info.bounds_min().z_mm(), 5.0);
}

// A part id is a sha256 in hex, and a name holds no control characters: a NUL, which SQLite would
// have cut the stored text at, is refused naming the field.
TEST(HostileClientE2E, PartIdsAndNamesWithANulAreRefused) {
  Daemon daemon(testing::temp_dir("hostile-nul-ids"));
  auto stub = daemon.stub();
  const std::string box = testing::box_obj(0, 0, 0, 1, 1, 1);
  const std::string id = testing::upload_part_id(*stub, box, "obj");
  const std::string with_nul = id + std::string("\0../../etc/passwd", 17);
  {
    grpc::ClientContext ctx;
    pb::GetPartInfoRequest get;
    get.set_part_id(with_nul);
    pb::PartInfo info;
    const grpc::Status s = stub->GetPartInfo(&ctx, get, &info);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("part_id"), std::string::npos) << s.error_message();
  }
  {
    grpc::ClientContext cctx;
    pb::SceneInfo scene;
    ASSERT_TRUE(stub->CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
    pb::PutObjectRequest put;
    put.set_scene_id(scene.scene_id());
    put.mutable_object()->set_part_id(with_nul);
    grpc::ClientContext ctx;
    pb::MoveResult out;
    const grpc::Status s = stub->PutObject(&ctx, put, &out);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("object.part_id"), std::string::npos) << s.error_message();
  }
  // NUL, DEL, and a right-to-left override (U+202E) that would show the name reversed.
  for (const std::string& name : {std::string("a\0b", 3), std::string("a\x7f" "b"), std::string("a\xe2\x80\xae" "b")}) {
    grpc::ClientContext ctx;
    pb::PartInfo info;
    auto writer = stub->UploadPart(&ctx, &info);
    pb::UploadPartChunk header;
    header.mutable_header()->set_name(name);
    header.mutable_header()->set_format("obj");
    header.mutable_header()->set_size_bytes(box.size());
    header.mutable_header()->set_sha256(id);
    writer->Write(header);
    pb::UploadPartChunk data;
    data.set_data(box);
    writer->Write(data);
    writer->WritesDone();
    const grpc::Status s = writer->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("header.name"), std::string::npos) << s.error_message();
  }
  expect_alive(*stub);
}

pb::AuditProgress audit_state(pb::Gatekeeper::Stub& stub, const std::string& job) {
  pb::GetAuditReportRequest get;
  get.set_job_id(job);
  pb::AuditReport report;
  grpc::ClientContext ctx;
  EXPECT_TRUE(stub.GetAuditReport(&ctx, get, &report).ok());
  return report.progress();
}

// Found by a review: with a million small tiles the broad phase ran on for many seconds after
// CancelAudit (and a SIGTERM waited for it past the drain time). It stops between tiles, and a
// broad phase cut short is never reported DONE.
TEST(HostileClientE2E, AnAuditOfAMillionTilesStopsWhenCancelled) {
  Daemon daemon(testing::temp_dir("hostile-tiles-cancel"));
  auto stub = daemon.stub();
  const std::string scene = robot_row(*stub, 40, 0.0);
  pb::StartAuditRequest start;
  start.set_scene_id(scene);
  start.set_tile_mm(1.2);
  pb::AuditJob job;
  grpc::ClientContext sctx;
  ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  pb::CancelAuditRequest cancel;
  cancel.set_job_id(job.job_id());
  pb::AuditProgress p;
  grpc::ClientContext cctx;
  ASSERT_TRUE(stub->CancelAudit(&cctx, cancel, &p).ok());
  const auto t0 = std::chrono::steady_clock::now();
  pb::AuditProgress state = audit_state(*stub, job.job_id());
  while (state.state() == pb::RUNNING && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(20)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    state = audit_state(*stub, job.job_id());
  }
  EXPECT_EQ(state.state(), pb::CANCELLED);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0 * testing::kTimeScale);
}

// SIGTERM cancels a running audit rather than waiting for it: the daemon stops within its drain
// time (it took 14 s with --drain-seconds 1), and the audit is kept as CANCELLED.
TEST(HostileClientE2E, SigtermDoesNotWaitForARunningAudit) {
  const std::string dir = testing::temp_dir("hostile-sigterm-audit");
  std::string id;
  {
    Daemon daemon(dir);  // the fixture's drain time is 1 s
    auto stub = daemon.stub();
    const std::string scene = robot_row(*stub, 80);
    pb::StartAuditRequest start;
    start.set_scene_id(scene);
    start.set_clearance_mm(50.0);
    start.set_compute_depth(true);
    start.set_compute_volume(true);
    pb::AuditJob job;
    grpc::ClientContext ctx;
    ASSERT_TRUE(stub->StartAudit(&ctx, start, &job).ok());
    id = job.job_id();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ASSERT_EQ(audit_state(*stub, id).state(), pb::RUNNING) << "the audit is too quick to show anything";
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(daemon.stop(SIGTERM), 0);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0 + 3.0 * testing::kTimeScale);
  }
  // Interrupted by the stop, not ended: the next start resumes it under the same id.
  Daemon again(dir);
  const pb::AuditState state = audit_state(*again.stub(), id).state();
  EXPECT_TRUE(state == pb::RUNNING || state == pb::DONE) << pb::AuditState_Name(state);
}

// A MoveObject whose deadline passes stops computing the moved object's contacts: the one scene
// worker is free for the next move at once (3,000 stacked robots took it 5 s past a 0.3 s deadline).
TEST(HostileClientE2E, ADeadlineStopsAMovesContacts) {
  Daemon daemon(testing::temp_dir("hostile-move-deadline"), {"--scene-workers", "1"});
  auto stub = daemon.stub();
  const std::string crowded = robot_row(*stub, 3000, 0.0);
  pb::GetSceneRequest get;
  get.set_scene_id(crowded);
  pb::SceneInfo info;
  grpc::ClientContext gctx;
  ASSERT_TRUE(stub->GetScene(&gctx, get, &info).ok());
  pb::MoveObjectRequest move;
  move.set_scene_id(crowded);
  move.set_object_id(info.objects(0).object_id());
  move.mutable_pose()->mutable_translation()->set_x_mm(1.0);
  {
    grpc::ClientContext ctx;
    // 3,000 colliding neighbours take about 130 ms (Release, this machine kind): a 20 ms deadline
    // ends the work, and the scene worker is free for the next call.
    ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(20));
    pb::MoveResult out;
    EXPECT_EQ(stub->MoveObject(&ctx, move, &out).error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  }
  const std::string small = robot_row(*stub, 2, 0.0);
  pb::GetSceneRequest get_small;
  get_small.set_scene_id(small);
  pb::SceneInfo small_info;
  grpc::ClientContext sgctx;
  ASSERT_TRUE(stub->GetScene(&sgctx, get_small, &small_info).ok());
  pb::MoveObjectRequest quick;
  quick.set_scene_id(small);
  quick.set_object_id(small_info.objects(0).object_id());
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(1500 * testing::kTimeScale));
  pb::MoveResult out;
  const grpc::Status s = stub->MoveObject(&ctx, quick, &out);
  EXPECT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(out.verdict(), pb::COLLISION);
}

}  // namespace
}  // namespace gk
