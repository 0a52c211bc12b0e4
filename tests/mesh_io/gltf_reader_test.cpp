// glTF read by our own reader (issue: geometry truth §1): float32 positions taken exactly, node
// transforms composed in double (a factory offset in a node keeps every digit), nothing outside the
// file read, and malformed documents refused with an error naming where.
#include "mesh_io/mesh_file_reader.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace gk::mesh_io {
namespace {

std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(in[i]) << 16) | (static_cast<unsigned char>(in[i + 1]) << 8) |
                       static_cast<unsigned char>(in[i + 2]);
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == in.size()) {
    const unsigned v = static_cast<unsigned char>(in[i]) << 16;
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == in.size()) {
    const unsigned v = (static_cast<unsigned char>(in[i]) << 16) | (static_cast<unsigned char>(in[i + 1]) << 8);
    out += {t[(v >> 18) & 63], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

// The unit corner tetrahedron (outward), float32 positions then uint16 indices.
std::string tetra_buffer() {
  const float p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::uint16_t idx[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  std::string b(reinterpret_cast<const char*>(p), sizeof p);
  b.append(reinterpret_cast<const char*>(idx), sizeof idx);
  return b;
}

std::string document(const std::string& nodes, const std::string& buffer_json) {
  std::ostringstream s;
  s << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":)" << nodes
    << R"(,"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"buffers":[)" << buffer_json
    << R"(],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":24}],)"
    << R"("accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"},)"
    << R"({"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}]})";
  return s.str();
}

std::string embedded() { return R"({"byteLength":72,"uri":"data:application/octet-stream;base64,)" + base64(tetra_buffer()) + "\"}"; }

TEST(GltfReader, NodeTransformsAreComposedInDoublePrecision) {
  // A parent at a factory offset written to the micrometre, a child turned 90 degrees about z.
  const std::string nodes =
      R"([{"translation":[50000.123456,-30000.000001,20000.5],"children":[1]},{"mesh":0,"rotation":[0,0,0.7071067811865476,0.7071067811865476]}])";
  auto read = read_mesh_bytes(document(nodes, embedded()), "gltf");
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  const auto& v = read.value().vertices();
  ASSERT_EQ(v.size(), 4u);
  EXPECT_EQ(v[0].x(), 50000.123456);  // the origin corner lands on the written offset exactly
  EXPECT_EQ(v[0].y(), -30000.000001);
  // (1, 0, 0) turned to (0, 1, 0): within double rounding of the composed transform.
  EXPECT_NEAR(v[1].x(), 50000.123456, 1e-11);
  EXPECT_NEAR(v[1].y(), -30000.000001 + 1.0, 1e-11);
  EXPECT_TRUE(read.value().is_closed_oriented());
  EXPECT_GT(read.value().signed_volume(), 0.0);
}

TEST(GltfReader, AMirroringNodeKeepsTheSolidOutward) {
  auto read = read_mesh_bytes(document(R"([{"mesh":0,"scale":[-1,1,1]}])", embedded()), "gltf");
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  EXPECT_NEAR(read.value().signed_volume(), 1.0 / 6.0, 1e-12);
}

TEST(GltfReader, AGlbContainerIsRead) {
  std::string json = document(R"([{"mesh":0,"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 1000.25,0,0,1]}])", R"({"byteLength":72})");
  while (json.size() % 4) json += ' ';
  std::string bin = tetra_buffer();
  std::string glb;
  auto u32 = [&](std::uint32_t x) { glb.append(reinterpret_cast<const char*>(&x), 4); };
  u32(0x46546C67);
  u32(2);
  u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  u32(static_cast<std::uint32_t>(json.size()));
  u32(0x4E4F534A);
  glb += json;
  u32(static_cast<std::uint32_t>(bin.size()));
  u32(0x004E4942);
  glb += bin;
  auto read = read_mesh_bytes(glb, "glb");
  ASSERT_TRUE(read.ok()) << read.error().to_string();
  EXPECT_EQ(read.value().vertices()[1].x(), 1001.25);
}

TEST(GltfReader, NothingOutsideTheFileIsRead) {
  for (const char* uri : {"../../../etc/passwd", "/etc/passwd", "file:///etc/passwd", "secret.bin"}) {
    auto read = read_mesh_bytes(document(R"([{"mesh":0}])", std::string(R"({"byteLength":72,"uri":")") + uri + "\"}"), "gltf");
    ASSERT_FALSE(read.ok()) << uri;
    EXPECT_NE(read.error().message.find("external references are refused"), std::string::npos) << read.error().to_string();
  }
}

TEST(GltfReader, MalformedDocumentsAreErrorsNamingWhere) {
  const std::vector<std::string> bad = {
      "not json",
      R"({"asset":{"version":"1.0"}})",
      document(R"([{"mesh":7}])", embedded()),                               // no such mesh
      document(R"([{"mesh":0,"children":[0]}])", embedded()),                // a cycle
      document(R"([{"mesh":0,"translation":[1,2]}])", embedded()),           // wrong arity
      document(R"([{"mesh":"zero"}])", embedded()),                          // wrong type
      document(R"([{"mesh":0}])", R"({"byteLength":72,"uri":"data:application/octet-stream;base64,AAAA"})"),  // short buffer
      document(R"([{"mesh":0,"translation":[1e400,0,0]}])", embedded()),     // not finite
  };
  for (const std::string& doc : bad) {
    auto read = read_mesh_bytes(doc, "gltf");
    EXPECT_FALSE(read.ok()) << doc.substr(0, 80);
  }
  // An index beyond the positions, and an accessor past its view.
  std::string idx = document(R"([{"mesh":0}])", embedded());
  idx.replace(idx.find("\"count\":12"), 10, "\"count\":14");
  EXPECT_FALSE(read_mesh_bytes(idx, "gltf").ok());
}

// glTF nodes form trees. Found by a review: 42 nodes each naming the next twice as a child is a
// 1 KB file with 2^41 paths through it, which kept the upload worker busy for good; the same
// sharing instanced one triangle millions of times from 2 KB. A node reached twice is refused.
TEST(GltfReader, NodesSharedBetweenParentsAreRefusedAtOnce) {
  std::string nodes = "[";
  for (int i = 0; i < 42; ++i) nodes += std::string(i ? "," : "") + "{\"mesh\":0,\"children\":[" + std::to_string(i + 1) + "," + std::to_string(i + 1) + "]}";
  nodes += ",{\"mesh\":0}]";
  const auto t0 = std::chrono::steady_clock::now();
  auto dag = read_mesh_bytes(document(nodes, embedded()), "gltf");
  ASSERT_FALSE(dag.ok());
  EXPECT_NE(dag.error().to_string().find("reached twice"), std::string::npos) << dag.error().to_string();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  // A cycle, and a root that is also another node's child.
  EXPECT_FALSE(read_mesh_bytes(document(R"([{"mesh":0,"children":[1]},{"children":[0]}])", embedded()), "gltf").ok());
  auto twice = read_mesh_bytes(document(R"([{"children":[1,1]},{"mesh":0}])", embedded()), "gltf");
  EXPECT_FALSE(twice.ok());
  // A proper tree still instances the mesh once per node.
  auto tree = read_mesh_bytes(document(R"([{"children":[1,2]},{"mesh":0},{"mesh":0,"translation":[5,0,0]}])", embedded()), "gltf");
  ASSERT_TRUE(tree.ok()) << tree.error().to_string();
  EXPECT_EQ(tree.value().triangle_count(), 8u);
}

}  // namespace
}  // namespace gk::mesh_io
