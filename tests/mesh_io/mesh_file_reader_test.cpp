// gk::mesh_io::read_mesh_file / read_mesh_bytes: the shared real meshes (counts from
// ../shared/data/MANIFEST.tsv), small files of every supported format written here and checked to
// give the same closed cube, and malformed inputs that must come back as errors naming the file.
#include "mesh_io/mesh_file_reader.h"

#include "tests/support/random_meshes.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace gk::mesh_io {
namespace {

namespace fs = std::filesystem;
using gk::testing::shared_data;

// ---------------------------------------------------------------------------------------------
// Helpers

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  ASSERT_TRUE(out.good()) << "cannot create " << path;
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

std::string base64_encode(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{static_cast<unsigned char>(bytes[i])} << 16) |
                            (std::uint32_t{static_cast<unsigned char>(bytes[i + 1])} << 8) |
                            std::uint32_t{static_cast<unsigned char>(bytes[i + 2])};
    out += kAlphabet[(n >> 18) & 63u];
    out += kAlphabet[(n >> 12) & 63u];
    out += kAlphabet[(n >> 6) & 63u];
    out += kAlphabet[n & 63u];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest == 1) {
    const std::uint32_t n = std::uint32_t{static_cast<unsigned char>(bytes[i])} << 16;
    out += kAlphabet[(n >> 18) & 63u];
    out += kAlphabet[(n >> 12) & 63u];
    out += "==";
  } else if (rest == 2) {
    const std::uint32_t n = (std::uint32_t{static_cast<unsigned char>(bytes[i])} << 16) |
                            (std::uint32_t{static_cast<unsigned char>(bytes[i + 1])} << 8);
    out += kAlphabet[(n >> 18) & 63u];
    out += kAlphabet[(n >> 12) & 63u];
    out += kAlphabet[(n >> 6) & 63u];
    out += '=';
  }
  return out;
}

template <typename T>
void append_pod(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out.append(raw, sizeof(T));
}

// The unit cube [0,1]^3, outward and counter-clockwise seen from outside (volume +1).
const std::array<std::array<int, 3>, 8> kCubeVertices = {{
    {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}};
const std::array<std::array<int, 3>, 12> kCubeFaces = {{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                                        {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                                        {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}}};

std::string cube_obj() {
  std::ostringstream s;
  s << "# unit cube\n";
  for (const auto& v : kCubeVertices) s << "v " << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& f : kCubeFaces) s << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
  return s.str();
}

std::string cube_off() {
  std::ostringstream s;
  s << "OFF\n8 12 0\n";
  for (const auto& v : kCubeVertices) s << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& f : kCubeFaces) s << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
  return s.str();
}

std::string cube_ply() {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\ncomment unit cube\n"
    << "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
    << "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : kCubeVertices) s << v[0] << ' ' << v[1] << ' ' << v[2] << '\n';
  for (const auto& f : kCubeFaces) s << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
  return s.str();
}

// A glTF 2.0 JSON file whose single buffer is embedded as a base64 data: URI: float32 positions
// followed by uint16 indices (the index view starts at a multiple of 4 since positions are 12 bytes each).
std::string gltf_with_embedded_buffer(const std::vector<std::array<float, 3>>& positions,
                                      const std::vector<std::uint16_t>& indices) {
  std::string buffer;
  std::array<float, 3> lo = positions.front(), hi = positions.front();
  for (const auto& p : positions) {
    for (int k = 0; k < 3; ++k) {
      append_pod(buffer, p[static_cast<std::size_t>(k)]);
      lo[static_cast<std::size_t>(k)] = std::min(lo[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k)]);
      hi[static_cast<std::size_t>(k)] = std::max(hi[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k)]);
    }
  }
  const std::size_t positions_bytes = buffer.size();
  for (std::uint16_t i : indices) append_pod(buffer, i);
  const std::size_t indices_bytes = buffer.size() - positions_bytes;

  std::ostringstream s;
  s << "{\n"
    << "  \"asset\": {\"version\": \"2.0\", \"generator\": \"gatekeeper mesh_file_reader_test\"},\n"
    << "  \"scene\": 0,\n"
    << "  \"scenes\": [{\"nodes\": [0]}],\n"
    << "  \"nodes\": [{\"mesh\": 0}],\n"
    << "  \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, \"mode\": 4}]}],\n"
    << "  \"buffers\": [{\"byteLength\": " << buffer.size()
    << ", \"uri\": \"data:application/octet-stream;base64," << base64_encode(buffer) << "\"}],\n"
    << "  \"bufferViews\": [\n"
    << "    {\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": " << positions_bytes << ", \"target\": 34962},\n"
    << "    {\"buffer\": 0, \"byteOffset\": " << positions_bytes << ", \"byteLength\": " << indices_bytes
    << ", \"target\": 34963}\n"
    << "  ],\n"
    << "  \"accessors\": [\n"
    << "    {\"bufferView\": 0, \"componentType\": 5126, \"count\": " << positions.size() << ", \"type\": \"VEC3\", "
    << "\"min\": [" << lo[0] << ", " << lo[1] << ", " << lo[2] << "], \"max\": [" << hi[0] << ", " << hi[1] << ", "
    << hi[2] << "]},\n"
    << "    {\"bufferView\": 1, \"componentType\": 5123, \"count\": " << indices.size() << ", \"type\": \"SCALAR\"}\n"
    << "  ]\n"
    << "}\n";
  return s.str();
}

