// The audit service end to end: a small factory put into a scene through the RPCs, audited with
// rules and tiles, compared with assessing every pair in process; a re-audit after a move equals a
// fresh audit; the HTML report loads, draws and lists the clashes in headless Chromium.
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "engine/audits/scene_audit.h"
#include "mesh_io/mesh_file_reader.h"
#include "clients/gatekeeper_client/audit_report.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/sanitized_build.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sqlite3.h>

#include <cstdio>
#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <tuple>
#include <cmath>
#include <sstream>
#include <thread>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;
using testing::get_scene;

struct Placed {
  std::string name, category, group, part;
  Vec3 at;
  double turn_deg = 0.0;
};

std::string box_obj(double sx, double sy, double sz) { return testing::box_obj(0, 0, 0, sx, sy, sz); }

std::string upload(pb::Gatekeeper::Stub& stub, const std::string& bytes, const std::string& format) {
  return testing::upload_part_id(stub, bytes, format);
}

pb::Pose pose_of(const Placed& p) {
  pb::Pose pose;
  pose.mutable_translation()->set_x_mm(p.at.x());
  pose.mutable_translation()->set_y_mm(p.at.y());
  pose.mutable_translation()->set_z_mm(p.at.z());
  pose.mutable_rotation_axis()->set_z_mm(1.0);
  pose.set_rotation_deg(p.turn_deg);
  return pose;
}

using testing::run_audit;

// A new scene with `count` copies of a 1 m cube (part uploaded), placed by where(i), in one batch
// request (returned, not sent) so a test can also send broken copies of it.
struct CubeScene {
  std::string scene_id, cube;
  pb::PutObjectsRequest batch;
};
CubeScene cube_scene(pb::Gatekeeper::Stub& stub, const std::string& prefix, int count, const std::function<Vec3(int)>& where) {
  CubeScene out;
  out.cube = upload(stub, box_obj(1000, 1000, 1000), "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  EXPECT_TRUE(stub.CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  out.scene_id = scene.scene_id();
  out.batch.set_scene_id(out.scene_id);
  for (int i = 0; i < count; ++i) {
    pb::SceneObject* o = out.batch.add_objects();
    o->set_name(prefix + std::to_string(i));
    o->set_category(prefix);
    o->set_part_id(out.cube);
    *o->mutable_pose() = pose_of({"", "", "", "", where(i)});
  }
  return out;
}

std::map<std::pair<std::string, std::string>, pb::Verdict> clash_set(const pb::AuditReport& report) {
  std::map<std::pair<std::string, std::string>, pb::Verdict> out;
  for (const pb::Clash& c : report.clashes()) out[{c.name_a(), c.name_b()}] = c.verdict();
  return out;
}

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  pclose(pipe);
  return out;
}

