// The exact shared volume (issue: geometry truth §6) against an integer oracle: boxes and a
// U-channel on a grid of 2^-10 mm, where every overlap is a sum of products of integers; at the
// origin and 5e4 mm away, the offset in the file or in the pose; many faces shared on purpose.
#include "kernel/measure/exact_interference_volume.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/bvh/mesh_bvh.h"
#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>

namespace gk {
namespace {

constexpr double kUnit = 1.0 / 1024.0;  // mm: every coordinate below is a multiple of it
constexpr std::int64_t kFactory = 50000 * 1024;

struct IntBox {
  std::array<std::int64_t, 3> lo, hi;  // in units
};

// The overlap of two boxes in cubic units, exactly (sides below 2^16 units: products fit).
std::int64_t overlap_units(const IntBox& a, const IntBox& b) {
  std::int64_t v = 1;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t len = std::min(a.hi[i], b.hi[i]) - std::max(a.lo[i], b.lo[i]);
    if (len <= 0) return 0;
    v *= len;
  }
  return v;
}

double to_mm3(std::int64_t units) { return std::ldexp(static_cast<double>(units), -30); }

Vec3 mm(const std::array<std::int64_t, 3>& u, std::int64_t shift) {
  return Vec3(static_cast<double>(u[0] + shift), static_cast<double>(u[1]), static_cast<double>(u[2])) * kUnit;
}

// The exact figure lies within its bound of the oracle (rounded once to double itself).
void expect_exact(const ExactVolume& got, double oracle_mm3) {
  EXPECT_LE(std::fabs(got.volume_mm3 - oracle_mm3), got.error_bound_mm3 + std::fabs(oracle_mm3) * 0x1p-52)
      << "got " << got.volume_mm3 << " oracle " << oracle_mm3;
  EXPECT_LE(got.error_bound_mm3, std::fabs(oracle_mm3) * 0x1p-50 + 1e-300);
}

TEST(ExactInterferenceVolume, BoxesSharingFacesEdgesAndCornersMatchTheIntegerOracle) {
  testing::Rng rng(20261123);
  // Coordinates from a few values: shared faces, edges and corners in most draws.
  const std::int64_t values[] = {0, 1, 3, 1024, 1025, 2048, 4096, 5000};
  std::uniform_int_distribution<int> pick(0, 7);
  int overlapping = 0, touching = 0;
  for (int trial = 0; trial < 120; ++trial) {
    IntBox a{}, b{};
    for (int i = 0; i < 3; ++i) {
      for (IntBox* box : {&a, &b}) {
        std::int64_t p = values[pick(rng)], q = values[pick(rng)];
        while (p == q) q = values[pick(rng)];
        box->lo[i] = std::min(p, q);
        box->hi[i] = std::max(p, q);
      }
    }
    const std::int64_t oracle = overlap_units(a, b);
    (oracle > 0 ? overlapping : touching) += 1;
    // Near the origin; at 5e4 mm in the file; at 5e4 mm by the pose.
    const std::int64_t shifts[] = {0, kFactory, 0};
    for (int where = 0; where < 3; ++where) {
      const TriangleMesh ma = testing::box_mesh(mm(a.lo, shifts[where]), mm(a.hi, shifts[where]));
      const TriangleMesh mb = testing::box_mesh(mm(b.lo, shifts[where]), mm(b.hi, shifts[where]));
      const RigidTransform pose = where == 2 ? RigidTransform::from_translation(Vec3(50000, 0, 0)) : RigidTransform{};
      SCOPED_TRACE("trial " + std::to_string(trial) + " where " + std::to_string(where));
      auto got = exact_interference_volume(ma, pose, mb, pose);
      ASSERT_TRUE(got.ok()) << got.error().to_string();
      expect_exact(got.value(), to_mm3(oracle));
    }
  }
  EXPECT_GT(overlapping, 20);
  EXPECT_GT(touching, 20);
}

TEST(ExactInterferenceVolume, AUChannelAgainstBoxesIsTheSumOverItsThreeBoxes) {
  // The channel is the union of three boxes with disjoint interiors (mm -> units: x 1024).
  const IntBox parts[] = {{{0, 0, 0}, {10240, 2048, 20480}}, {{0, 2048, 0}, {2048, 10240, 20480}},
                          {{8192, 2048, 0}, {10240, 10240, 20480}}};
  const TriangleMesh channel = testing::u_channel_mesh();
  testing::Rng rng(7);
  std::uniform_int_distribution<std::int64_t> coord(-2048, 12288);
  for (int trial = 0; trial < 60; ++trial) {
    IntBox b{};
    for (int i = 0; i < 3; ++i) {
      const std::int64_t p = coord(rng), q = p + 1 + coord(rng) / 2 + 2048;
      b.lo[i] = p;
      b.hi[i] = q;
    }
    if (trial % 3 == 0) {  // flush with the slot's wall
      b.lo[0] = 2048;
      b.hi[0] = std::max(b.hi[0], b.lo[0] + 1024);
    }
    std::int64_t oracle = 0;
    for (const IntBox& part : parts) oracle += overlap_units(part, b);
    auto got = exact_interference_volume(channel, {}, testing::box_mesh(mm(b.lo, 0), mm(b.hi, 0)), {});
    ASSERT_TRUE(got.ok()) << got.error().to_string();
    SCOPED_TRACE("trial " + std::to_string(trial) + " box " + std::to_string(b.lo[0]) + " " + std::to_string(b.lo[1]) + " " +
                 std::to_string(b.lo[2]) + " .. " + std::to_string(b.hi[0]) + " " + std::to_string(b.hi[1]) + " " +
                 std::to_string(b.hi[2]));
    expect_exact(got.value(), to_mm3(oracle));
  }
}

TEST(ExactInterferenceVolume, InwardWoundMeshesGiveTheSameVolume) {
  const TriangleMesh outward = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10));
  std::vector<TriangleMesh::Face> flipped = outward.faces();
  for (auto& f : flipped) std::swap(f[1], f[2]);
  const TriangleMesh inward = TriangleMesh::create(outward.vertices(), flipped).value();
  ASSERT_LT(inward.signed_volume(), 0.0);
  const TriangleMesh b = testing::box_mesh(Vec3(8, 8, 8), Vec3(12, 13, 14));
  EXPECT_EQ(exact_interference_volume(inward, {}, b, {}).value().volume_mm3, 8.0);
  EXPECT_EQ(exact_interference_volume(b, {}, inward, {}).value().volume_mm3, 8.0);
}

