#include "kernel/bvh/mesh_pack.h"

#include "kernel/core/content_hash.h"

#include <cstring>

namespace gk {
namespace {

constexpr char kPackMagic[8] = {'G', 'K', 'P', 'A', 'C', 'K', '0', '1'};
constexpr std::size_t kChecksumBytes = 16;

Hash128 checksum(std::string_view bytes) {
  ContentHash h;
  h.add_bytes(bytes.data(), bytes.size());
  return h.value();
}

}  // namespace

std::string pack_mesh_bvh(const MeshBvh& bvh) {
  std::string out;
  pack_mesh_bvh(bvh, out);
  return out;
}

void pack_mesh_bvh(const MeshBvh& bvh, std::string& out) {
  // In tree order, so the reader needs no reordering and keeps no second copy of the corners.
  const std::shared_ptr<const MeshBvh> ordered = bvh.in_tree_order();
  const TriangleMesh& mesh = ordered->mesh();
  // Sized up front: a pack of millions of triangles is not copied while it grows.
  const std::size_t estimate = 256 + mesh.vertices().size() * sizeof(Vec3) + mesh.triangle_count() * (12 + 1 + 4 + 4) +
                               mesh.body_seeds().size() * 4 + static_cast<std::size_t>(ordered->node_count()) * sizeof(BvhNode);
  out.clear();
  out.reserve(estimate);
  out.append(kPackMagic, sizeof kPackMagic);
  const std::size_t size_at = out.size();
  out.append(8, '\0');
  mesh.append_bytes(out);
  const std::uint64_t mesh_size = out.size() - size_at - 8;
  std::memcpy(out.data() + size_at, &mesh_size, sizeof mesh_size);
  ordered->append_serialized(out);
  const Hash128 sum = checksum(out);
  out.append(reinterpret_cast<const char*>(&sum.low), 8);
  out.append(reinterpret_cast<const char*>(&sum.high), 8);
}

Hash128 pack_checksum(std::string_view bytes) {
  Hash128 stored;
  if (bytes.size() < sizeof kPackMagic + 8 + kChecksumBytes) return stored;
  std::memcpy(&stored.low, bytes.data() + bytes.size() - kChecksumBytes, 8);
  std::memcpy(&stored.high, bytes.data() + bytes.size() - 8, 8);
  return stored;
}

Result<std::shared_ptr<MeshBvh>> unpack_mesh_bvh(std::string_view bytes) {
  auto bad = [](const std::string& why) { return invalid_argument("packed mesh", why); };
  if (bytes.size() < sizeof kPackMagic + 8 + kChecksumBytes || std::memcmp(bytes.data(), kPackMagic, sizeof kPackMagic) != 0)
    return bad("not a packed mesh of this version");
  const std::string_view body = bytes.substr(0, bytes.size() - kChecksumBytes);
  if (checksum(body) != pack_checksum(bytes)) return bad("the checksum does not match: the bytes are damaged");
  std::uint64_t mesh_size = 0;
  std::memcpy(&mesh_size, body.data() + sizeof kPackMagic, sizeof mesh_size);
  std::string_view rest = body.substr(sizeof kPackMagic + sizeof mesh_size);
  if (mesh_size > rest.size()) return bad("the mesh is longer than the block");
  std::string_view mesh_bytes = rest.substr(0, static_cast<std::size_t>(mesh_size));
  auto mesh = TriangleMesh::read_bytes(mesh_bytes);
  if (!mesh.ok()) return mesh.error();
  if (!mesh_bytes.empty()) return bad("the mesh's bytes have a tail");
  return MeshBvh::deserialize(std::make_shared<const TriangleMesh>(std::move(mesh).value()),
                              rest.substr(static_cast<std::size_t>(mesh_size)));
}

}  // namespace gk
