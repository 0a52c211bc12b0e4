// The audit's clashes as BCF 2.1 through what a user runs: the real daemon audits a scene, the
// real gatekeeper-cli writes the .bcfzip, Python's zipfile checks every entry's CRC and unpacks it,
// and xmllint validates every file against buildingSMART's own schemas (tests/data/bcf-2.1).
#include "clients/gatekeeper_client/bcf_export.h"
#include "clients/gatekeeper_client/zip_writer.h"
#include "tests/server/daemon_fixture.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <string>

namespace gk {
namespace {

namespace pb = ::gatekeeper::v1;
using testing::Daemon;

std::string run(const std::string& command) {
  std::string out;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return out;
  char buffer[4096];
  while (std::size_t n = fread(buffer, 1, sizeof buffer, pipe)) out.append(buffer, n);
  pclose(pipe);
  return out;
}

std::string put(pb::Gatekeeper::Stub& stub, const std::string& scene, const std::string& name, const std::string& category,
                const std::string& part, double x, double y, double z) {
  grpc::ClientContext ctx;
  pb::PutObjectRequest request;
  request.set_scene_id(scene);
  request.mutable_object()->set_name(name);
  request.mutable_object()->set_category(category);
  request.mutable_object()->set_part_id(part);
  request.mutable_object()->mutable_pose()->mutable_translation()->set_x_mm(x);
  request.mutable_object()->mutable_pose()->mutable_translation()->set_y_mm(y);
  request.mutable_object()->mutable_pose()->mutable_translation()->set_z_mm(z);
  pb::MoveResult moved;
  EXPECT_TRUE(stub.PutObject(&ctx, request, &moved).ok());
  return moved.object_id();
}

// Exports the job's report with the CLI, checks the archive and every file against the schemas;
// returns the topic Guid of each (object_a, object_b) pair as the markup files name them.
std::map<std::pair<std::string, std::string>, std::string> export_and_validate(const Daemon& daemon, const std::string& job,
                                                                               const std::string& tag, std::size_t clashes) {
  const std::string dir = testing::temp_dir(tag);
  const std::string file = dir + "/clashes.bcfzip";
  const std::string cli = run(std::string(GATEKEEPER_CLI_PATH) + " --address " + daemon.address() + " audit-report " + job +
                              " --bcf " + file + " > /dev/null");
  EXPECT_TRUE(std::filesystem::exists(file)) << cli;
  // Every entry's CRC, then the files.
  const std::string tested = run("python3 -m zipfile -t " + file);
  EXPECT_NE(tested.find("Done testing"), std::string::npos) << tested;
  EXPECT_EQ(tested.find("corrupted"), std::string::npos) << tested;
  EXPECT_EQ(run("python3 -m zipfile -e " + file + " " + dir + "/unzipped"), "");
  const std::string schemas = GATEKEEPER_BCF_SCHEMAS;
  const std::string root = dir + "/unzipped";
  EXPECT_NE(run("xmllint --noout --schema " + schemas + "/version.xsd " + root + "/bcf.version").find("validates"),
            std::string::npos);
  std::map<std::pair<std::string, std::string>, std::string> guids;
  std::size_t topics = 0;
  for (const auto& entry : std::filesystem::directory_iterator(root)) {
    if (!entry.is_directory()) continue;
    ++topics;
    const std::string topic = entry.path().string();
    const std::string markup = run("xmllint --noout --schema " + schemas + "/markup.xsd " + topic + "/markup.bcf");
    EXPECT_NE(markup.find("validates"), std::string::npos) << markup;
    const std::string view = run("xmllint --noout --schema " + schemas + "/visinfo.xsd " + topic + "/viewpoint.bcfv");
    EXPECT_NE(view.find("validates"), std::string::npos) << view;
    // The folder is the topic's Guid; the viewpoint selects both objects by their ids.
    const std::string text = testing::read_file(topic + "/markup.bcf");
    EXPECT_NE(text.find("Guid=\"" + entry.path().filename().string() + "\""), std::string::npos);
    const std::string viewpoint = testing::read_file(topic + "/viewpoint.bcfv");
    std::vector<std::string> ids;
    const std::regex tool_id("<AuthoringToolId>([^<]*)</AuthoringToolId>");
    for (auto it = std::sregex_iterator(viewpoint.begin(), viewpoint.end(), tool_id); it != std::sregex_iterator(); ++it)
      ids.push_back((*it)[1]);
    EXPECT_EQ(ids.size(), 2u);
    if (ids.size() == 2) guids[{ids[0], ids[1]}] = entry.path().filename().string();
  }
  EXPECT_EQ(topics, clashes);
  return guids;
}

TEST(BcfExportE2E, AnAuditsClashesExportAsBcfThatBuildingSmartsSchemasAcceptWithGuidsStableAcrossAudits) {
  Daemon daemon(testing::temp_dir("bcf"));
  auto stub = daemon.stub();
  const std::string column = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 400, 400, 8000), "obj");
  const std::string pipe = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 30000, 200, 200), "obj");
  const std::string crate = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 1000, 1000, 1000), "obj");
  grpc::ClientContext cctx;
  pb::CreateSceneRequest create;
  create.set_name("hall");
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->CreateScene(&cctx, create, &scene).ok());
  for (int i = 0; i < 4; ++i) put(*stub, scene.scene_id(), "column <" + std::to_string(i) + ">", "column", column, i * 8000.0, 0, 0);
  put(*stub, scene.scene_id(), "pipe & \"duct\"", "pipe", pipe, -1000, 100, 3000);  // crosses every column
  put(*stub, scene.scene_id(), "crate-a", "crate", crate, 2000, 3000, 0);
  put(*stub, scene.scene_id(), "crate-b", "crate", crate, 2995, 3000, 0);  // 5 mm into crate-a
  put(*stub, scene.scene_id(), "crate-c", "crate", crate, 4002, 3000, 0);  // 7 mm from crate-b
  pb::StartAuditRequest start;
  start.set_scene_id(scene.scene_id());
  start.set_clearance_mm(10.0);
  const pb::AuditReport first = testing::run_audit(*stub, start, false);
  ASSERT_EQ(first.progress().state(), pb::DONE);
  ASSERT_EQ(first.clashes_size(), 6);
  std::set<std::string> ids;
  for (const pb::Clash& c : first.clashes()) ids.insert(c.clash_id());
  EXPECT_EQ(ids.size(), 6u);

  const auto exported = export_and_validate(daemon, first.progress().job_id(), "bcf-first", 6);
  for (const pb::Clash& c : first.clashes()) {
    const auto it = exported.find({c.object_a(), c.object_b()});
    ASSERT_NE(it, exported.end()) << c.object_a() << " / " << c.object_b();
    EXPECT_EQ(it->second, c.clash_id());
  }
  // A second audit of the same scene: the same pairs, the same topic Guids.
  const pb::AuditReport second = testing::run_audit(*stub, start, false);
  ASSERT_EQ(second.clashes_size(), 6);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(second.clashes(i).clash_id(), first.clashes(i).clash_id());
  EXPECT_EQ(export_and_validate(daemon, second.progress().job_id(), "bcf-second", 6), exported);
}