TEST(ExactInterferenceVolume, AMeshCrossingItselfWhereThePartsMeetIsRefusedByName) {
  // Two overlapping boxes in one mesh (each closed: the mesh passes as closed) have no single inside.
  const TriangleMesh b1 = testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10));
  const TriangleMesh b2 = testing::box_mesh(Vec3(5, 5, 5), Vec3(15, 15, 15));
  std::vector<Vec3> v = b1.vertices();
  v.insert(v.end(), b2.vertices().begin(), b2.vertices().end());
  std::vector<TriangleMesh::Face> f = b1.faces();
  for (auto face : b2.faces()) f.push_back({face[0] + 8, face[1] + 8, face[2] + 8});
  const TriangleMesh crossing = TriangleMesh::create(v, f).value();
  ASSERT_TRUE(crossing.is_closed_oriented());
  const TriangleMesh probe = testing::box_mesh(Vec3(4, 4, 4), Vec3(11, 11, 11));
  auto got = exact_interference_volume(crossing, {}, probe, {});
  ASSERT_FALSE(got.ok());
  EXPECT_EQ(got.error().code, ErrorCode::kFailedPrecondition);
  EXPECT_EQ(got.error().field, "a");
  EXPECT_NE(got.error().message.find("does not bound a volume"), std::string::npos) << got.error().to_string();
  // The ray cast's parity would count the shells' shared region as outside: no figure at all.
  const auto a = MeshBvh::build(testing::share(crossing)).value();
  const auto p = MeshBvh::build(testing::share(probe)).value();
  auto refused = interference_volume(*p, {}, *a, {}, 64);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().field, "b");
}

