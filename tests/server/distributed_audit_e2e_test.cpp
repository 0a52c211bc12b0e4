// gatekeeper-audit under mpiexec (Debian's Open MPI, processes oversubscribed on this machine):
// with 1, 2 and 4 processes the merged report equals the daemon's own audit of the same scene,
// clash for clash (ids, verdicts, distances to the bit); a process killed part way ends the MPI
// job, and the same command run again computes only the tiles that have no result yet and gives
// the same report.
#include "clients/gatekeeper_client/audit_report.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/sanitized_build.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
namespace fs = std::filesystem;
using testing::Daemon;

// Runs a shell command; returns its exit status (-1 when it could not run).
int shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string mpiexec(int processes, const std::string& data_dir, const std::string& scene, const std::string& work_dir,
                    const std::string& out, const std::string& extra) {
  std::ostringstream c;
  // As root here (CI), oversubscribed (2 cores). Under the sanitized stage the driver's processes
  // run without leak detection: Open MPI keeps allocations of its components until exit, and
  // their stacks stop at the first frame (no frame pointers), so no suppression can name them.
  // Memory errors are still caught; the engine code the driver runs is leak-checked by the
  // daemon's and the engine's suites.
  c << "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
    << "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 "
    << "mpiexec --oversubscribe -n " << processes << " " << GATEKEEPER_AUDIT_PATH << " --data-dir " << data_dir
    << " --scene " << scene << " --work-dir " << work_dir << " --out " << out << " " << extra << " >" << work_dir
    << ".log 2>&1";
  return c.str();
}

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

pb::Pose at(double x, double y, double turn_deg) {
  pb::Pose pose;
  pose.mutable_translation()->set_x_mm(x);
  pose.mutable_translation()->set_y_mm(y);
  pose.mutable_rotation_axis()->set_z_mm(1.0);
  pose.set_rotation_deg(turn_deg);
  return pose;
}