pb::ClashStatus status_in(const pb::AuditReport& report, const std::string& clash_id) {
  for (const pb::Clash& c : report.clashes())
    if (c.clash_id() == clash_id) return c.status();
  return pb::CLASH_STATUS_UNSPECIFIED;
}

grpc::Status set_status(pb::Gatekeeper::Stub& stub, const std::string& scene, const std::string& clash, pb::ClashStatus status,
                        pb::ClashStatusInfo* out) {
  grpc::ClientContext ctx;
  pb::SetClashStatusRequest request;
  request.set_scene_id(scene);
  request.set_clash_id(clash);
  request.set_status(status);
  return stub.SetClashStatus(&ctx, request, out);
}

std::map<std::string, pb::ClashStatusInfo> listed(pb::Gatekeeper::Stub& stub, const std::string& scene) {
  grpc::ClientContext ctx;
  pb::ListClashStatusesRequest request;
  request.set_scene_id(scene);
  pb::ListClashStatusesResponse response;
  EXPECT_TRUE(stub.ListClashStatuses(&ctx, request, &response).ok());
  std::map<std::string, pb::ClashStatusInfo> out;
  for (const pb::ClashStatusInfo& s : response.statuses()) out[s.clash_id()] = s;
  return out;
}

void move_to(pb::Gatekeeper::Stub& stub, const std::string& scene, const std::string& object, double x, double y) {
  grpc::ClientContext ctx;
  pb::MoveObjectRequest move;
  move.set_scene_id(scene);
  move.set_object_id(object);
  move.mutable_pose()->mutable_translation()->set_x_mm(x);
  move.mutable_pose()->mutable_translation()->set_y_mm(y);
  pb::MoveResult moved;
  ASSERT_TRUE(stub.MoveObject(&ctx, move, &moved).ok());
}