TEST(AuditE2E, AFactoryAuditWithRulesEqualsEveryPairAndItsPageDrawsInChromium) {
  Daemon daemon(testing::temp_dir("audit-factory"));
  auto stub = daemon.stub();
  // Parts: a column, a crate, two KUKA collision links (metres: scaled by the pose? no: kept small).
  const std::string column = upload(*stub, box_obj(400, 400, 8000), "obj");
  const std::string crate = upload(*stub, box_obj(1000, 1000, 1000), "obj");
  const std::string pipe = upload(*stub, box_obj(30000, 200, 200), "obj");
  const std::string link0 = upload(*stub, testing::read_file(testing::shared_data("meshes/robots/kuka_kr10r1420/collision/base_link.stl")), "stl");
  const std::string link1 = upload(*stub, testing::read_file(testing::shared_data("meshes/robots/kuka_kr10r1420/collision/link_1.stl")), "stl");
  std::vector<Placed> placed;
  for (int i = 0; i < 4; ++i) placed.push_back({"column" + std::to_string(i), "column", "", column, Vec3(i * 8000.0, 0, 0)});
  placed.push_back({"pipe", "pipe", "", pipe, Vec3(-1000, 100, 3000)});       // crosses every column: 4 clashes
  placed.push_back({"crate-a", "crate", "", crate, Vec3(2000, 3000, 0)});
  placed.push_back({"crate-b", "crate", "", crate, Vec3(2995, 3000, 0)});     // overlaps crate-a by 5 mm
  placed.push_back({"crate-c", "crate", "", crate, Vec3(4002, 3000, 0)});     // 7 mm from crate-b: a clearance violation
  placed.push_back({"crate-d <!--<script>", "crate", "", crate, Vec3(9000, 3000, 0)});     // alone
  for (int r = 0; r < 3; ++r) {                                                // robots: links of one robot overlap
    const std::string group = "robot" + std::to_string(r);
    placed.push_back({group + "/base", "robot", group, link0, Vec3(14000.0 + 3000 * r, 5000, 0), 30.0 * r});
    placed.push_back({group + "/link1", "robot", group, link1, Vec3(14000.0 + 3000 * r, 5000, 0), 30.0 * r});
  }
  grpc::ClientContext cctx;
  pb::CreateSceneRequest create;
  create.set_name("hall <7>");
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->CreateScene(&cctx, create, &scene).ok());
  std::map<std::string, std::string> id_of;
  for (const Placed& p : placed) {
    grpc::ClientContext ctx;
    pb::PutObjectRequest put;
    put.set_scene_id(scene.scene_id());
    put.mutable_object()->set_name(p.name);
    put.mutable_object()->set_category(p.category);
    put.mutable_object()->set_group(p.group);
    put.mutable_object()->set_part_id(p.part);
    *put.mutable_object()->mutable_pose() = pose_of(p);
    pb::MoveResult moved;
    ASSERT_TRUE(stub->PutObject(&ctx, put, &moved).ok());
    id_of[p.name] = moved.object_id();
  }
  pb::StartAuditRequest start;
  start.set_scene_id(scene.scene_id());
  start.set_clearance_mm(10.0);
  start.set_tile_mm(6000.0);
  pb::ContactRule* rule = start.add_rules();
  rule->set_name("links of one robot");
  rule->set_category_a("robot");
  rule->set_category_b("robot");
  rule->set_same_group_only(true);
  const pb::AuditReport report = run_audit(*stub, start, true);
  EXPECT_EQ(report.progress().state(), pb::DONE);
  EXPECT_GT(report.progress().tiles_total(), 4u);
  EXPECT_EQ(report.excluded_by_rules(), 3u);
  // The oracle: every pair in process (names in id order, as the service orders them).
  std::map<std::string, std::shared_ptr<MeshBvh>> meshes;
  auto mesh_of = [&](const Placed& p) {
    if (!meshes.count(p.part)) {
      const std::string file = p.part == link0   ? testing::shared_data("meshes/robots/kuka_kr10r1420/collision/base_link.stl")
                               : p.part == link1 ? testing::shared_data("meshes/robots/kuka_kr10r1420/collision/link_1.stl")
                                                 : "";
      TriangleMesh m = file.empty() ? testing::box_mesh(Vec3::Zero(), p.part == column ? Vec3(400, 400, 8000)
                                                                       : p.part == crate ? Vec3(1000, 1000, 1000)
                                                                                          : Vec3(30000, 200, 200))
                                    : mesh_io::read_mesh_file(file).value();
      meshes[p.part] = MeshBvh::build(testing::share(std::move(m))).value();
    }
    return meshes[p.part];
  };
  std::map<std::pair<std::string, std::string>, pb::Verdict> expected;
  for (std::size_t i = 0; i < placed.size(); ++i)
    for (std::size_t j = i + 1; j < placed.size(); ++j) {
      const Placed& a = placed[i];
      const Placed& b = placed[j];
      if (a.category == "robot" && b.category == "robot" && a.group == b.group) continue;
      const auto v = assess(*mesh_of(a), RigidTransform::from_axis_angle(Vec3::UnitZ(), a.turn_deg * 3.14159265358979323846 / 180, a.at),
                            *mesh_of(b), RigidTransform::from_axis_angle(Vec3::UnitZ(), b.turn_deg * 3.14159265358979323846 / 180, b.at))
                         .value();
      if (v.verdict == Verdict::kClear && v.distance_mm >= 10.0) continue;
      const bool a_first = id_of[a.name] < id_of[b.name];
      expected[{a_first ? a.name : b.name, a_first ? b.name : a.name}] =
          v.verdict == Verdict::kCollision ? pb::COLLISION : v.verdict == Verdict::kTouching ? pb::TOUCHING
                                                           : v.verdict == Verdict::kClear     ? pb::CLEAR
                                                                                              : pb::INCONCLUSIVE;
    }
  EXPECT_EQ(clash_set(report), expected);
  EXPECT_EQ(expected.size(), 6u);  // pipe x 4 columns, crates a-b, crates b-c (clearance)
  bool crates_grouped = false;
  for (const pb::ClashGroup& g : report.by_category()) crates_grouped = crates_grouped || (g.key() == "crate / crate" && g.clashes() == 2);
  EXPECT_TRUE(crates_grouped);
  ASSERT_GT(report.by_object_size(), 0);
  EXPECT_EQ(report.by_object(0).clashes(), 4u);  // the pipe

  // The page: self-contained, then loaded in headless Chromium, which must draw it and list every clash.
  const std::string& html = report.html();
  EXPECT_NE(html.find("hall &lt;7&gt;"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);  // nothing fetched from the network
  const std::string page = testing::temp_dir("audit-page") + "/report.html";
  std::ofstream(page) << html;
  const std::string dom = run("chromium --headless=new --no-sandbox --disable-dev-shm-usage --enable-unsafe-swiftshader "
                              "--use-angle=swiftshader --virtual-time-budget=10000 --dump-dom file://" + page + " 2>/dev/null");
  ASSERT_FALSE(dom.empty()) << "chromium did not run (scripts/install_deps.sh installs it)";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("<body([^>]*)>"))) << dom.substr(0, 400);
  const std::string body = m[1];
  EXPECT_NE(body.find("data-state=\"drawn\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-rows=\"6\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-drawn-markers=\"6\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-drawn-objects=\"" + std::to_string(placed.size()) + "\""), std::string::npos) << body;
  // The 8 objects in a clash (pipe, 4 columns, 3 crates) with their meshes, the others as boxes.
  EXPECT_NE(body.find("data-drawn-meshes=\"8\""), std::string::npos) << body;
  // Opened on clash 1: the view frames both its objects (the union of their boxes).
  const std::string framed_dom = run("chromium --headless=new --no-sandbox --disable-dev-shm-usage --enable-unsafe-swiftshader "
                                     "--use-angle=swiftshader --virtual-time-budget=10000 --dump-dom 'file://" + page + "#clash=1' 2>/dev/null");
  ASSERT_TRUE(std::regex_search(framed_dom, m, std::regex("<body([^>]*)>")));
  const std::string framed_body = m[1];
  EXPECT_NE(framed_body.find("data-selected=\"1\""), std::string::npos) << framed_body;
  {
    const std::size_t script = html.find("<script id=\"report-data\" type=\"application/json\">");
    ASSERT_NE(script, std::string::npos);
    const std::size_t from = html.find('>', script) + 1;
    const nlohmann::json data = nlohmann::json::parse(html.substr(from, html.find("</script>", from) - from));
    const auto& first = data["clashes"][0];
    const auto& oa = data["objects"][first["a_index"].get<std::size_t>()];
    const auto& ob = data["objects"][first["b_index"].get<std::size_t>()];
    std::string union_box;
    for (const char* end : {"min", "max"})
      for (int k = 0; k < 3; ++k) {
        const double a = oa[end][k].get<double>(), b = ob[end][k].get<double>();
        char text[32];
        std::snprintf(text, sizeof text, "%s%.0f", union_box.empty() ? "" : ",", std::string(end) == "min" ? std::min(a, b) : std::max(a, b));
        union_box += text;
      }
    EXPECT_NE(framed_body.find("data-framed=\"" + union_box + "\""), std::string::npos) << framed_body << " expected " << union_box;
    EXPECT_GT(data["parts"].size(), 0u);
  }
  EXPECT_NE(body.find("data-renderer=\"webgl\""), std::string::npos) << body;  // the 3D view, not the 2D fallback
  std::printf("chromium: %s\n", body.c_str());
  EXPECT_NE(dom.find("crate-b"), std::string::npos);

  // Move crate-b away: a re-audit against the first job equals a fresh audit and computes fewer pairs.
  grpc::ClientContext mctx;
  pb::MoveObjectRequest move;
  move.set_scene_id(scene.scene_id());
  move.set_object_id(id_of["crate-b"]);
  Placed moved_b = placed[6];
  moved_b.at = Vec3(2995, 9000, 0);
  *move.mutable_pose() = pose_of(moved_b);
  pb::MoveResult moved;
  ASSERT_TRUE(stub->MoveObject(&mctx, move, &moved).ok());
  pb::StartAuditRequest again = start;
  again.set_baseline_job_id(report.progress().job_id());
  const pb::AuditReport incremental = run_audit(*stub, again);
  const pb::AuditReport fresh = run_audit(*stub, start);
  EXPECT_EQ(clash_set(incremental), clash_set(fresh));
  EXPECT_EQ(clash_set(fresh).size(), 4u);
  EXPECT_LT(incremental.recomputed_pairs(), fresh.recomputed_pairs());

  // Bad input names the field.
  pb::StartAuditRequest bad = start;
  bad.mutable_rules(0)->set_category_a("");
  grpc::ClientContext b1;
  pb::AuditJob job;
  grpc::Status s = stub->StartAudit(&b1, bad, &job);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.error_message().find("rules[0].category_a"), std::string::npos);
  bad = start;
  bad.set_baseline_job_id("audit-404");
  grpc::ClientContext b2;
  s = stub->StartAudit(&b2, bad, &job);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(s.error_message().find("baseline_job_id"), std::string::npos);
  // A baseline computed with other options is never reused: its answers would be stale (a 30 mm
  // pair is no violation at a 20 mm clearance, but is one at 50). Refused, naming the option.
  for (auto change : std::vector<std::function<void(pb::StartAuditRequest&)>>{
           [](pb::StartAuditRequest& r) { r.set_clearance_mm(r.clearance_mm() + 40.0); },
           [](pb::StartAuditRequest& r) { r.mutable_rules(0)->set_same_group_only(!r.rules(0).same_group_only()); },
           [](pb::StartAuditRequest& r) { r.set_compute_depth(!r.compute_depth()); }}) {
    pb::StartAuditRequest other = again;
    change(other);
    grpc::ClientContext c;
    s = stub->StartAudit(&c, other, &job);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << s.error_message();
    EXPECT_NE(s.error_message().find("the baseline was audited with"), std::string::npos) << s.error_message();
  }
  pb::StartAuditRequest clearance = again;
  clearance.set_clearance_mm(again.clearance_mm() + 40.0);
  grpc::ClientContext c3;
  s = stub->StartAudit(&c3, clearance, &job);
  EXPECT_EQ(s.error_message().rfind("clearance_mm", 0), 0u) << s.error_message();
}