std::string cube_gltf() {
  std::vector<std::array<float, 3>> positions;
  for (const auto& v : kCubeVertices)
    positions.push_back({static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])});
  std::vector<std::uint16_t> indices;
  for (const auto& f : kCubeFaces)
    for (int k : f) indices.push_back(static_cast<std::uint16_t>(k));
  return gltf_with_embedded_buffer(positions, indices);
}

// The corner tetrahedron (0,0,0),(1,0,0),(0,1,0),(0,0,1), outward: volume +1/6.
std::string tetrahedron_gltf() {
  const std::vector<std::array<float, 3>> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<std::uint16_t> indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  return gltf_with_embedded_buffer(positions, indices);
}

// A binary STL of the cube: 80-byte header (zeros: must not begin with "solid"), count, 50 bytes a facet.
std::string cube_binary_stl(std::uint32_t declared_count, std::size_t facets_written) {
  std::string out(80, '\0');
  append_pod(out, declared_count);
  for (std::size_t t = 0; t < facets_written; ++t) {
    const auto& f = kCubeFaces[t % kCubeFaces.size()];
    for (int k = 0; k < 3; ++k) append_pod(out, 0.0f);  // normal
    for (int c : f)
      for (int k = 0; k < 3; ++k)
        append_pod(out, static_cast<float>(kCubeVertices[static_cast<std::size_t>(c)][static_cast<std::size_t>(k)]));
    append_pod(out, std::uint16_t{0});  // attribute byte count
  }
  return out;
}

void expect_unit_cube(const Result<TriangleMesh>& read, const std::string& what) {
  ASSERT_TRUE(read.ok()) << what << ": " << read.error().to_string();
  const TriangleMesh& mesh = read.value();
  EXPECT_EQ(mesh.triangle_count(), 12u) << what;
  EXPECT_EQ(mesh.vertices().size(), 8u) << what << " (after merging identical vertices)";
  EXPECT_TRUE(mesh.is_closed_oriented()) << what << ": boundary edges " << mesh.report().boundary_edges
                                         << ", non-manifold edges " << mesh.report().non_manifold_edges;
  // Tolerance 1e-6 mm^3: the coordinates are exact small integers in every format.
  EXPECT_NEAR(std::fabs(mesh.signed_volume()), 1.0, 1e-6) << what;
  // Tolerance 0 (exact): the corners 0 and 1 are representable in float and double.
  EXPECT_EQ(mesh.bounds().min, Vec3(0, 0, 0)) << what;
  EXPECT_EQ(mesh.bounds().max, Vec3(1, 1, 1)) << what;
  EXPECT_TRUE(mesh.report().zero_area_triangles.empty()) << what;
}

// The error names the file (its path appears in the error text) and says something.
void expect_error_naming(const Result<TriangleMesh>& read, const fs::path& path, const std::string& what) {
  if (read.ok()) {
    std::ostringstream got;
    for (const Vec3& v : read.value().vertices()) got << " (" << v.transpose() << ")";
    ADD_FAILURE() << what << ": expected an error, got a mesh of " << read.value().triangle_count()
                  << " triangles, vertices" << got.str();
    return;
  }
  EXPECT_FALSE(read.error().message.empty()) << what;
  EXPECT_NE(read.error().to_string().find(path.filename().string()), std::string::npos)
      << what << ": error does not name the file: " << read.error().to_string();
  std::cout << "[ info     ] " << what << " -> " << read.error().to_string() << '\n';
}

