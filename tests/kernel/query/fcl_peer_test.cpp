// FCL 0.7 as a peer on FCL's own env/rob benchmark (test_fcl_collision mesh_mesh,
// test_fcl_distance mesh_distance): env.obj posed relative to rob.obj at identity.
//
// Both libraries get the same vertices and faces (read once with read_mesh_file, merging on), so
// FCL's contact b1/b2 (triangle indices in addSubModel order) are our triangle ids. For each pose:
//   (a) collision boolean: gk::collide vs fcl::collide (all contacts, enable_contact = true);
//   (b) the set of intersecting triangle pairs: ours vs FCL's (o1 = env, o2 = rob);
//   (c) distance: gk::distance vs fcl::distance, within 1e-6 mm, when neither reports a collision.
// Where the two disagree, the all-pairs oracle (brute_force_contacts / brute_force_distance)
// decides; the test fails only when OURS differs from brute force. FCL's triangle test is floating
// point (not exact), so touching configurations may differ: those are counted and printed. Ours is
// also checked against brute force on every TSV pose and every 10th random pose.
// Beyond FCL's procedure (20 TSV poses + 200 random poses), two extra sets probe contact at the
// limit: touching / nearly touching poses (exact axis-aligned contacts, gaps of 1e-3..1e-12 mm) and
// grazing poses (a rob vertex on env's floor up to rounding); brute force runs on every one of them.
// Runtime (Release): about 6 s in all, most of it brute force (~470k triangle pairs a pose).
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/query/triangle_distance.h"
#include "kernel/mesh/triangle_mesh.h"
#include "mesh_io/mesh_file_reader.h"
#include "tests/support/brute_force.h"
#include "tests/support/random_meshes.h"
#include "tests/support/sanitized_build.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>
#include <fcl/narrowphase/distance.h>
#include <fcl/narrowphase/distance_request.h>
#include <fcl/narrowphase/distance_result.h>

#include "tests/support/fcl_peer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace gk {
namespace {

using testing::PairSet;
using testing::shared_data;

using testing::FclModel;
using testing::make_fcl_model;
using testing::to_fcl;

// Far more than the ~470k triangle pairs env x rob has: FCL never truncates the contact list.
constexpr std::size_t kFclMaxContacts = 10'000'000;

// (c) Ours vs FCL distance when both say non-colliding. [mm]
constexpr double kPeerDistanceToleranceMm = 1e-6;
// Ours vs brute force: the same triangle_distance on the same coordinates in the same frame, so
// only the order in which the minimum is taken differs; 1e-9 mm is far above any rounding there. [mm]
constexpr double kOracleDistanceToleranceMm = 1e-9;
// A witness point lies on its triangle / the witnesses are distance apart, after one rigid transform
// of coordinates up to ~5000 mm (rounding ~1e-12 mm); 1e-8 mm. [mm]
constexpr double kWitnessToleranceMm = 1e-8;

struct Models {
  std::shared_ptr<const TriangleMesh> env_mesh, rob_mesh;
  std::shared_ptr<MeshBvh> env_bvh, rob_bvh;
  std::shared_ptr<FclModel> env_fcl, rob_fcl;
};

struct LabeledPose {
  std::string label;
  RigidTransform env_pose;  // rob is at identity
};

// derived/fcl_env_rob_transforms.tsv: set idx x y z a b c R00..R22 (row-major).
std::vector<LabeledPose> read_tsv_poses(const std::string& path, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = "cannot open " + path;
    return {};
  }
  std::vector<LabeledPose> poses;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("set\t", 0) == 0) continue;
    std::istringstream row(line);
    std::string set;
    int idx = 0;
    double x, y, z, a, b, c;
    RigidTransform pose;
    row >> set >> idx >> x >> y >> z >> a >> b >> c;
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) row >> pose.rotation(r, col);
    if (!row) {
      error = "malformed row in " + path + ": " + line;
      return {};
    }
    pose.translation = Vec3(x, y, z);
    poses.push_back({"tsv " + set + "[" + std::to_string(idx) + "]", pose});
  }
  return poses;
}