TEST(AuditE2E, ADragStreamAnswersLikeSingleMovesEvenWhenOthersEditTheScene) {
  Daemon daemon(testing::temp_dir("drag-session"));
  auto stub = daemon.stub();
  const std::string column = upload(*stub, box_obj(400, 400, 8000), "obj");
  const std::string link0 = upload(*stub, testing::read_file(testing::shared_data("meshes/robots/kuka_kr10r1420/collision/base_link.stl")), "stl");
  // Two identical scenes: one dragged through a stream (its layout session stays valid between
  // frames), the other moved by unary calls (the plain all-objects check) as the oracle.
  struct Built {
    std::string scene, robot;
    std::vector<std::string> columns;
  };
  auto build = [&]() {
    Built out;
    grpc::ClientContext cctx;
    pb::SceneInfo info;
    EXPECT_TRUE(stub->CreateScene(&cctx, pb::CreateSceneRequest(), &info).ok());
    out.scene = info.scene_id();
    for (int i = 0; i < 12; ++i) {
      grpc::ClientContext ctx;
      pb::PutObjectRequest put;
      put.set_scene_id(out.scene);
      put.mutable_object()->set_name("column" + std::to_string(i));
      put.mutable_object()->set_category("column");
      put.mutable_object()->set_part_id(column);
      *put.mutable_object()->mutable_pose() = pose_of({"", "", "", "", Vec3(1000.0 * i, (i % 2) * 700.0, 0)});
      pb::MoveResult r;
      EXPECT_TRUE(stub->PutObject(&ctx, put, &r).ok());
      out.columns.push_back(r.object_id());
    }
    grpc::ClientContext pctx;
    pb::PutObjectRequest put;
    put.set_scene_id(out.scene);
    put.mutable_object()->set_name("robot");
    put.mutable_object()->set_category("robot");
    put.mutable_object()->set_part_id(link0);
    pb::MoveResult r;
    EXPECT_TRUE(stub->PutObject(&pctx, put, &r).ok());
    out.robot = r.object_id();
    return out;
  };
  const Built dragged_scene = build(), unary_scene = build();
  // Object ids differ between the scenes: compare contacts by the columns' index.
  auto by_index = [](const pb::MoveResult& r, const Built& b) {
    std::set<std::tuple<std::size_t, int, long long>> out;
    for (const pb::ObjectContact& c : r.contacts()) {
      const auto at = std::find(b.columns.begin(), b.columns.end(), c.other_object_id()) - b.columns.begin();
      out.insert({static_cast<std::size_t>(at), static_cast<int>(c.verdict()), std::llround(c.distance_mm() * 1e6)});
    }
    return out;
  };
  grpc::ClientContext dctx;
  auto stream = stub->DragObject(&dctx);
  auto other_client = daemon.stub();
  int frames_with_contacts = 0;
  for (int f = 0; f < 60; ++f) {
    pb::MoveObjectRequest move;
    move.set_clearance_mm(100.0);
    *move.mutable_pose() = pose_of({"", "", "", "", Vec3(-500.0 + 200.0 * f, 350.0, 0), 3.0 * f});
    move.set_scene_id(dragged_scene.scene);
    move.set_object_id(dragged_scene.robot);
    ASSERT_TRUE(stream->Write(move));
    pb::MoveResult dragged, single;
    ASSERT_TRUE(stream->Read(&dragged));
    move.set_scene_id(unary_scene.scene);
    move.set_object_id(unary_scene.robot);
    grpc::ClientContext uctx;
    ASSERT_TRUE(other_client->MoveObject(&uctx, move, &single).ok());
    EXPECT_EQ(by_index(dragged, dragged_scene), by_index(single, unary_scene)) << "frame " << f;
    EXPECT_EQ(dragged.verdict(), single.verdict()) << "frame " << f;
    frames_with_contacts += dragged.contacts_size() > 0;
    if (f == 30) {  // another client moves a column into the robot's path, in both scenes
      for (const Built* b : {&dragged_scene, &unary_scene}) {
        grpc::ClientContext ectx;
        pb::MoveObjectRequest edit;
        edit.set_scene_id(b->scene);
        edit.set_object_id(b->columns[8]);
        *edit.mutable_pose() = pose_of({"", "", "", "", Vec3(7000.0, 0, 0)});
        ASSERT_TRUE(other_client->MoveObject(&ectx, edit, &single).ok());
      }
    }
  }
  stream->WritesDone();
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_GT(frames_with_contacts, 10);
}