// Shells nested with the same orientation (a box inside a box, both outward), and a body wound
// inward beside an outward one, do not bound a volume either; a cavity wound inward does.
TEST(ExactInterferenceVolume, NestedShellsMustAlternateTheirOrientation) {
  auto join = [](const TriangleMesh& outer, const TriangleMesh& inner, bool flip_inner) {
    std::vector<Vec3> v = outer.vertices();
    v.insert(v.end(), inner.vertices().begin(), inner.vertices().end());
    std::vector<TriangleMesh::Face> f = outer.faces();
    const auto n = static_cast<std::uint32_t>(outer.vertices().size());
    for (auto face : inner.faces()) {
      if (flip_inner) std::swap(face[1], face[2]);
      f.push_back({face[0] + n, face[1] + n, face[2] + n});
    }
    return TriangleMesh::create(v, f).value();
  };
  const TriangleMesh outer = testing::box_mesh(Vec3(0, 0, 0), Vec3(20, 20, 20));
  const TriangleMesh inner = testing::box_mesh(Vec3(5, 5, 5), Vec3(15, 15, 15));
  const TriangleMesh probe = testing::box_mesh(Vec3(10, 10, 10), Vec3(20, 20, 20));
  EXPECT_FALSE(bounds_a_volume(join(outer, inner, false), "a").value());
  const TriangleMesh hollow = join(outer, inner, true);
  ASSERT_TRUE(bounds_a_volume(hollow, "a").value());
  // The hollow box against [10, 20]^3: 1000 less the cavity's 125.
  EXPECT_EQ(exact_interference_volume(hollow, {}, probe, {}).value().volume_mm3, 875.0);
  const TriangleMesh beside = testing::box_mesh(Vec3(30, 0, 0), Vec3(40, 10, 10));
  EXPECT_FALSE(bounds_a_volume(join(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)), beside, true), "a").value());
}

// The overlaps the ray cast's grid could not resolve (a corner of 1.5e-6 mm^3, a 45-degree edge
// 0.0114 mm deep) now come back exact.
TEST(ExactInterferenceVolume, TheRayCastFallsBackToItWhereTheGridCannotResolveTheOverlap) {
  const auto a = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)))).value();
  const double h = 0.0114;
  const double c = 10.0 - h;     // the corner's position as a double...
  const double depth = 10.0 - c;  // ...and the overlap's exact side (Sterbenz: no rounding)
  const auto corner = MeshBvh::build(testing::share(testing::box_mesh(Vec3(c, c, c), Vec3(c + 10, c + 10, c + 10)))).value();
  const VolumeEstimate v = interference_volume(*a, {}, *corner, {}, 64).value();
  EXPECT_EQ(v.method, VolumeMethod::kExactCorefinement);
  EXPECT_NEAR(v.volume_mm3, depth * depth * depth, 1e-15 * depth * depth * depth);
  // The same at 5e4 mm by the pose.
  const RigidTransform far = RigidTransform::from_translation(Vec3(50000, -50000, 50000));
  const VolumeEstimate vf = interference_volume(*a, far, *corner, far, 64).value();
  EXPECT_EQ(vf.method, VolumeMethod::kExactCorefinement);
  EXPECT_NEAR(vf.volume_mm3, depth * depth * depth, 1e-15 * depth * depth * depth);
}

}  // namespace
}  // namespace gk

namespace gk {
namespace {

// Corner and edge overlaps far thinner than the coordinates' magnitude (2^-20 mm at 10 mm): the
// figure, by whichever method, lies within its bound of the exact e^3 or e^2 * 10.
TEST(InterferenceVolume, TheBoundHoldsForOverlapsFarThinnerThanTheCoordinates) {
  const auto cube = MeshBvh::build(testing::share(testing::box_mesh(Vec3(0, 0, 0), Vec3(10, 10, 10)))).value();
  for (int k : {20, 23, 26}) {
    const double e = std::ldexp(1.0, -k);
    struct Case {
      Vec3 t;
      double exact;
    };
    const Case cases[] = {{Vec3(10 - e, 10 - e, 10 - e), e * e * e}, {Vec3(10 - e, 10 - e, 0), e * e * 10}, {Vec3(10 - e, 10 - e, 3), e * e * 7}};
    for (const Case& c : cases) {
      const VolumeEstimate v = interference_volume(*cube, {}, *cube, RigidTransform::from_translation(c.t), 256).value();
      SCOPED_TRACE("k " + std::to_string(k) + " t " + std::to_string(c.t.z()) + " method " + std::to_string(static_cast<int>(v.method)));
      EXPECT_LE(std::fabs(v.volume_mm3 - c.exact), v.error_bound_mm3) << v.volume_mm3 << " vs " << c.exact << " bound " << v.error_bound_mm3;
    }
  }
}

}  // namespace
}  // namespace gk
