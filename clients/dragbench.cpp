// gatekeeper-dragbench: a layout tool's drag through gatekeeperd, timed. It uploads a 1 m cube,
// fills a new scene with a grid of copies (one PutObjects batch; 2,000 mm apart along x, 2,060 mm
// between rows), then drags one more cube along the grid's rows through a DragObject stream,
// midway between two rows, so that every neighbour in both rows passes 30 mm away (inside the
// clearance), and prints the per-frame round trip and the daemon's
// own time per frame. With --mesh, a mesh file (in mm) takes the cube's place, for the static
// copies and the dragged one alike: rows of copies two box widths apart along x, the dragged copy
// midway between two rows with 30 mm between the boxes, swinging --weave mm either side (so it is
// driven into the rows' boxes and, where the meshes reach that far, into the meshes).
//
//   gatekeeper-dragbench --address 127.0.0.1:50051 [--objects 2000] [--frames 2000] [--clearance 50]
//                        [--mesh FILE] [--weave MM]
#include "clients/channel_options.h"
#include "clients/gatekeeper_client/upload.h"
#include "gatekeeper/v1/gatekeeper.grpc.pb.h"

#include <CLI/CLI.hpp>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace pb = ::gatekeeper::v1;
using Clock = std::chrono::steady_clock;