TEST(AuditE2E, PutObjectsStoresAWholeBatchOrNothingAndItSurvivesKill9) {
  const std::string dir = testing::temp_dir("put-objects");
  std::string scene_id;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    CubeScene made = cube_scene(*stub, "cube", 500, [](int i) { return Vec3(2000.0 * (i % 25), 2000.0 * (i / 25), 0); });
    scene_id = made.scene_id;
    pb::PutObjectsRequest& batch = made.batch;
    for (int i = 0; i < 500; ++i) batch.mutable_objects(i)->set_group(i % 2 ? "odd" : "even");
    // One bad object: nothing of the batch is stored, and the error names it.
    pb::PutObjectsRequest bad = batch;
    bad.mutable_objects(321)->mutable_pose()->mutable_translation()->set_z_mm(std::nan(""));
    pb::PutObjectsResponse ids;
    grpc::ClientContext bctx;
    const grpc::Status refused = stub->PutObjects(&bctx, bad, &ids);
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(refused.error_message().find("objects[321].pose.translation"), std::string::npos) << refused.error_message();
    bad = batch;
    bad.mutable_objects(7)->set_part_id(std::string(64, 'f'));
    grpc::ClientContext b2;
    EXPECT_EQ(stub->PutObjects(&b2, bad, &ids).error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(get_scene(*stub, scene_id).objects_size(), 0);
    grpc::ClientContext pctx;
    ASSERT_TRUE(stub->PutObjects(&pctx, batch, &ids).ok());
    EXPECT_EQ(ids.object_ids_size(), 500);
    EXPECT_EQ(daemon.stop(SIGKILL), -SIGKILL);  // acknowledged: must survive
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  const pb::SceneInfo scene = get_scene(*stub, scene_id);
  ASSERT_EQ(scene.objects_size(), 500);
  std::set<std::string> groups;
  for (const pb::SceneObject& o : scene.objects()) groups.insert(o.group());
  EXPECT_EQ(groups, (std::set<std::string>{"even", "odd"}));
}

// A closed UV sphere of radius r (mm) with about 2 * rings * segments triangles, as OBJ text.
std::string sphere_obj(double r, int rings, int segments) {
  std::ostringstream out;
  out.precision(17);
  out << "v 0 0 " << r << "\n";
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = M_PI * i / rings, ph = 2.0 * M_PI * j / segments;
      out << "v " << r * std::sin(th) * std::cos(ph) << " " << r * std::sin(th) * std::sin(ph) << " " << r * std::cos(th) << "\n";
    }
  out << "v 0 0 " << -r << "\n";
  auto at = [&](int i, int j) { return 2 + (i - 1) * segments + (j % segments); };  // OBJ is 1-based
  const int south = 2 + (rings - 1) * segments;
  for (int j = 0; j < segments; ++j) out << "f 1 " << at(1, j) << " " << at(1, j + 1) << "\n";
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      out << "f " << at(i, j) << " " << at(i + 1, j) << " " << at(i + 1, j + 1) << "\n";
      out << "f " << at(i, j) << " " << at(i + 1, j + 1) << " " << at(i, j + 1) << "\n";
    }
  for (int j = 0; j < segments; ++j) out << "f " << at(rings - 1, j) << " " << south << " " << at(rings - 1, j + 1) << "\n";
  return out.str();
}

