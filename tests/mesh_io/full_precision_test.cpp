// Coordinates arrive as they were written: the box pair 50 m from the origin, written as OBJ, OFF,
// ASCII PLY and ASCII STL text, keeps its 0.001 mm overlap or gap (Assimp's single precision
// snapped it to 2^-8 mm = 0.0039 mm there); binary float32 and float64 values are taken exactly;
// counts and indices that do not match the data are errors naming where.
#include "kernel/query/contact_verdict.h"
#include "mesh_io/mesh_file_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace gk::mesh_io {
namespace {

struct Box {
  double x0, x1, y0, y1, z0, z1;
};

// The box's 8 corners (k = a + 2b + 4c) and 12 outward triangles.
std::vector<Vec3> corners(const Box& b) {
  std::vector<Vec3> v;
  for (int k = 0; k < 8; ++k) v.emplace_back((k & 1) ? b.x1 : b.x0, (k & 2) ? b.y1 : b.y0, (k & 4) ? b.z1 : b.z0);
  return v;
}
const int kFaces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                           {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};

// Each number written with 17 significant digits: the double itself, as a person writing the file
// at factory coordinates would have it.
std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}

std::string as_obj(const Box& b) {
  std::string out = "# a box at factory coordinates\nmtllib /etc/passwd\n";
  for (const Vec3& c : corners(b)) out += "v " + number(c.x()) + " " + number(c.y()) + " " + number(c.z()) + "\n";
  for (const auto& f : kFaces) out += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " + std::to_string(f[2] + 1) + "\n";
  return out;
}

std::string as_off(const Box& b) {
  std::string out = "OFF\n8 12 0\n";
  for (const Vec3& c : corners(b)) out += number(c.x()) + " " + number(c.y()) + " " + number(c.z()) + "\n";
  for (const auto& f : kFaces) out += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return out;
}

std::string as_ply(const Box& b) {
  std::string out = "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\nproperty double z\n"
                    "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& c : corners(b)) out += number(c.x()) + " " + number(c.y()) + " " + number(c.z()) + "\n";
  for (const auto& f : kFaces) out += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return out;
}

std::string as_ascii_stl(const Box& b) {
  const std::vector<Vec3> v = corners(b);
  std::string out = "solid box\n";
  for (const auto& f : kFaces) {
    out += "  facet normal 0 0 0\n    outer loop\n";
    for (int k : f) out += "      vertex " + number(v[k].x()) + " " + number(v[k].y()) + " " + number(v[k].z()) + "\n";
    out += "    endloop\n  endfacet\n";
  }
  return out + "endsolid box\n";
}

Verdict verdict_of(const TriangleMesh& a, const TriangleMesh& b, double* distance) {
  auto ba = MeshBvh::build(std::make_shared<const TriangleMesh>(a)).value();
  auto bb = MeshBvh::build(std::make_shared<const TriangleMesh>(b)).value();
  const VerdictResult r = assess(*ba, {}, *bb, {}).value();
  *distance = r.distance_mm;
  return r.verdict;
}

TEST(FullPrecision, ABoxPairFiftyMetresOutKeepsItsMicrometreOverlapAndGapInEveryTextFormat) {
  // A = [50000, 50100] x [0, 100]^2; B from X to 50150 in x, [10, 90] in y and z.
  const Box a{50000.0, 50100.0, 0.0, 100.0, 0.0, 100.0};
  struct Case {
    double x;
    Verdict verdict;
    double distance;
  };
  const Case cases[] = {{50099.999, Verdict::kCollision, 0.0},
                        {50100.001, Verdict::kClear, 50100.001 - 50100.0},
                        {50100.003, Verdict::kClear, 50100.003 - 50100.0}};
  using Writer = std::string (*)(const Box&);
  const std::pair<const char*, Writer> formats[] = {{"obj", as_obj}, {"off", as_off}, {"ply", as_ply}, {"stl", as_ascii_stl}};
  for (const auto& [format, write] : formats) {
    const TriangleMesh ma = read_mesh_bytes(write(a), format).value();
    EXPECT_EQ(ma.bounds().max.x(), 50100.0) << format;
    for (const Case& c : cases) {
      const Box b{c.x, 50150.0, 10.0, 90.0, 10.0, 90.0};
      auto mb = read_mesh_bytes(write(b), format);
      ASSERT_TRUE(mb.ok()) << format << ": " << mb.error().to_string();
      // The coordinate is the double nearest the text, as the writer's own double was.
      EXPECT_EQ(mb.value().bounds().min.x(), c.x) << format;
      double d = -1.0;
      EXPECT_EQ(verdict_of(ma, mb.value(), &d), c.verdict) << format << " at X = " << number(c.x);
      // The distance is the difference of the two doubles (exactly representable here to 1e-12).
      EXPECT_NEAR(d, c.distance, 1e-9) << format << " at X = " << number(c.x);
    }
  }
}