// A per-test scratch directory under the system temp dir, removed afterwards.
class MeshFileReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    dir_ = fs::temp_directory_path() / ("gk_mesh_reader_" + std::to_string(::getpid()) + "_" + info->name() + "_" +
                                        std::to_string(stamp));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path file(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_ / name;
    write_file(p, bytes);
    return p;
  }
  fs::path dir_;
};

// ---------------------------------------------------------------------------------------------
// The shared real meshes: triangle counts as listed in MANIFEST.tsv.

struct SharedMesh {
  const char* path;
  std::size_t triangles;
};

class SharedMeshTest : public ::testing::TestWithParam<SharedMesh> {};

TEST_P(SharedMeshTest, TriangleCountMatchesManifestAndBoundsAreFinite) {
  const SharedMesh& m = GetParam();
  const std::string path = shared_data(m.path);
  const auto read = read_mesh_file(path);
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  const TriangleMesh& mesh = read.value();
  EXPECT_EQ(mesh.triangle_count(), m.triangles) << path;
  const Aabb b = mesh.bounds();
  EXPECT_FALSE(b.empty()) << path;
  EXPECT_TRUE(b.min.allFinite() && b.max.allFinite()) << path;
  EXPECT_TRUE((b.max - b.min).maxCoeff() > 0.0) << path;
  EXPECT_TRUE(mesh.area() > 0.0 && std::isfinite(mesh.area())) << path;
  std::cout << "[ info     ] " << m.path << ": " << mesh.triangle_count() << " triangles, " << mesh.vertices().size()
            << " vertices, zero-area " << mesh.report().zero_area_triangles.size() << ", closed "
            << mesh.report().closed << ", bounds [" << b.min.transpose() << "] .. [" << b.max.transpose() << "]\n";
}