// A scene of `count` crates on a jittered grid (some overlapping, some a few mm apart), uploaded
// through the daemon; returns the scene id.
std::string crate_yard(pb::Gatekeeper::Stub& stub, int count, unsigned seed) {
  const std::string crate = testing::upload_part_id(stub, testing::box_obj(0, 0, 0, 1000, 800, 600), "obj");
  const std::string beam = testing::upload_part_id(stub, testing::box_obj(0, 0, 0, 6000, 200, 300), "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  EXPECT_TRUE(stub.CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-150.0, 150.0), turn(0.0, 30.0);
  const int side = static_cast<int>(std::ceil(std::sqrt(count)));
  for (int i = 0; i < count; ++i) {
    pb::SceneObject* o = batch.add_objects();
    o->set_name("crate" + std::to_string(i));
    o->set_category(i % 7 == 0 ? "beam" : "crate");
    o->set_part_id(i % 7 == 0 ? beam : crate);
    *o->mutable_pose() = at(1100.0 * (i % side) + jitter(rng), 900.0 * (i / side) + jitter(rng), turn(rng));
  }
  pb::PutObjectsResponse ids;
  grpc::ClientContext pctx;
  EXPECT_TRUE(stub.PutObjects(&pctx, batch, &ids).ok());
  return scene.scene_id();
}

void expect_report_equals_daemons(const nlohmann::json& report, const pb::AuditReport& daemon_report) {
  ASSERT_TRUE(report.is_object());
  ASSERT_EQ(report["clashes"].size(), static_cast<std::size_t>(daemon_report.clashes_size()));
  for (int i = 0; i < daemon_report.clashes_size(); ++i) {
    const pb::Clash& d = daemon_report.clashes(i);
    const nlohmann::json& c = report["clashes"][static_cast<std::size_t>(i)];
    EXPECT_EQ(c["object_a"], d.object_a()) << i;
    EXPECT_EQ(c["object_b"], d.object_b()) << i;
    EXPECT_EQ(c["verdict"], pb::Verdict_Name(d.verdict()).substr(pb::Verdict_Name(d.verdict()).find_last_of('_') + 1)) << i;
    EXPECT_EQ(c["distance_mm"].get<double>(), d.distance_mm()) << i;  // to the bit
    EXPECT_EQ(c["contacts"].get<unsigned>(), d.contact_pairs()) << i;
  }
  EXPECT_EQ(report["candidate_pairs"].get<std::uint64_t>(), daemon_report.candidate_pairs());
}

TEST(DistributedAuditE2E, OneTwoAndFourProcessesEqualTheDaemonsAudit) {
  const std::string dir = testing::temp_dir("mpi-audit");
  std::string scene;
  pb::AuditReport daemon_report;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    scene = crate_yard(*stub, 150, 3);
    pb::StartAuditRequest start;
    start.set_scene_id(scene);
    start.set_clearance_mm(20.0);
    start.set_tile_mm(2500.0);
    daemon_report = testing::run_audit(*stub, start);
    ASSERT_EQ(daemon_report.progress().state(), pb::DONE);
    ASSERT_GT(daemon_report.clashes_size(), 20);
  }
  nlohmann::json first;
  for (int processes : {1, 2, 4}) {
    const std::string work = dir + "/work-" + std::to_string(processes);
    const std::string out = dir + "/report-" + std::to_string(processes) + ".json";
    ASSERT_EQ(shell(mpiexec(processes, dir, scene, work, out, "--clearance-mm 20 --tile-mm 2500")), 0)
        << testing::read_file(work + ".log");
    const nlohmann::json report = read_json(out);
    expect_report_equals_daemons(report, daemon_report);
    ASSERT_EQ(report["per_process"].size(), static_cast<std::size_t>(processes));
    std::size_t computed = 0;
    for (const auto& p : report["per_process"]) computed += p["tiles_computed"].get<std::size_t>();
    EXPECT_GT(report["tiles"].get<std::size_t>(), 4u);
    if (processes > 1) {
      EXPECT_EQ(report["clashes"], first["clashes"]);
      for (const auto& p : report["per_process"]) EXPECT_GT(p["tiles_computed"].get<std::size_t>(), 0u);  // everyone worked
    } else {
      first = report;
    }
    EXPECT_GT(computed, 4u);
  }
  // Out of core: every part written once as a pack, meshes read tile by tile within a budget
  // smaller than any tile (one tile at a time): the same report.
  for (int processes : {1, 2}) {
    const std::string work = dir + "/work-packed-" + std::to_string(processes);
    const std::string out = dir + "/report-packed-" + std::to_string(processes) + ".json";
    ASSERT_EQ(shell(mpiexec(processes, dir, scene, work, out, "--clearance-mm 20 --tile-mm 2500 --memory-budget-gb 0.000001")), 0)
        << testing::read_file(work + ".log");
    const nlohmann::json report = read_json(out);
    expect_report_equals_daemons(report, daemon_report);
    // A pack holds its mesh renumbered in tree order, so which of a pair's contacts stands for the
    // clash (point_a, point_b) may differ; everything else is equal.
    auto without_points = [](nlohmann::json clashes) {
      for (auto& c : clashes) {
        c.erase("point_a");
        c.erase("point_b");
      }
      return clashes;
    };
    EXPECT_EQ(without_points(report["clashes"]), without_points(first["clashes"]));
    std::size_t packs_read = 0;
    for (const auto& p : report["per_process"]) packs_read += p["packs_read"].get<std::size_t>();
    EXPECT_GT(packs_read, 0u);
  }
  EXPECT_TRUE(fs::is_directory(dir + "/bvh-cache/packs"));
  // The 1-process work directory belongs to that audit: another clearance there is refused.
  const std::string work = dir + "/work-1";
  EXPECT_NE(shell(mpiexec(1, dir, scene, work, dir + "/other.json", "--clearance-mm 25 --tile-mm 2500")), 0);
  EXPECT_NE(testing::read_file(work + ".log").find("--work-dir"), std::string::npos) << testing::read_file(work + ".log");
  EXPECT_FALSE(fs::exists(dir + "/other.json"));
  // And a directory that is no daemon's data directory is refused without creating anything there.
  const std::string nowhere = dir + "/no-such-data";
  EXPECT_NE(shell(mpiexec(1, nowhere, scene, dir + "/work-x", dir + "/x.json", "")), 0);
  EXPECT_FALSE(fs::exists(nowhere));
}