// Review statuses as a clash tool keeps them: NEW when first found, ACTIVE when found again, a
// user's REVIEWED / APPROVED kept while found, RESOLVED when no longer found, ACTIVE again when
// it comes back; kept across a restart, and carried into the BCF topics' TopicStatus.
TEST(BcfExportE2E, ClashStatusesFollowThePairsAcrossAuditsRestartsAndIntoBcf) {
  const std::string data = testing::temp_dir("clash-status");
  auto daemon = std::make_unique<Daemon>(data);
  auto stub = daemon->stub();
  const std::string column = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 400, 400, 8000), "obj");
  const std::string pipe = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 30000, 200, 200), "obj");
  const std::string crate = testing::upload_part_id(*stub, testing::box_obj(0, 0, 0, 1000, 1000, 1000), "obj");
  grpc::ClientContext cctx;
  pb::CreateSceneRequest create;
  create.set_name("hall");
  pb::SceneInfo scene;
  ASSERT_TRUE(stub->CreateScene(&cctx, create, &scene).ok());
  const std::string id = scene.scene_id();
  std::vector<std::string> columns;
  for (int i = 0; i < 4; ++i) columns.push_back(put(*stub, id, "column" + std::to_string(i), "column", column, i * 8000.0, 0, 0));
  const std::string pipe_id = put(*stub, id, "pipe", "pipe", pipe, -1000, 100, 3000);
  const std::string a = put(*stub, id, "crate-a", "crate", crate, 2000, 3000, 0);
  const std::string b = put(*stub, id, "crate-b", "crate", crate, 2995, 3000, 0);
  const std::string c = put(*stub, id, "crate-c", "crate", crate, 4002, 3000, 0);
  pb::StartAuditRequest start;
  start.set_scene_id(id);
  start.set_clearance_mm(10.0);
  const pb::AuditReport first = testing::run_audit(*stub, start, false);
  ASSERT_EQ(first.clashes_size(), 6);
  for (const pb::Clash& k : first.clashes()) EXPECT_EQ(k.status(), pb::CLASH_NEW) << k.name_a() << " / " << k.name_b();
  const auto clash_of = [&](const pb::AuditReport& r, const std::string& x, const std::string& y) {
    for (const pb::Clash& k : r.clashes())
      if ((k.object_a() == x && k.object_b() == y) || (k.object_a() == y && k.object_b() == x)) return k.clash_id();
    return std::string();
  };
  const std::string pipe_column = clash_of(first, pipe_id, columns[0]);
  const std::string crates_ab = clash_of(first, a, b);
  const std::string crates_bc = clash_of(first, b, c);
  ASSERT_FALSE(pipe_column.empty());
  ASSERT_FALSE(crates_ab.empty());
  ASSERT_FALSE(crates_bc.empty());
  {
    const auto kept = listed(*stub, id);
    ASSERT_EQ(kept.size(), 6u);
    for (const auto& [k, s] : kept) {
      EXPECT_EQ(s.status(), pb::CLASH_NEW);
      EXPECT_EQ(s.first_job_id(), first.progress().job_id());
    }
  }
  pb::ClashStatusInfo info;
  ASSERT_TRUE(set_status(*stub, id, pipe_column, pb::CLASH_REVIEWED, &info).ok());
  EXPECT_TRUE(info.set_by_user());
  ASSERT_TRUE(set_status(*stub, id, crates_ab, pb::CLASH_APPROVED, &info).ok());
  // Refusals name the field: NEW is the audits' own; an unknown clash or scene is NOT_FOUND.
  grpc::Status refused = set_status(*stub, id, crates_ab, pb::CLASH_NEW, &info);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("status"), std::string::npos) << refused.error_message();
  refused = set_status(*stub, id, "00000000-0000-8000-8000-000000000000", pb::CLASH_REVIEWED, &info);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(refused.error_message().find("clash_id"), std::string::npos) << refused.error_message();
  refused = set_status(*stub, "no-such-scene", pipe_column, pb::CLASH_REVIEWED, &info);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::NOT_FOUND);

  // crate-c moved away: its clearance clash with crate-b is no longer found.
  move_to(*stub, id, c, 4002, 9000);
  const pb::AuditReport second = testing::run_audit(*stub, start, false);
  ASSERT_EQ(second.clashes_size(), 5);
  EXPECT_EQ(status_in(second, pipe_column), pb::CLASH_REVIEWED);
  EXPECT_EQ(status_in(second, crates_ab), pb::CLASH_APPROVED);
  for (const pb::Clash& k : second.clashes()) {
    if (k.clash_id() != pipe_column && k.clash_id() != crates_ab) {
      EXPECT_EQ(k.status(), pb::CLASH_ACTIVE) << k.name_a();
    }
  }
  EXPECT_EQ(listed(*stub, id).at(crates_bc).status(), pb::CLASH_RESOLVED);

  // Restarted: the statuses stay. crate-c back: its clash is found again, ACTIVE (reopened).
  daemon.reset();
  daemon = std::make_unique<Daemon>(data);
  stub = daemon->stub();
  EXPECT_EQ(listed(*stub, id).at(pipe_column).status(), pb::CLASH_REVIEWED);
  move_to(*stub, id, c, 4002, 3000);
  const pb::AuditReport third = testing::run_audit(*stub, start, false);
  ASSERT_EQ(third.clashes_size(), 6);
  EXPECT_EQ(status_in(third, crates_bc), pb::CLASH_ACTIVE);
  EXPECT_EQ(status_in(third, pipe_column), pb::CLASH_REVIEWED);
  EXPECT_EQ(listed(*stub, id).at(crates_bc).last_job_id(), third.progress().job_id());

  // The BCF topics carry them.
  std::string archive, error;
  ASSERT_TRUE(client::write_bcf(third, {}, &archive, &error)) << error;
  const std::string dir = testing::temp_dir("clash-status-bcf");
  std::ofstream(dir + "/c.bcfzip", std::ios::binary) << archive;
  EXPECT_EQ(run("python3 -m zipfile -e " + dir + "/c.bcfzip " + dir + "/u"), "");
  const auto topic_status = [&](const std::string& clash) {
    std::smatch m;
    const std::string text = testing::read_file(dir + "/u/" + clash + "/markup.bcf");
    return std::regex_search(text, m, std::regex("TopicStatus=\"([A-Za-z]+)\"")) ? std::string(m[1]) : std::string();
  };
  EXPECT_EQ(topic_status(pipe_column), "Reviewed");
  EXPECT_EQ(topic_status(crates_ab), "Approved");
  EXPECT_EQ(topic_status(crates_bc), "Active");
}

