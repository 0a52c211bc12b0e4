// ClearanceQuery through the real daemon on loopback: two large real meshes uploaded, then one
// query per near-contact pose, each timed from the client (request built, sent, answer parsed).
//   build/tests/benchmarks/clearance_daemon_benchmark [passes]
// The poses are those of kernel_benchmark's Large_Clearance (gap uniform in [-1, 3] mm, found with
// the kernel in this process before the timing); the same answer computed in process is timed
// too, so the table shows what gRPC and the service add. Safety gap 1 mm, as there.
#include "kernel/measure/contact_regions.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/server/daemon_fixture.h"
#include "tests/support/near_contact_poses.h"
#include "tests/support/file_text.h"
#include "tests/support/random_meshes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

using gk::RigidTransform;
using gk::Vec3;
using Clock = std::chrono::steady_clock;
namespace pb = ::gatekeeper::v1;

struct Part {
  gk::TriangleMesh mesh;
  std::shared_ptr<gk::MeshBvh> bvh;
};

Part load(const std::string& relative, double scale) {
  auto read = gk::mesh_io::read_mesh_file(gk::testing::shared_data(relative));
  if (!read.ok()) {
    std::fprintf(stderr, "%s\n", read.error().to_string().c_str());
    std::exit(2);
  }
  Part p{std::move(read).value(), nullptr};
  if (scale != 1.0) {
    std::vector<Vec3> v = p.mesh.vertices();
    for (Vec3& x : v) x *= scale;
    (void)p.mesh.set_vertices(std::move(v));
  }
  p.bvh = gk::MeshBvh::build(gk::testing::share(p.mesh)).value();
  return p;
}

void to_proto(const RigidTransform& t, pb::Pose* out) {
  const Eigen::AngleAxisd aa(t.rotation);
  out->mutable_translation()->set_x_mm(t.translation.x());
  out->mutable_translation()->set_y_mm(t.translation.y());
  out->mutable_translation()->set_z_mm(t.translation.z());
  out->mutable_rotation_axis()->set_x_mm(aa.axis().x());
  out->mutable_rotation_axis()->set_y_mm(aa.axis().y());
  out->mutable_rotation_axis()->set_z_mm(aa.axis().z());
  out->set_rotation_deg(aa.angle() * 180.0 / 3.14159265358979323846);
}

// The pose as the daemon rebuilds it from the axis and angle (what the in-process run must use).
RigidTransform from_proto(const pb::Pose& p) {
  const Vec3 axis(p.rotation_axis().x_mm(), p.rotation_axis().y_mm(), p.rotation_axis().z_mm());
  const Vec3 t(p.translation().x_mm(), p.translation().y_mm(), p.translation().z_mm());
  return RigidTransform::from_axis_angle(axis, p.rotation_deg() * 3.14159265358979323846 / 180.0, t);
}

struct Row {
  std::vector<double> us;
  void print(const char* name) {
    std::sort(us.begin(), us.end());
    auto at = [&](double q) { return us[std::min(us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(us.size())))]; };
    std::printf("| %s | %zu | %.0f | %.0f | %.0f | %.0f | %.0f |\n", name, us.size(), at(0.1), at(0.5), at(0.9), at(0.99), us.back());
  }
};

}  // namespace

int main(int argc, char** argv) {
  const int passes = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  struct PairSpec {
    const char* name;
    const char* a;
    double scale_a;
    const char* b;
    double scale_b;
    unsigned seed;
  };
  const PairSpec pairs[] = {
      {"TR12J (67k) vs KUKA base (70k)", "meshes/occt/TR12J_OCC64K.stl", 1.0, "meshes/robots/kuka_kr10r1420/visual/base_link.stl",
       1000.0, 1000},
      {"fandisk (32k) vs TR12J (67k)", "meshes/cgal/fandisk_large.off", 100.0, "meshes/occt/TR12J_OCC64K.stl", 1.0, 1001},
  };
  gk::testing::Daemon daemon(gk::testing::temp_dir("clearance-bench"));
  auto stub = daemon.stub();
  std::printf("| pair, path | queries | p10 | median | p90 | p99 | max (us) |\n|---|---|---|---|---|---|---|\n");
  for (const PairSpec& spec : pairs) {
    const Part a = load(spec.a, spec.scale_a), b = load(spec.b, spec.scale_b);
    const std::string id_a = gk::testing::upload_part_id(*stub, gk::testing::obj_text(a.mesh), "obj");
    const std::string id_b = gk::testing::upload_part_id(*stub, gk::testing::obj_text(b.mesh), "obj");
    if (id_a.empty() || id_b.empty()) return 2;
    std::vector<pb::ClearanceQueryRequest> requests;
    for (const RigidTransform& pose : gk::testing::near_contact_poses(*a.bvh, *b.bvh, spec.seed, 100)) {
      pb::ClearanceQueryRequest r;
      r.mutable_a()->set_part_id(id_a);
      r.mutable_b()->set_part_id(id_b);
      to_proto(pose, r.mutable_b()->mutable_pose());
      r.set_safety_gap_mm(1.0);
      requests.push_back(r);
    }
    // One untimed pass: the daemon's first touch of each part (page faults, caches).
    for (const auto& r : requests) {
      grpc::ClientContext ctx;
      pb::ClearanceQueryResponse out;
      (void)stub->ClearanceQuery(&ctx, r, &out);
    }
    Row daemon_row, in_process_row;
    int verdicts[4] = {0, 0, 0, 0};
    for (int p = 0; p < passes; ++p) {
      for (const auto& r : requests) {
        const auto t0 = Clock::now();
        grpc::ClientContext ctx;
        pb::ClearanceQueryResponse out;
        const grpc::Status status = stub->ClearanceQuery(&ctx, r, &out);
        daemon_row.us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        if (!status.ok()) {
          std::fprintf(stderr, "ClearanceQuery: %s\n", status.error_message().c_str());
          return 1;
        }
        if (p == 0) ++verdicts[std::clamp(static_cast<int>(out.verdict()) - 1, 0, 3)];
      }
      for (const auto& r : requests) {
        const RigidTransform pose = from_proto(r.b().pose());
        const auto t0 = Clock::now();
        const auto v = gk::assess(*a.bvh, RigidTransform{}, *b.bvh, pose).value();
        const auto near = gk::pairs_within(*a.bvh, RigidTransform{}, *b.bvh, pose, 1.0, 100000).value();
        const auto regions = gk::group_into_regions(near.pairs, 10.0);
        in_process_row.us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        if (regions.size() > near.pairs.size() + 1 || v.distance_mm < -1.0) return 3;  // keeps the work observable
      }
    }
    const std::string daemon_name = std::string(spec.name) + ", gRPC ClearanceQuery";
    const std::string process_name = std::string(spec.name) + ", in process (kernel only)";
    daemon_row.print(daemon_name.c_str());
    in_process_row.print(process_name.c_str());
    std::printf("|   verdicts of the 100 poses: CLEAR %d, TOUCHING %d, COLLISION %d, INCONCLUSIVE %d | | | | | | |\n", verdicts[0],
                verdicts[1], verdicts[2], verdicts[3]);
  }
  return 0;
}