template <class T>
void put(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out.append(raw, sizeof(T));
}

TEST(FullPrecision, BinaryFloat32AndFloat64ValuesAreTakenExactly) {
  // Binary STL stores float32: the value read is that float, exactly (no further rounding).
  const float f = 50099.99609375f;  // a float32 at factory coordinates
  std::string stl(80, '\0');
  put<std::uint32_t>(stl, 1);
  for (int k = 0; k < 3; ++k) put<float>(stl, 0.0f);
  const float tri[3][3] = {{f, 0.0f, 0.0f}, {f, 1.0f, 0.0f}, {f, 0.0f, 1.0f}};
  for (const auto& v : tri)
    for (float c : v) put<float>(stl, c);
  put<std::uint16_t>(stl, 0);
  auto read = read_mesh_bytes(stl, "stl");
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  EXPECT_EQ(read.value().vertices()[0].x(), static_cast<double>(f));
  // Binary PLY with float64 properties keeps every bit of the double.
  const double x = 50099.999;  // not a float32
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                    "property double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  for (const Vec3& v : {Vec3(x, 0, 0), Vec3(x, 1, 0), Vec3(x, 0, 1)}) {
    put<double>(ply, v.x());
    put<double>(ply, v.y());
    put<double>(ply, v.z());
  }
  put<std::uint8_t>(ply, 3);
  for (std::uint32_t i : {0u, 1u, 2u}) put<std::uint32_t>(ply, i);
  auto p = read_mesh_bytes(ply, "ply");
  ASSERT_TRUE(p.ok()) << p.error().to_string();
  EXPECT_EQ(p.value().vertices()[0].x(), x);
}