// A factory's audit can list more clashes than a plain zip counts (65,535 entries: 32,767 BCF
// topics): the archive then carries the zip64 end records, and Python's zipfile reads every entry.
TEST(BcfExport, AnArchiveOfMoreThan65535EntriesIsReadWhole) {
  client::ZipWriter zip(0x5B7B, 0);
  for (int i = 0; i < 70000; ++i) zip.add("topic-" + std::to_string(i) + "/markup.bcf", "<Markup>" + std::to_string(i) + "</Markup>");
  const std::string dir = testing::temp_dir("zip64");
  std::ofstream(dir + "/big.zip", std::ios::binary) << zip.finish();
  const std::string listed = run("python3 -c \"import zipfile,sys; z=zipfile.ZipFile(sys.argv[1]); print(len(z.namelist()), z.testzip(), "
                                 "z.read('topic-69999/markup.bcf').decode())\" " + dir + "/big.zip");
  EXPECT_EQ(listed, "70000 None <Markup>69999</Markup>\n");
}

// Names may hold U+FFFE or U+FFFF, which XML does not allow: the files stay valid (the
// replacement character instead).
TEST(BcfExport, NonCharactersInNamesLeaveValidXml) {
  pb::AuditReport report;
  pb::Clash* c = report.add_clashes();
  c->set_object_a("a");
  c->set_object_b("b");
  c->set_name_a("pipe \xEF\xBF\xBE end");
  c->set_category_a("duct \xEF\xBF\xBF");
  c->set_clash_id("0123abcd-0000-8000-8000-000000000001");
  c->set_verdict(pb::COLLISION);
  std::string archive, error;
  ASSERT_TRUE(client::write_bcf(report, {}, &archive, &error)) << error;
  const std::string dir = testing::temp_dir("bcf-nonchar");
  std::ofstream(dir + "/x.bcfzip", std::ios::binary) << archive;
  EXPECT_EQ(run("python3 -m zipfile -e " + dir + "/x.bcfzip " + dir + "/u"), "");
  const std::string markup = run("xmllint --noout --schema " + std::string(GATEKEEPER_BCF_SCHEMAS) + "/markup.xsd " + dir +
                                 "/u/0123abcd-0000-8000-8000-000000000001/markup.bcf");
  EXPECT_NE(markup.find("validates"), std::string::npos) << markup;
}

// A report without clash ids (an older daemon's) is refused rather than written with made-up Guids.
TEST(BcfExport, AReportWithoutClashIdsIsRefused) {
  pb::AuditReport report;
  pb::Clash* c = report.add_clashes();
  c->set_object_a("a");
  c->set_object_b("b");
  std::string archive, error;
  EXPECT_FALSE(client::write_bcf(report, {}, &archive, &error));
  EXPECT_NE(error.find("clash_id"), std::string::npos) << error;
}

}  // namespace
}  // namespace gk