namespace {

// Rows of 1 m cubes this far apart leave 1,060 mm between them: a 1 m cube midway is 30 mm from both.
constexpr double kRowPitchMm = 2060.0;

std::string cube_obj() {
  std::string obj;
  for (int k = 0; k < 8; ++k)
    obj += std::string("v ") + ((k & 1) ? "500" : "-500") + ((k & 2) ? " 500" : " -500") + ((k & 4) ? " 1000\n" : " 0\n");
  return obj + "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n";
}


pb::Pose at(double x, double y) {
  pb::Pose p;
  p.mutable_translation()->set_x_mm(x);
  p.mutable_translation()->set_y_mm(y);
  return p;
}

double pct(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  gk::clients::ChannelOptions connection;
  int objects = 2000, frames = 2000;
  double clearance = 50.0;
  CLI::App app{"gatekeeper-dragbench: DragObject frame latency among many static objects"};
  connection.add_to(app);
  app.add_option("--objects", objects)->check(CLI::Range(1, 100000));
  app.add_option("--frames", frames)->check(CLI::Range(1, 1000000));
  app.add_option("--clearance", clearance)->check(CLI::Range(0.0, 1000.0));
  std::string mesh_path;
  double weave = 0.0;
  app.add_option("--mesh", mesh_path, "a mesh file (stl, obj, off, ply) in mm instead of the 1 m cube");
  app.add_option("--weave", weave, "the dragged object's swing either side of the row's midline [mm]")->check(CLI::Range(0.0, 1e5));
  CLI11_PARSE(app, argc, argv);
  std::shared_ptr<grpc::Channel> channel;
  try {
    channel = connection.open();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  if (!channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10))) {
    std::fprintf(stderr, "cannot connect to %s\n", connection.address.c_str());
    return 2;
  }
  auto stub = pb::Gatekeeper::NewStub(channel);
  std::string bytes = cube_obj();
  gk::client::UploadOptions upload_options;
  upload_options.format = "obj";
  if (!mesh_path.empty()) {
    std::ifstream in(mesh_path, std::ios::binary);
    std::ostringstream content;
    content << in.rdbuf();
    if (!in) {
      std::fprintf(stderr, "cannot read %s\n", mesh_path.c_str());
      return 2;
    }
    bytes = content.str();
    upload_options.format = gk::client::format_of(mesh_path);
  }
  pb::PartInfo cube;
  {
    const grpc::Status uploaded = gk::client::upload_part(*stub, bytes, upload_options, &cube);
    if (!uploaded.ok()) {
      std::fprintf(stderr, "upload: %s\n", uploaded.error_message().c_str());
      return 1;
    }
  }
  // Pitches from the part's box: copies two widths apart along x; rows so that a copy midway
  // between two has 30 mm to the boxes of both.
  const double width = cube.bounds_max().x_mm() - cube.bounds_min().x_mm();
  const double depth = cube.bounds_max().y_mm() - cube.bounds_min().y_mm();
  const double x_pitch = mesh_path.empty() ? 2000.0 : 2.0 * width;
  const double row_pitch = mesh_path.empty() ? kRowPitchMm : 2.0 * depth + 60.0;
  pb::SceneInfo scene;
  {
    grpc::ClientContext ctx;
    pb::CreateSceneRequest create;
    create.set_name("dragbench");
    if (!stub->CreateScene(&ctx, create, &scene).ok()) return 1;
  }
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(objects))));
  const auto t_fill = Clock::now();
  pb::PutObjectsRequest batch;
  batch.set_scene_id(scene.scene_id());
  for (int i = 0; i < objects; ++i) {
    pb::SceneObject* o = batch.add_objects();
    o->set_part_id(cube.part_id());
    o->set_category("cube");
    *o->mutable_pose() = at(x_pitch * (i % side), row_pitch * (i / side));
  }
  {
    grpc::ClientContext fill;
    pb::PutObjectsResponse ids;
    if (!stub->PutObjects(&fill, batch, &ids).ok()) return 1;
  }
  const double fill_s = std::chrono::duration<double>(Clock::now() - t_fill).count();
  std::string dragged;
  {
    grpc::ClientContext ctx;
    pb::PutObjectRequest put;
    put.set_scene_id(scene.scene_id());
    put.mutable_object()->set_part_id(cube.part_id());
    put.mutable_object()->set_name("dragged");
    *put.mutable_object()->mutable_pose() = at(-1.5 * x_pitch, 0.5 * row_pitch);
    pb::MoveResult r;
    if (!stub->PutObject(&ctx, put, &r).ok()) return 1;
    dragged = r.object_id();
  }
  grpc::ClientContext ctx;
  auto stream = stub->DragObject(&ctx);
  std::vector<double> round_trip_us, server_us;
  long contacts = 0, colliding_frames = 0;
  const double row_length = x_pitch * (side + 1);
  for (int f = 0; f < frames; ++f) {
    // Along a row, 40 mm per frame, then on to the next row.
    const double s = 40.0 * f;
    const int row = static_cast<int>(s / row_length) % std::max(1, side - 1);
    pb::MoveObjectRequest move;
    move.set_scene_id(scene.scene_id());
    move.set_object_id(dragged);
    move.set_clearance_mm(clearance);
    *move.mutable_pose() = at(-0.5 * x_pitch + std::fmod(s, row_length),
                              row_pitch * row + 0.5 * row_pitch + weave * std::sin(0.02 * f));
    const auto t0 = Clock::now();
    pb::MoveResult r;
    if (!stream->Write(move) || !stream->Read(&r)) break;
    round_trip_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    server_us.push_back(r.elapsed_us());
    contacts += r.contacts_size();
    if (r.verdict() == pb::VERDICT_COLLISION) ++colliding_frames;
  }
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  std::printf("%s: %u triangles\n", mesh_path.empty() ? "1 m cube" : mesh_path.c_str(), cube.triangles());
  std::printf("%d static objects (filled in %.1f s), %zu frames, clearance %.0f mm, %.2f contacts per frame\n", objects, fill_s,
              round_trip_us.size(), clearance, static_cast<double>(contacts) / static_cast<double>(std::max<std::size_t>(1, round_trip_us.size())));
  std::printf("frames answered COLLISION: %ld\n", colliding_frames);
  std::printf("round trip: p50 %.0f us, p90 %.0f us, p99 %.0f us, max %.0f us\n", pct(round_trip_us, 0.5), pct(round_trip_us, 0.9),
              pct(round_trip_us, 0.99), pct(round_trip_us, 1.0));
  std::printf("daemon (store + answer): p50 %.0f us, p90 %.0f us, p99 %.0f us, max %.0f us\n", pct(server_us, 0.5), pct(server_us, 0.9),
              pct(server_us, 0.99), pct(server_us, 1.0));
  return status.ok() && static_cast<int>(round_trip_us.size()) == frames ? 0 : 1;
}