TEST(FullPrecision, CountsAndIndicesThatDoNotMatchTheDataAreErrorsNamingWhere) {
  // An OFF header declaring more than it gives (this aborted the daemon inside Assimp).
  auto short_off = read_mesh_bytes("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off");
  ASSERT_FALSE(short_off.ok());
  // (Its face line is read as the fourth vertex; then the face is missing.)
  EXPECT_NE(short_off.error().to_string().find("declares 1 faces, gives 0"), std::string::npos) << short_off.error().to_string();
  EXPECT_FALSE(read_mesh_bytes("OFF\n4 0 0\n0 0 0\n1 0 0\n0 1 0\n", "off").ok());
  // A face index beyond the vertices (stored as a 1-triangle part before).
  auto bad_index = read_mesh_bytes("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99\n", "off");
  ASSERT_FALSE(bad_index.ok());
  EXPECT_NE(bad_index.error().to_string().find("line 6"), std::string::npos) << bad_index.error().to_string();
  auto ply_index = read_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
                                   "ply");
  ASSERT_FALSE(ply_index.ok());
  EXPECT_NE(ply_index.error().to_string().find("element face[0]"), std::string::npos) << ply_index.error().to_string();
  // A huge declared count with no data is refused before anything is allocated for it.
  EXPECT_FALSE(read_mesh_bytes("OFF\n2000000000 2000000000 0\n", "off").ok());
  EXPECT_FALSE(read_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n", "ply").ok());
  // ASCII STL with a facet of two vertices.
  EXPECT_FALSE(read_mesh_bytes("solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid s\n", "stl").ok());
  // OBJ: relative indices count back from the last vertex; a zero index is an error.
  auto relative = read_mesh_bytes("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", "obj");
  ASSERT_TRUE(relative.ok()) << relative.error().to_string();
  EXPECT_EQ(relative.value().triangle_count(), 1u);
  EXPECT_FALSE(read_mesh_bytes("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "obj").ok());
}

TEST(FullPrecision, WhatAReviewerSentIsReadAsWrittenOrRefused) {
  // A lone CR ends a line: nothing is silently dropped.
  auto cr = read_mesh_bytes("v 0 0 0\rv 9 9 9\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n", "obj");
  ASSERT_TRUE(cr.ok()) << cr.error().to_string();
  EXPECT_EQ(cr.value().bounds().max, Vec3(9, 9, 9));
  // "+-5" is no number; a vertex of four coordinates or a data line with more values is refused.
  EXPECT_FALSE(read_mesh_bytes("v +-5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj").ok());
  EXPECT_FALSE(read_mesh_bytes("solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0 7\nvertex 1 0 0\nvertex 0 1 0\n"
                               "endloop\nendfacet\nendsolid s\n", "stl").ok());
  EXPECT_FALSE(read_mesh_bytes("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 9 9\n1 0 0\n0 1 0\n3 0 1 2\n",
                               "ply").ok());
  // A binary PLY whose list count is a float NaN.
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list float int vertex_indices\nend_header\n";
  for (int k = 0; k < 9; ++k) put<float>(ply, static_cast<float>(k % 3 == 0 ? 1 : 0));
  put<float>(ply, std::nanf(""));
  for (int i : {0, 1, 2}) put<std::int32_t>(ply, i);
  EXPECT_FALSE(read_mesh_bytes(ply, "ply").ok());
  EXPECT_FALSE(read_mesh_bytes("XYZOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off").ok());
}

TEST(FullPrecision, MutatedFilesComeBackAsMeshesOrErrorsNeverACrash) {
  // Bytes flipped, cut and duplicated at random in valid files of every format.
  const Box box{50000.0, 50100.0, 0.0, 100.0, 0.0, 100.0};
  const std::pair<const char*, std::string> files[] = {
      {"obj", as_obj(box)}, {"off", as_off(box)}, {"ply", as_ply(box)}, {"stl", as_ascii_stl(box)}};
  std::uint64_t state = 12345;
  auto next = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::size_t>(state >> 33);
  };
  int ok = 0, errors = 0;
  for (const auto& [format, text] : files)
    for (int trial = 0; trial < 1500; ++trial) {
      std::string bytes = text;
      for (int edit = 0, n = 1 + static_cast<int>(next() % 4); edit < n && !bytes.empty(); ++edit) {
        const std::size_t at = next() % bytes.size();
        switch (next() % 4) {
          case 0: bytes[at] = static_cast<char>(next() % 256); break;
          case 1: bytes.erase(at, 1 + next() % 16); break;
          case 2: bytes.insert(at, bytes.substr(at, 1 + next() % 32)); break;
          case 3: bytes.resize(at); break;
        }
      }
      const auto read = read_mesh_bytes(bytes, format);
      (read.ok() ? ok : errors) += 1;
      if (!read.ok()) {
        EXPECT_FALSE(read.error().message.empty());
      }
    }
  EXPECT_GT(errors, 100);
  EXPECT_GT(ok, 100);
}

}  // namespace
}  // namespace gk::mesh_io

namespace gk::mesh_io {
namespace {

// Written numbers too small for a double round to zero (or a subnormal), as a correctly rounding
// reader must; too large ones are refused.
TEST(FullPrecision, UnderflowingCoordinatesRoundToZeroAndOverflowingOnesAreRefused) {
  auto tiny = read_mesh_bytes("v 1e-400 0 0\nv 1 0 0\nv 0 1 -4.9e-320\nf 1 2 3\n", "obj");
  ASSERT_TRUE(tiny.ok()) << tiny.error().to_string();
  EXPECT_EQ(tiny.value().vertices()[0].x(), 0.0);
  EXPECT_EQ(tiny.value().vertices()[2].z(), -4.9e-320);  // a subnormal, kept
  EXPECT_FALSE(read_mesh_bytes("v 1e400 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj").ok());
}

// PLY allows any element order: faces declared (and written) before the vertices they index.
TEST(FullPrecision, PlyFacesBeforeVerticesAreRead) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 3\n"
      "property double x\nproperty double y\nproperty double z\nend_header\n3 0 1 2\n50000.001 0 0\n50001 0 0\n50000 1 0\n";
  auto read = read_mesh_bytes(ply, "ply");
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  EXPECT_EQ(read.value().triangle_count(), 1u);
  EXPECT_EQ(read.value().vertices()[0].x(), 50000.001);
  EXPECT_FALSE(read_mesh_bytes(
                   "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 3\n"
                   "property double x\nproperty double y\nproperty double z\nend_header\n3 0 1 3\n0 0 0\n1 0 0\n0 1 0\n",
                   "ply")
                   .ok());
}

}  // namespace
}  // namespace gk::mesh_io