TEST(DistributedAuditE2E, AKilledProcessEndsTheJobAndTheSameCommandRedoesOnlyItsMissingTiles) {
  const std::string dir = testing::temp_dir("mpi-audit-kill");
  std::string scene;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    scene = crate_yard(*stub, 150, 5);
  }
  // The uninterrupted answer, from one process.
  // The depth and volume make each tile take long enough to kill a process part way (the volume
  // is left out under the sanitizers, where everything is slower anyway).
  const std::string extra = std::string("--clearance-mm 20 --tile-mm 2500 --compute-depth") + (testing::kSanitizedBuild ? "" : " --compute-volume");
  ASSERT_EQ(shell(mpiexec(1, dir, scene, dir + "/whole", dir + "/whole.json", extra)), 0) << testing::read_file(dir + "/whole.log");
  const nlohmann::json whole = read_json(dir + "/whole.json");
  // Two processes; process 1 is killed once any tile has a result.
  const std::string work = dir + "/cut", out = dir + "/cut.json";
  std::thread killer([&] {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (std::chrono::steady_clock::now() < give_up) {
      std::size_t tiles = 0;
      std::error_code ec;  // the directory appears when the job starts
      for (const auto& e : fs::directory_iterator(work, ec))
        tiles += e.path().filename().string().rfind("tile-", 0) == 0 && e.path().extension() == ".bin";
      std::ifstream pid_file(work + "/process-1.pid");
      pid_t pid = 0;
      if (tiles >= 1 && (pid_file >> pid) && pid > 0) {
        ::kill(pid, SIGKILL);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  const int cut_status = shell(mpiexec(2, dir, scene, work, out, extra));
  killer.join();
  std::size_t kept = 0;
  for (const auto& e : fs::directory_iterator(work)) kept += e.path().extension() == ".bin";
  if (cut_status == 0) GTEST_SKIP() << "the job finished before a process could be killed";
  EXPECT_FALSE(fs::exists(out));
  // Run again: the kept tiles are not computed again, the report equals the uninterrupted one.
  ASSERT_EQ(shell(mpiexec(2, dir, scene, work, out, extra)), 0) << testing::read_file(work + ".log");
  const nlohmann::json again = read_json(out);
  EXPECT_EQ(again["clashes"], whole["clashes"]);
  std::size_t resumed = 0, computed = 0;
  for (const auto& p : again["per_process"]) {
    resumed += p["tiles_resumed"].get<std::size_t>();
    computed += p["tiles_computed"].get<std::size_t>();
  }
  EXPECT_EQ(resumed, kept);
  std::size_t all = 0;
  for (const auto& p : whole["per_process"]) all += p["tiles_computed"].get<std::size_t>();
  EXPECT_EQ(resumed + computed, all);
}


// The daemon configured with a driver hands a large audit to it (gatekeeper-audit under mpiexec,
// two processes) and reports the same audit as when it runs it itself, clash for clash, with
// progress; a driver that fails makes the job FAILED naming it, and a cancel ends the driver.
TEST(DistributedAuditE2E, TheDaemonHandsALargeAuditToItsDriverAndReportsTheSame) {
  const std::string dir = testing::temp_dir("mpi-handoff");
  std::string scene;
  pb::StartAuditRequest start;
  start.set_clearance_mm(20.0);
  start.set_tile_mm(2500.0);
  pb::AuditReport local;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    scene = crate_yard(*stub, 150, 7);
    start.set_scene_id(scene);
    local = testing::run_audit(*stub, start);
    ASSERT_EQ(local.progress().state(), pb::DONE);
    ASSERT_GT(local.clashes_size(), 20);
  }
  const std::string driver = std::string("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
                                         "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 mpiexec --oversubscribe -n 2 ") +
                             GATEKEEPER_AUDIT_PATH;
  {
    Daemon daemon(dir, {"--audit-driver", driver, "--audit-driver-min-triangles", "1"});
    auto stub = daemon.stub();
    const pb::AuditReport handed = testing::run_audit(*stub, start);
    ASSERT_EQ(handed.progress().state(), pb::DONE) << handed.progress().message();
    EXPECT_EQ(handed.progress().tiles_done(), handed.progress().tiles_total());
    EXPECT_EQ(handed.progress().tiles_total(), local.progress().tiles_total());  // counted as the daemon counts them
    EXPECT_GT(handed.progress().tiles_total(), 4u);
    EXPECT_EQ(handed.progress().pairs_done(), handed.progress().pairs_total());
    ASSERT_EQ(handed.clashes_size(), local.clashes_size());
    for (int i = 0; i < local.clashes_size(); ++i) {
      const pb::Clash& a = local.clashes(i);
      const pb::Clash& b = handed.clashes(i);
      EXPECT_EQ(a.object_a(), b.object_a());
      EXPECT_EQ(a.object_b(), b.object_b());
      EXPECT_EQ(a.verdict(), b.verdict());
      EXPECT_EQ(a.distance_mm(), b.distance_mm());  // to the bit
      EXPECT_EQ(a.contact_pairs(), b.contact_pairs());
      EXPECT_EQ(a.point().x_mm(), b.point().x_mm());
      EXPECT_EQ(a.point_b().y_mm(), b.point_b().y_mm());
      EXPECT_EQ(a.clash_id(), b.clash_id());
    }
    EXPECT_EQ(handed.candidate_pairs(), local.candidate_pairs());
    EXPECT_FALSE(fs::exists(dir + "/audit-work") && !fs::is_empty(dir + "/audit-work"));  // a finished job's work is removed
  }
  {  // A driver that fails: the job fails, naming it and its log.
    Daemon daemon(dir, {"--audit-driver", "false", "--audit-driver-min-triangles", "1"});
    auto stub = daemon.stub();
    const pb::AuditReport failed = testing::run_audit(*stub, start);
    EXPECT_EQ(failed.progress().state(), pb::FAILED);
    EXPECT_NE(failed.progress().message().find("'false' ended with exit code 1"), std::string::npos) << failed.progress().message();
  }
  {  // A driver that would run long and ignores SIGTERM (as do its children): a cancel ends it.
    const std::string pid_file = dir + "/driver.pid";
    Daemon daemon(dir, {"--audit-driver", "echo $$ > " + pid_file + "; trap '' TERM; (while true; do sleep 1; done) & wait; true",
                        "--audit-driver-min-triangles", "1"});
    auto stub = daemon.stub();
    pb::AuditJob job;
    grpc::ClientContext sctx;
    ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    const auto t0 = std::chrono::steady_clock::now();
    grpc::ClientContext cctx;
    pb::CancelAuditRequest cancel;
    cancel.set_job_id(job.job_id());
    pb::AuditProgress after;
    ASSERT_TRUE(stub->CancelAudit(&cctx, cancel, &after).ok());
    pb::AuditProgress progress;
    for (int i = 0; i < 100; ++i) {
      grpc::ClientContext gctx;
      pb::GetAuditReportRequest get;
      get.set_job_id(job.job_id());
      pb::AuditReport report;
      ASSERT_TRUE(stub->GetAuditReport(&gctx, get, &report).ok());
      progress = report.progress();
      if (progress.state() != pb::RUNNING) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    EXPECT_EQ(progress.state(), pb::CANCELLED);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(8));
    // The driver's shell leads its process group: nothing of the group is left.
    ASSERT_TRUE(fs::exists(pid_file));
    EXPECT_NE(shell("kill -0 -- -$(cat " + pid_file + ") 2>/dev/null"), 0) << "the driver's process group outlived the cancel";
  }
}

}  // namespace
}  // namespace gk