INSTANTIATE_TEST_SUITE_P(Manifest, SharedMeshTest,
                         ::testing::Values(SharedMesh{"meshes/fcl/env.obj", 2180}, SharedMesh{"meshes/fcl/rob.obj", 216},
                                           SharedMesh{"meshes/occt/TR12J_OCC64K.stl", 67498},
                                           SharedMesh{"meshes/occt/video_part.stl", 9694},
                                           SharedMesh{"meshes/occt/motor.stl", 13506},  // ASCII STL, "solid" alone on its line
                                           SharedMesh{"meshes/cgal/turbine.off", 18460}),
                         [](const ::testing::TestParamInfo<SharedMesh>& param_info) {
                           std::string name = fs::path(param_info.param.path).stem().string();
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

TEST(SharedMeshes, EnvObjWithoutMergingKeepsTheSoupVertexCount) {
  // MANIFEST: env.obj is a soup with v=6540 (3 unshared vertices a face); merging must shrink it.
  ReadOptions no_merge;
  no_merge.merge_identical_vertices = false;
  const auto soup = read_mesh_file(shared_data("meshes/fcl/env.obj"), no_merge);
  ASSERT_TRUE(soup.ok()) << soup.error().to_string();
  EXPECT_EQ(soup.value().vertices().size(), 6540u);
  EXPECT_EQ(soup.value().triangle_count(), 2180u);
  const auto merged = read_mesh_file(shared_data("meshes/fcl/env.obj"));
  ASSERT_TRUE(merged.ok()) << merged.error().to_string();
  EXPECT_LT(merged.value().vertices().size(), 6540u);
  EXPECT_EQ(merged.value().triangle_count(), 2180u);
  // Tolerance 0 (exact): merging moves no coordinate, so the boxes are identical.
  EXPECT_EQ(merged.value().bounds().min, soup.value().bounds().min);
  EXPECT_EQ(merged.value().bounds().max, soup.value().bounds().max);
}

// ---------------------------------------------------------------------------------------------
// Every format gives the same closed unit cube.

TEST_F(MeshFileReaderTest, EveryFormatGivesTheSameClosedCube) {
  const std::vector<std::pair<std::string, std::string>> files = {
      {"cube.obj", cube_obj()},       {"cube.off", cube_off()},
      {"cube.ply", cube_ply()},       {"cube.gltf", cube_gltf()},
      {"cube.stl", cube_binary_stl(12, 12)}};
  std::vector<TriangleMesh> meshes;
  for (const auto& [name, bytes] : files) {
    const auto read = read_mesh_file(file(name, bytes).string());
    expect_unit_cube(read, name);
    if (read.ok()) meshes.push_back(read.value());
  }
  ASSERT_EQ(meshes.size(), files.size());
  // Same cube: same corner set and, up to orientation, the same volume. Tolerances as above.
  for (std::size_t i = 1; i < meshes.size(); ++i) {
    std::vector<std::array<double, 3>> a, b;
    for (const Vec3& v : meshes[0].vertices()) a.push_back({v.x(), v.y(), v.z()});
    for (const Vec3& v : meshes[i].vertices()) b.push_back({v.x(), v.y(), v.z()});
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b) << files[i].first << " vs " << files[0].first;
    EXPECT_NEAR(meshes[i].signed_volume(), meshes[0].signed_volume(), 1e-6) << files[i].first;  // [mm^3]
    EXPECT_NEAR(meshes[i].area(), 6.0, 1e-6) << files[i].first;                                // [mm^2]
  }
  // Our OBJ/OFF/PLY winding is outward, so the volume is +1 (tolerance 1e-6 mm^3).
  EXPECT_NEAR(meshes[0].signed_volume(), 1.0, 1e-6);
}

TEST_F(MeshFileReaderTest, GltfEmbeddedBase64Tetrahedron) {
  const auto read = read_mesh_file(file("tetra.gltf", tetrahedron_gltf()).string());
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  const TriangleMesh& mesh = read.value();
  EXPECT_EQ(mesh.triangle_count(), 4u);
  EXPECT_EQ(mesh.vertices().size(), 4u);
  EXPECT_TRUE(mesh.is_closed_oriented());
  // Tolerance 1e-9 mm^3: exact small coordinates, volume 1/6.
  EXPECT_NEAR(mesh.signed_volume(), 1.0 / 6.0, 1e-9);
}

TEST(Base64, MatchesRfc4648Vectors) {
  EXPECT_EQ(base64_encode(""), "");
  EXPECT_EQ(base64_encode("f"), "Zg==");
  EXPECT_EQ(base64_encode("fo"), "Zm8=");
  EXPECT_EQ(base64_encode("foo"), "Zm9v");
  EXPECT_EQ(base64_encode("foob"), "Zm9vYg==");
  EXPECT_EQ(base64_encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64_encode(std::string("\xff\x00\x80", 3)), "/wCA");
}

// ---------------------------------------------------------------------------------------------
// Errors: each is !ok() with a message naming the file; nothing crashes.

TEST_F(MeshFileReaderTest, MissingFileIsAnError) {
  const fs::path p = dir_ / "does_not_exist.obj";
  expect_error_naming(read_mesh_file(p.string()), p, "missing file");
}

TEST_F(MeshFileReaderTest, DirectoryIsAnError) {
  const fs::path p = dir_ / "a_directory.stl";
  fs::create_directories(p);
  expect_error_naming(read_mesh_file(p.string()), p, "directory");
}

TEST_F(MeshFileReaderTest, EmptyFileIsAnError) {
  for (const char* name : {"empty.stl", "empty.obj", "empty.off", "empty.ply", "empty.gltf"}) {
    const fs::path p = file(name, "");
    expect_error_naming(read_mesh_file(p.string()), p, std::string("empty file ") + name);
  }
}

TEST_F(MeshFileReaderTest, GarbageBytesWithStlExtensionIsAnError) {
  std::mt19937 rng(12345);  // fixed seed
  std::uniform_int_distribution<int> byte(0, 255);
  std::string garbage(1000, '\0');
  for (char& c : garbage) c = static_cast<char>(byte(rng));
  // Keep the header from looking like ASCII STL by chance.
  garbage[0] = '\x01';
  const fs::path p = file("garbage.stl", garbage);
  expect_error_naming(read_mesh_file(p.string()), p, "garbage .stl");
}

TEST_F(MeshFileReaderTest, TruncatedBinaryStlIsAnError) {
  // Header says 12 facets, only 5 are present (and a partial sixth).
  std::string bytes = cube_binary_stl(12, 5);
  bytes += std::string(20, '\0');
  const fs::path p = file("truncated.stl", bytes);
  expect_error_naming(read_mesh_file(p.string()), p, "truncated binary STL");
  // A header promising a huge number of facets with none present.
  const fs::path q = file("truncated_huge.stl", cube_binary_stl(0xFFFFFFFFu, 0));
  expect_error_naming(read_mesh_file(q.string()), q, "binary STL claiming 2^32-1 facets");
}

TEST_F(MeshFileReaderTest, ObjFaceIndexOutOfRangeIsAnError) {
  const fs::path p = file("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n");
  expect_error_naming(read_mesh_file(p.string()), p, "OBJ face referencing vertex 99");
}

TEST_F(MeshFileReaderTest, ObjNanCoordinatesAreAnError) {
  // Whatever Assimp makes of "nan", the result must never be an ok() mesh: either Assimp refuses, or
  // it yields NaN and the kernel's validation refuses the coordinate. Checked with and without
  // vertex merging.
  //
  // Observed with Assimp 5.2.5 (Debian): its OBJ parser yields NaN for "nan", "NaN", "-nan", but
  // aiProcess_JoinIdenticalVertices (merge_identical_vertices = true, the default) then merges the
  // NaN vertex with a finite one (or the finite ones into the NaN one) before our validation runs.
  // Cases 2 and 3 below come back ok() as a 2-vertex mesh with one zero-area triangle: the NaN
  // silently vanishes. That is a mesh_io bug (validate before joining), kept failing on purpose.
  const char* texts[] = {"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n",
                         "v 0 0 0\nv 1 0 0\nv 0 1 -nan\nf 1 2 3\n",
                         "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 nan\nf 1 2 3\nf 2 4 3\n"};
  for (bool merge : {true, false}) {
    ReadOptions options;
    options.merge_identical_vertices = merge;
    int n = 0;
    for (const char* text : texts) {
      const fs::path p = file("nan_" + std::to_string(n++) + ".obj", text);
      SCOPED_TRACE(std::string("merge_identical_vertices=") + (merge ? "true" : "false") + ", file:\n" + text);
      expect_error_naming(read_mesh_file(p.string(), options), p, "OBJ with NaN");
      // The same from memory: no ok() mesh either.
      EXPECT_FALSE(read_mesh_bytes(text, "obj", options).ok()) << "read_mesh_bytes, OBJ with NaN";
    }
  }
}

TEST_F(MeshFileReaderTest, ObjInfiniteAndHugeCoordinatesAreAnError) {
  const fs::path p = file("inf.obj", "v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error_naming(read_mesh_file(p.string()), p, "OBJ with inf");
  const fs::path q = file("huge.obj", "v 1e12 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error_naming(read_mesh_file(q.string()), q, "OBJ with a 1e12 mm coordinate");
}

TEST_F(MeshFileReaderTest, FileWithoutTrianglesIsAnError) {
  const fs::path p = file("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  expect_error_naming(read_mesh_file(p.string()), p, "OBJ with vertices only");
}

// ---------------------------------------------------------------------------------------------
// From bytes in memory.

TEST(ReadMeshBytes, CubeObjString) {
  expect_unit_cube(read_mesh_bytes(cube_obj(), "obj"), "cube OBJ bytes");
}

TEST(ReadMeshBytes, RobObjBytesMatchTheFile) {
  const std::string path = shared_data("meshes/fcl/rob.obj");
  const auto from_file = read_mesh_file(path);
  const auto from_bytes = read_mesh_bytes(slurp(path), "obj");
  ASSERT_TRUE(from_file.ok()) << from_file.error().to_string();
  ASSERT_TRUE(from_bytes.ok()) << from_bytes.error().to_string();
  EXPECT_EQ(from_bytes.value().triangle_count(), 216u);
  EXPECT_EQ(from_bytes.value().vertices(), from_file.value().vertices());
  EXPECT_EQ(from_bytes.value().faces(), from_file.value().faces());
}

TEST(ReadMeshBytes, EmptyBytesIsAnError) {
  const auto read = read_mesh_bytes("", "obj");
  ASSERT_FALSE(read.ok());
  EXPECT_FALSE(read.error().message.empty());
}

TEST(ReadMeshBytes, GarbageBytesAreAnError) {
  static const char kGarbage[] = "\x01\x02\x03 not a mesh at all \xfe\xff";
  const auto read = read_mesh_bytes(std::string(kGarbage, sizeof kGarbage - 1), "stl");
  ASSERT_FALSE(read.ok());
  EXPECT_FALSE(read.error().message.empty());
}

}  // namespace
}  // namespace gk::mesh_io