// Rows in the daemon's checkpoint table of finished tiles (read beside the running daemon).
long long checkpointed_tiles(const std::string& dir) {
  sqlite3* db = nullptr;
  long long n = -1;
  if (sqlite3_open_v2((dir + "/gatekeeper.sqlite").c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(db, 2000);
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT COUNT(*) FROM audit_tiles", -1, &stmt, nullptr) == SQLITE_OK && sqlite3_step(stmt) == SQLITE_ROW)
      n = sqlite3_column_int64(stmt, 0);
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return n;
}

// The report of a job that is already running, once it has ended.
pb::AuditReport report_when_ended(pb::Gatekeeper::Stub& stub, const std::string& job_id) {
  grpc::ClientContext wctx;
  pb::WatchAuditRequest watch;
  watch.set_job_id(job_id);
  auto reader = stub.WatchAudit(&wctx, watch);
  pb::AuditProgress progress;
  while (reader->Read(&progress)) {
  }
  EXPECT_TRUE(reader->Finish().ok());
  pb::AuditReport report;
  EXPECT_TRUE(client::read_audit_report(stub, job_id, &report, client::ReportOptions{}).ok());
  return report;
}

// A new scene of `count` spheres of 7,200 triangles in a row, each overlapping the next by 40 mm
// (one pair per 1.5 m tile; with the depth each pair takes a noticeable time). Returns its id.
// Under the sanitizers, where everything is several times slower, spheres of 1,800 triangles.
std::string sphere_row(pb::Gatekeeper::Stub& stub, int count) {
  const int rings = testing::kSanitizedBuild ? 30 : 60;
  const std::string ball = upload(stub, sphere_obj(500.0, rings, rings), "obj");
  grpc::ClientContext cctx;
  pb::SceneInfo scene;
  EXPECT_TRUE(stub.CreateScene(&cctx, pb::CreateSceneRequest(), &scene).ok());
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  for (int i = 0; i < count; ++i) {
    pb::SceneObject* o = batch.add_objects();
    o->set_name("ball" + std::to_string(i));
    o->set_category("ball");
    o->set_part_id(ball);
    *o->mutable_pose() = pose_of({"", "", "", "", Vec3(960.0 * i, 0, 0), 7.0 * i});
  }
  pb::PutObjectsResponse ids;
  grpc::ClientContext pctx;
  EXPECT_TRUE(stub.PutObjects(&pctx, batch, &ids).ok());
  return scene.scene_id();
}

// A nightly audit stopped part way (kill -9, or a stop) resumes when the daemon starts again,
// from the tiles it had finished (checkpointed in its database), under the same job id; its
// report equals an audit that ran without interruption, clash for clash and bit for bit.
TEST(AuditE2E, AnAuditStoppedPartWayResumesFromItsTilesAndEqualsAnUninterruptedOne) {
  for (int signal_number : {SIGKILL, SIGTERM}) {
    const std::string dir = testing::temp_dir(signal_number == SIGKILL ? "audit-resume-kill" : "audit-resume-term");
    std::string job_id;
    pb::StartAuditRequest start;
    long long tiles_before = 0;
    {
      // No drain: on SIGTERM a running audit goes on while in-flight calls finish (up to
      // --drain-seconds; the fixture's 1 s), and since distance queries prune with node slabs
      // this row's remaining tiles take less than that - the audit would end, with nothing to
      // resume.
      Daemon daemon(dir, {"--drain-seconds", "0"});
      auto stub = daemon.stub();
      const std::string scene_id = sphere_row(*stub, 16);
      start.set_scene_id(scene_id);
      start.set_clearance_mm(1.0);
      start.set_tile_mm(1500.0);
      start.set_threads(1);
      start.set_compute_depth(true);
      pb::AuditJob job;
      grpc::ClientContext sctx;
      ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
      job_id = job.job_id();
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
      while ((tiles_before = checkpointed_tiles(dir)) < 3 && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      ASSERT_GE(tiles_before, 3);
      daemon.stop(signal_number);
    }
    const long long tiles_at_stop = checkpointed_tiles(dir);
    ASSERT_GE(tiles_at_stop, tiles_before);
    ASSERT_LT(tiles_at_stop, 15) << "the audit ended before it was stopped: nothing to resume";
    Daemon daemon(dir, {"--log-level", "info", "--log-file", dir + "/gatekeeperd.log"});
    auto stub = daemon.stub();
    const pb::AuditReport resumed = report_when_ended(*stub, job_id);
    EXPECT_EQ(resumed.progress().state(), pb::DONE);
    EXPECT_EQ(checkpointed_tiles(dir), 0);  // ended and archived: its checkpoint is gone
    const pb::AuditReport fresh = testing::run_audit(*stub, start);
    ASSERT_EQ(fresh.progress().state(), pb::DONE);
    EXPECT_NE(fresh.progress().job_id(), job_id);
    ASSERT_EQ(resumed.clashes_size(), 15);
    ASSERT_EQ(fresh.clashes_size(), 15);
    for (int i = 0; i < fresh.clashes_size(); ++i) {
      EXPECT_GT(fresh.clashes(i).depth_mm(), 0.0);
      // The review status is the pair's status now, not a finding: the resumed audit found each
      // pair first (NEW, read before the fresh audit ran), the fresh one again (ACTIVE).
      EXPECT_EQ(resumed.clashes(i).status(), pb::CLASH_NEW);
      EXPECT_EQ(fresh.clashes(i).status(), pb::CLASH_ACTIVE);
      pb::Clash resumed_finding = resumed.clashes(i), fresh_finding = fresh.clashes(i);
      resumed_finding.clear_status();
      fresh_finding.clear_status();
      EXPECT_EQ(resumed_finding.SerializeAsString(), fresh_finding.SerializeAsString()) << "clash " << i;
    }
    EXPECT_EQ(resumed.candidate_pairs(), fresh.candidate_pairs());
    EXPECT_EQ(resumed.objects(), fresh.objects());
    EXPECT_EQ(resumed.triangles(), fresh.triangles());
    EXPECT_EQ(resumed.progress().pairs_done(), fresh.progress().pairs_done());
    // The resumed run took the finished tiles from the checkpoint.
    const std::string log = testing::read_file(dir + "/gatekeeperd.log");
    EXPECT_NE(log.find("audit " + job_id + " resumed from " + std::to_string(tiles_at_stop) + " finished tiles"), std::string::npos)
        << log;
  }
}

// A client's cancel sticks across a stop: a job cancelled while it waited in the queue (and one
// cancelled while running) ends CANCELLED after kill -9 and a restart; it is not resumed to DONE.
TEST(AuditE2E, ACancelledAuditStaysCancelledAcrossAKill) {
  const std::string dir = testing::temp_dir("audit-cancel-kill");
  std::string running, queued;
  {
    Daemon daemon(dir, {"--audit-jobs", "1"});
    auto stub = daemon.stub();
    const std::string scene_id = sphere_row(*stub, 12);
    pb::StartAuditRequest start;
    start.set_scene_id(scene_id);
    start.set_tile_mm(1500.0);
    start.set_threads(1);
    start.set_compute_depth(true);
    for (std::string* id : {&running, &queued}) {
      pb::AuditJob job;
      grpc::ClientContext sctx;
      ASSERT_TRUE(stub->StartAudit(&sctx, start, &job).ok());
      *id = job.job_id();
    }
    for (const std::string& id : {queued, running}) {
      pb::CancelAuditRequest cancel;
      cancel.set_job_id(id);
      pb::AuditProgress progress;
      grpc::ClientContext xctx;
      ASSERT_TRUE(stub->CancelAudit(&xctx, cancel, &progress).ok());
    }
    daemon.stop(SIGKILL);  // before either could end and be archived
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  for (const std::string& id : {queued, running}) {
    const pb::AuditReport report = report_when_ended(*stub, id);
    EXPECT_EQ(report.progress().state(), pb::CANCELLED) << id;
  }
  EXPECT_EQ(checkpointed_tiles(dir), 0);
}

TEST(AuditE2E, EndedAuditsSurviveKill9AndStayUsableAsBaselines) {
  const std::string dir = testing::temp_dir("audit-archive");
  std::string scene_id, job_id, crate_b;
  std::map<std::pair<std::string, std::string>, pb::Verdict> before;
  pb::StartAuditRequest start;
  {
    Daemon daemon(dir);
    auto stub = daemon.stub();
    // Crates in a row, each overlapping the next by 5 mm.
    const CubeScene made = cube_scene(*stub, "crate", 6, [](int i) { return Vec3(995.0 * i, 0, 0); });
    scene_id = made.scene_id;
    const pb::PutObjectsRequest& batch = made.batch;
    pb::PutObjectsResponse ids;
    grpc::ClientContext pctx;
    ASSERT_TRUE(stub->PutObjects(&pctx, batch, &ids).ok());
    crate_b = ids.object_ids(1);
    start.set_scene_id(scene_id);
    start.set_clearance_mm(1.0);
    const pb::AuditReport report = run_audit(*stub, start);
    ASSERT_EQ(report.progress().state(), pb::DONE);
    job_id = report.progress().job_id();
    before = clash_set(report);
    ASSERT_EQ(before.size(), 5u);
    EXPECT_EQ(daemon.stop(SIGKILL), -SIGKILL);
  }
  Daemon daemon(dir);
  auto stub = daemon.stub();
  grpc::ClientContext rctx;
  pb::GetAuditReportRequest get;
  get.set_job_id(job_id);
  get.set_html(true);
  pb::AuditReport kept;
  ASSERT_TRUE(stub->GetAuditReport(&rctx, get, &kept).ok());
  EXPECT_EQ(kept.progress().state(), pb::DONE);
  EXPECT_EQ(clash_set(kept), before);
  EXPECT_NE(kept.html().find("crate3"), std::string::npos);
  // The kept job is a baseline: move crate1 away, re-audit against it, compare with a fresh audit.
  grpc::ClientContext mctx;
  pb::MoveObjectRequest move;
  move.set_scene_id(scene_id);
  move.set_object_id(crate_b);
  *move.mutable_pose() = pose_of({"", "", "", "", Vec3(995.0, 5000, 0)});
  pb::MoveResult moved;
  ASSERT_TRUE(stub->MoveObject(&mctx, move, &moved).ok());
  pb::StartAuditRequest again = start;
  again.set_baseline_job_id(job_id);
  const pb::AuditReport incremental = run_audit(*stub, again);
  const pb::AuditReport fresh = run_audit(*stub, start);
  EXPECT_EQ(clash_set(incremental), clash_set(fresh));
  EXPECT_EQ(clash_set(fresh).size(), 3u);
  EXPECT_NE(incremental.progress().job_id(), job_id);  // new ids continue after the kept ones
  EXPECT_NE(fresh.progress().job_id(), job_id);
}

}  // namespace
}  // namespace gk