// Touching poses (extra to FCL's procedure): only axis-aligned rotations (and Rz(30)), so every coordinate
// below is exact and the contacts are truly touching. env: floor top at z = -5.5 spanning
// x,y in [-2987.5, 2987.5]; an open room x in [1004.5, 2987.5] with a wall x in [995.5, 1004.5]
// (z in [12.5, 987.5]). rob: z in [-425, 425] (leg bottoms at -425), table top x in [-500, 500].
std::vector<LabeledPose> touching_poses() {
  const Mat3 rz90 = (Mat3() << 0, -1, 0, 1, 0, 0, 0, 0, 1).finished();
  const Mat3 rz30 = Eigen::AngleAxisd(3.14159265358979323846 / 6.0, Vec3::UnitZ()).toRotationMatrix();
  std::vector<LabeledPose> poses;
  auto add = [&](const std::string& label, const Mat3& r, const Vec3& t) { poses.push_back({"touch " + label, {r, t}}); };
  add("legs on floor", Mat3::Identity(), Vec3(-2000, 0, -419.5));
  add("legs on floor, rotated 90", rz90, Vec3(0, -2000, -419.5));
  // Rz has an exact z row, so the floor stays exactly at z = -425 in rob's frame.
  add("legs on floor, rotated 30", rz30, -(rz30 * Vec3(2000, 0, 0)) + Vec3(0, 0, -419.5));
  add("table side on wall", Mat3::Identity(), Vec3(-1504.5, 0, -500));
  add("table side on wall, legs on floor", Mat3::Identity(), Vec3(-1504.5, 0, -419.5));
  add("leg half over floor edge", Mat3::Identity(), Vec3(450 - 2987.5, 0, -419.5));
  add("leg edge on floor edge", Mat3::Identity(), Vec3(430 - 2987.5, 0, -419.5));
  add("floor 1e-3 below legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 - 1e-3));
  add("floor 1e-3 into legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 + 1e-3));
  // Nearly touching: a gap or an overlap of ~1e-9 and ~1e-12 mm (the rounded literals are what counts).
  add("floor 1e-9 below legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 - 1e-9));
  add("floor 1e-9 into legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 + 1e-9));
  add("floor 1e-12 below legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 - 1e-12));
  add("floor 1e-12 into legs", Mat3::Identity(), Vec3(-2000, 0, -419.5 + 1e-12));
  add("table side 1e-9 off wall", Mat3::Identity(), Vec3(-1504.5 - 1e-9, 0, -500));
  add("table side 1e-9 into wall", Mat3::Identity(), Vec3(-1504.5 + 1e-9, 0, -500));
  add("legs on floor, rotated 30, floor 1e-12 below", rz30, -(rz30 * Vec3(2000, 0, 0)) + Vec3(0, 0, -419.5 - 1e-12));
  return poses;
}

// Grazing poses (extra to FCL's procedure): a random rotation of env, translated so that the point
// (2000, 0, -5.5) of env's floor top lands on rob's extreme vertex in the direction away from the
// floor. Rob then rests on the floor on one vertex, up to the rounding of the transform (~1e-13 mm):
// whether that vertex pair touches, crosses or misses is decided by the rounded coordinates.
std::vector<LabeledPose> grazing_poses(const TriangleMesh& rob) {
  testing::Rng rng(0x67726178ULL);  // fixed seed
  std::vector<LabeledPose> poses;
  for (int i = 0; i < 24; ++i) {
    const Mat3 r = testing::random_pose(rng, 0.0).rotation;
    const Vec3 n = r.col(2);  // env's floor normal in rob's frame
    Vec3 support = rob.vertices().front();
    for (const Vec3& v : rob.vertices())
      if (n.dot(v) < n.dot(support)) support = v;
    poses.push_back({"graze[" + std::to_string(i) + "]", {r, support - r * Vec3(2000, 0, -5.5)}});
  }
  return poses;
}

std::vector<LabeledPose> random_poses() {
  testing::Rng rng(0x46434c70656572ULL);  // fixed seed
  std::vector<LabeledPose> poses;
  for (int i = 0; i < 200; ++i) poses.push_back({"random[" + std::to_string(i) + "]", testing::random_pose(rng, 3000.0)});
  return poses;
}

std::string describe(const PairSet& pairs, std::size_t limit = 8) {
  std::ostringstream s;
  s << "{";
  std::size_t n = 0;
  for (const auto& [a, b] : pairs) {
    if (n == limit) {
      s << " ... (" << pairs.size() << " in all)";
      break;
    }
    s << (n++ ? ", " : "") << "(" << a << "," << b << ")";
  }
  s << "}";
  return s.str();
}

PairSet difference(const PairSet& x, const PairSet& y) {
  PairSet out;
  std::set_difference(x.begin(), x.end(), y.begin(), y.end(), std::inserter(out, out.end()));
  return out;
}

const char* verdict(bool ours_right, bool fcl_right) {
  if (ours_right && fcl_right) return "both right";
  if (ours_right) return "OURS right, FCL wrong";
  if (fcl_right) return "FCL right, OURS WRONG";
  return "NEITHER right (OURS WRONG)";
}

struct Stats {
  int poses = 0;
  int ours_colliding = 0;
  int fcl_colliding = 0;
  int bool_disagreements = 0, bool_ours_right = 0, bool_fcl_right = 0;
  int pair_disagreements = 0, pair_ours_right = 0, pair_fcl_right = 0;
  int distance_compared = 0, distance_disagreements = 0, distance_ours_right = 0, distance_fcl_right = 0;
  double max_distance_difference = 0.0;  // over poses both call non-colliding [mm]
  double min_distance_compared = std::numeric_limits<double>::infinity();
  int oracle_contact_checks = 0, oracle_distance_checks = 0;
  long long ours_pairs_total = 0, fcl_pairs_total = 0;

  void print(const std::string& name) const {
    std::cout << "[ FCL peer ] " << name << ": " << poses << " poses; colliding ours " << ours_colliding << ", FCL "
              << fcl_colliding << "; pairs ours " << ours_pairs_total << ", FCL " << fcl_pairs_total
              << "\n[ FCL peer ]   collision boolean disagreements: " << bool_disagreements << " (ours right "
              << bool_ours_right << ", FCL right " << bool_fcl_right << ")"
              << "\n[ FCL peer ]   contact pair-set disagreements: " << pair_disagreements << " (ours right "
              << pair_ours_right << ", FCL right " << pair_fcl_right << ")"
              << "\n[ FCL peer ]   distance: " << distance_compared << " compared, " << distance_disagreements
              << " beyond " << kPeerDistanceToleranceMm << " mm (ours right " << distance_ours_right << ", FCL right "
              << distance_fcl_right << "), max |ours - FCL| " << max_distance_difference << " mm, smallest distance "
              << min_distance_compared << " mm"
              << "\n[ FCL peer ]   brute-force checks: contacts " << oracle_contact_checks << ", distance "
              << oracle_distance_checks << std::endl;
    ::testing::Test::RecordProperty("poses", poses);
    ::testing::Test::RecordProperty("fcl_bool_disagreements", bool_disagreements);
    ::testing::Test::RecordProperty("fcl_bool_disagreements_ours_right", bool_ours_right);
    ::testing::Test::RecordProperty("fcl_pair_disagreements", pair_disagreements);
    ::testing::Test::RecordProperty("fcl_pair_disagreements_ours_right", pair_ours_right);
    ::testing::Test::RecordProperty("fcl_distance_disagreements", distance_disagreements);
    ::testing::Test::RecordProperty("fcl_distance_disagreements_ours_right", distance_ours_right);
  }
};

class FclPeerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (models_) return;
    auto load = [](const char* relative, std::shared_ptr<const TriangleMesh>& mesh,
                   std::shared_ptr<MeshBvh>& bvh) -> std::string {
      auto read = mesh_io::read_mesh_file(shared_data(relative));  // merge_identical_vertices on (default)
      if (!read.ok()) return read.error().to_string();
      mesh = testing::share(std::move(read).value());
      auto built = MeshBvh::build(mesh);
      if (!built.ok()) return built.error().to_string();
      bvh = built.value();
      return {};
    };
    auto m = std::make_unique<Models>();
    load_error_ = load("meshes/fcl/env.obj", m->env_mesh, m->env_bvh);
    if (load_error_.empty()) load_error_ = load("meshes/fcl/rob.obj", m->rob_mesh, m->rob_bvh);
    if (!load_error_.empty()) return;
    m->env_fcl = make_fcl_model(*m->env_mesh);
    m->rob_fcl = make_fcl_model(*m->rob_mesh);
    models_ = std::move(m);
  }

  void SetUp() override { ASSERT_TRUE(models_ != nullptr) << "loading env/rob failed: " << load_error_; }

  // Compares ours, FCL and (when needed or sampled) brute force on one pose.
  static void compare_pose(const LabeledPose& p, bool sample, Stats& stats) {
    const Models& m = *models_;
    const RigidTransform rob_pose = RigidTransform::identity();
    SCOPED_TRACE(p.label);
    ++stats.poses;

    // --- Ours: all contacts.
    CollisionRequest request;
    request.all_contacts = true;
    const auto ours = collide(*m.env_bvh, p.env_pose, *m.rob_bvh, rob_pose, request);
    ASSERT_TRUE(ours.ok()) << ours.error().to_string();
    const CollisionResult& oc = ours.value();
    EXPECT_FALSE(oc.truncated);
    EXPECT_EQ(oc.colliding, !oc.contacts.empty());
    PairSet ours_pairs;
    for (const Contact& c : oc.contacts) ours_pairs.insert({c.triangle_a, c.triangle_b});
    EXPECT_EQ(ours_pairs.size(), oc.contacts.size()) << "a triangle pair reported twice";

    // --- FCL: all contacts, env = o1, rob = o2.
    const fcl::CollisionObjectd env_obj(m.env_fcl, to_fcl(p.env_pose));
    const fcl::CollisionObjectd rob_obj(m.rob_fcl, fcl::Transform3d::Identity());
    const fcl::CollisionRequestd fcl_request(kFclMaxContacts, /*enable_contact=*/true);
    fcl::CollisionResultd fcl_result;
    fcl::collide(&env_obj, &rob_obj, fcl_request, fcl_result);
    const bool fcl_colliding = fcl_result.isCollision();
    std::vector<fcl::Contactd> fcl_contacts;
    fcl_result.getContacts(fcl_contacts);
    ASSERT_LT(fcl_contacts.size(), kFclMaxContacts);
    PairSet fcl_pairs;  // FCL may add up to two contact points for one triangle pair: a set
    for (const fcl::Contactd& c : fcl_contacts) {
      ASSERT_EQ(c.o1, static_cast<const fcl::CollisionGeometryd*>(m.env_fcl.get()));
      ASSERT_EQ(c.o2, static_cast<const fcl::CollisionGeometryd*>(m.rob_fcl.get()));
      fcl_pairs.insert({static_cast<std::uint32_t>(c.b1), static_cast<std::uint32_t>(c.b2)});
    }

    stats.ours_colliding += oc.colliding;
    stats.fcl_colliding += fcl_colliding;
    stats.ours_pairs_total += static_cast<long long>(ours_pairs.size());
    stats.fcl_pairs_total += static_cast<long long>(fcl_pairs.size());

    // --- Brute force decides disagreements, and checks ours on the sampled poses.
    const bool bool_agree = oc.colliding == fcl_colliding;
    const bool pairs_agree = ours_pairs == fcl_pairs;
    if (!bool_agree || !pairs_agree || sample) {
      ++stats.oracle_contact_checks;
      const PairSet oracle = testing::brute_force_contacts(*m.env_mesh, p.env_pose, *m.rob_mesh, rob_pose);
      EXPECT_EQ(ours_pairs, oracle) << "OURS differs from brute force: ours-only " << describe(difference(ours_pairs, oracle))
                                    << ", brute-force-only " << describe(difference(oracle, ours_pairs));
      const bool oracle_colliding = !oracle.empty();
      if (!bool_agree) {
        ++stats.bool_disagreements;
        const bool ours_right = oc.colliding == oracle_colliding, fcl_right = fcl_colliding == oracle_colliding;
        stats.bool_ours_right += ours_right;
        stats.bool_fcl_right += fcl_right;
        std::cout << "[ FCL diff ] " << p.label << ": collision ours=" << oc.colliding << " FCL=" << fcl_colliding
                  << " brute force=" << oracle_colliding << " -> " << verdict(ours_right, fcl_right) << std::endl;
      }
      if (!pairs_agree) {
        ++stats.pair_disagreements;
        const bool ours_right = ours_pairs == oracle, fcl_right = fcl_pairs == oracle;
        stats.pair_ours_right += ours_right;
        stats.pair_fcl_right += fcl_right;
        std::cout << "[ FCL diff ] " << p.label << ": contact pairs ours=" << ours_pairs.size()
                  << " FCL=" << fcl_pairs.size() << " brute force=" << oracle.size() << "; FCL missed "
                  << describe(difference(oracle, fcl_pairs)) << ", FCL extra " << describe(difference(fcl_pairs, oracle))
                  << " -> " << verdict(ours_right, fcl_right) << std::endl;
      }
    }

    // --- Distance.
    const auto ours_distance = distance(*m.env_bvh, p.env_pose, *m.rob_bvh, rob_pose);
    ASSERT_TRUE(ours_distance.ok()) << ours_distance.error().to_string();
    const DistanceResult& od = ours_distance.value();
    ASSERT_TRUE(od.found);
    // Ours is 0 exactly when ours collides: both rest on the same exact intersection decision.
    if (oc.colliding) {
      EXPECT_EQ(od.distance_mm, 0.0);
    } else {
      EXPECT_GT(od.distance_mm, 0.0);
    }
    // Witnesses: on their triangles, and distance_mm apart (tolerance kWitnessToleranceMm).
    {
      const Triangle ta = m.env_mesh->triangle(od.triangle_a);
      const Triangle ta_world = {p.env_pose.apply(ta[0]), p.env_pose.apply(ta[1]), p.env_pose.apply(ta[2])};
      const Triangle tb_world = m.rob_mesh->triangle(od.triangle_b);  // rob at identity
      EXPECT_NEAR((closest_point_on_triangle(od.point_a, ta_world) - od.point_a).norm(), 0.0, kWitnessToleranceMm);
      EXPECT_NEAR((closest_point_on_triangle(od.point_b, tb_world) - od.point_b).norm(), 0.0, kWitnessToleranceMm);
      EXPECT_NEAR((od.point_a - od.point_b).norm(), od.distance_mm, kWitnessToleranceMm);
    }

    const fcl::DistanceRequestd fcl_distance_request(/*enable_nearest_points=*/true);
    fcl::DistanceResultd fcl_distance_result;
    fcl::distance(&env_obj, &rob_obj, fcl_distance_request, fcl_distance_result);
    const double fcl_d = fcl_distance_result.min_distance;

    std::optional<double> oracle_d;
    auto oracle_distance = [&]() {
      if (!oracle_d) {
        ++stats.oracle_distance_checks;
        oracle_d = testing::brute_force_distance(*m.env_mesh, p.env_pose, *m.rob_mesh, rob_pose);
      }
      return *oracle_d;
    };
    if (!oc.colliding && !fcl_colliding) {
      ++stats.distance_compared;
      const double diff = std::fabs(od.distance_mm - fcl_d);
      stats.max_distance_difference = std::max(stats.max_distance_difference, diff);
      stats.min_distance_compared = std::min(stats.min_distance_compared, od.distance_mm);
      if (!(diff <= kPeerDistanceToleranceMm)) {
        ++stats.distance_disagreements;
        const double truth = oracle_distance();
        const bool ours_right = std::fabs(od.distance_mm - truth) <= kOracleDistanceToleranceMm;
        const bool fcl_right = std::fabs(fcl_d - truth) <= kPeerDistanceToleranceMm;
        stats.distance_ours_right += ours_right;
        stats.distance_fcl_right += fcl_right;
        std::cout.precision(17);
        std::cout << "[ FCL diff ] " << p.label << ": distance ours=" << od.distance_mm << " FCL=" << fcl_d
                  << " brute force=" << truth << " -> " << verdict(ours_right, fcl_right) << std::endl;
        std::cout.precision(6);
      }
    }
    if (sample) oracle_distance();
    if (oracle_d) {
      // Ours equals brute force (tolerance kOracleDistanceToleranceMm = 1e-9 mm).
      EXPECT_NEAR(od.distance_mm, *oracle_d, kOracleDistanceToleranceMm) << "OURS differs from brute-force distance";
    }
  }

  static void run(const std::vector<LabeledPose>& poses, int sample_every, const std::string& name) {
    const auto start = std::chrono::steady_clock::now();
    Stats stats;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      compare_pose(poses[i], sample_every > 0 && i % static_cast<std::size_t>(sample_every * testing::kSampleDivisor) == 0, stats);
      if (::testing::Test::HasFatalFailure()) return;
    }
    stats.print(name);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "[ FCL peer ]   " << name << " took " << seconds << " s" << std::endl;
  }

  static std::unique_ptr<Models> models_;
  static std::string load_error_;
};

std::unique_ptr<Models> FclPeerTest::models_;
std::string FclPeerTest::load_error_;

TEST_F(FclPeerTest, SameMeshesInBothLibraries) {
  const Models& m = *models_;
  EXPECT_EQ(m.env_mesh->triangle_count(), 2180u);  // MANIFEST
  EXPECT_EQ(m.rob_mesh->triangle_count(), 216u);
  EXPECT_EQ(static_cast<std::size_t>(m.env_fcl->num_tris), m.env_mesh->triangle_count());
  EXPECT_EQ(static_cast<std::size_t>(m.rob_fcl->num_tris), m.rob_mesh->triangle_count());
  EXPECT_EQ(static_cast<std::size_t>(m.env_fcl->num_vertices), m.env_mesh->vertices().size());
  EXPECT_EQ(static_cast<std::size_t>(m.rob_fcl->num_vertices), m.rob_mesh->vertices().size());
  // FCL keeps the triangle order: triangle k of FCL's model is our triangle k.
  for (std::size_t k = 0; k < m.env_mesh->triangle_count(); ++k) {
    const fcl::Triangle& t = m.env_fcl->tri_indices[k];
    const auto& f = m.env_mesh->faces()[k];
    ASSERT_TRUE(t[0] == f[0] && t[1] == f[1] && t[2] == f[2]) << "triangle " << k;
  }
  // The brute-force oracle requires non-degenerate triangles.
  EXPECT_FALSE(m.env_mesh->has_degenerate_triangles());
  EXPECT_FALSE(m.rob_mesh->has_degenerate_triangles());
}

TEST_F(FclPeerTest, TsvPosesFromFclTests) {
  std::string error;
  const auto poses = read_tsv_poses(shared_data("derived/fcl_env_rob_transforms.tsv"), error);
  ASSERT_TRUE(error.empty()) << error;
  ASSERT_EQ(poses.size(), 20u);
  for (const auto& p : poses) ASSERT_TRUE(p.env_pose.is_rigid()) << p.label;
  run(poses, /*sample_every=*/1, "20 TSV poses");
}

TEST_F(FclPeerTest, RandomPoses) {
  run(random_poses(), /*sample_every=*/10, "200 random poses (+-3000 mm, uniform rotation)");
}

TEST_F(FclPeerTest, TouchingAndNearlyTouchingPoses) {
  run(touching_poses(), /*sample_every=*/1, "touching and nearly touching poses");
}

TEST_F(FclPeerTest, GrazingVertexOnFloorPoses) {
  run(grazing_poses(*models_->rob_mesh), /*sample_every=*/1, "grazing vertex-on-floor poses");
}

}  // namespace
}  // namespace gk
