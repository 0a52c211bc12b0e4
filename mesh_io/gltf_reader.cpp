// glTF 2.0 (.gltf JSON with embedded data: URIs, or binary .glb): the triangles of every mesh
// instanced by the scene's nodes, placed by the node transforms composed in double precision (a
// factory offset in a node's translation is kept to the last digit written). Positions are
// float32 by the format's definition and taken exactly. A file may reference nothing outside
// itself: a buffer with an external uri is refused (it could name any file on the server).
#include "mesh_io/format_readers.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace gk::mesh_io {
namespace {

using Json = nlohmann::json;
using Affine = Eigen::Matrix4d;

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;
constexpr std::uint32_t kChunkBin = 0x004E4942;
constexpr int kMaxNodeDepth = 256;                 // deeper node trees are malformed (or cyclic)
// Instanced triangles (and vertices), at most: a small file instancing a mesh many times could otherwise ask for
// more memory than the machine has (the reader holds about 130 bytes a triangle: 20 million
// take about 2.6 GB, and about 40 s here).
constexpr std::size_t kMaxInstanced = 20000000;

std::uint32_t read_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + at, 4);
  return v;  // glTF is little-endian, as is every machine this runs on
}

Result<std::string> decode_base64(std::string_view text, const std::string& where) {
  static const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve(text.size() / 4 * 3);
  std::uint32_t acc = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    const std::size_t v = alphabet.find(c);
    if (v == std::string::npos) return invalid_argument(where, "the data: URI is not base64");
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

// An unsigned integer member, or the default when absent; an error when present but not one.
Result<std::size_t> count_of(const Json& object, const char* key, const std::string& where, std::size_t fallback) {
  if (!object.contains(key)) return fallback;
  const Json& v = object[key];
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<long long>() >= 0))
    return invalid_argument(where + "." + key, "must be a non-negative integer");
  return static_cast<std::size_t>(v.get<unsigned long long>());
}

class GltfReader {
 public:
  GltfReader(Json document, std::string bin) : doc_(std::move(document)), bin_(std::move(bin)) {}

  Result<RawMesh> read() {
    auto buffers = load_buffers();
    if (!buffers.ok()) return buffers.error();
    std::vector<std::size_t> roots;
    if (doc_.contains("scenes") && doc_["scenes"].is_array() && !doc_["scenes"].empty()) {
      auto which = count_of(doc_, "scene", "scene", 0);
      if (!which.ok()) return which.error();
      if (which.value() >= doc_["scenes"].size()) return invalid_argument("scene", "no such scene");
      const Json& scene = doc_["scenes"][which.value()];
      if (scene.contains("nodes"))
        for (const Json& n : scene["nodes"]) {
          if (!n.is_number_unsigned()) return invalid_argument("scenes.nodes", "must be node indices");
          roots.push_back(n.get<std::size_t>());
        }
    } else if (doc_.contains("nodes") && doc_["nodes"].is_array()) {
      std::vector<char> child(doc_["nodes"].size(), 0);
      for (const Json& n : doc_["nodes"])
        if (n.contains("children"))
          for (const Json& c : n["children"])
            if (c.is_number_unsigned() && c.get<std::size_t>() < child.size()) child[c.get<std::size_t>()] = 1;
      for (std::size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(i);
    } else if (doc_.contains("meshes") && doc_["meshes"].is_array()) {
      // No nodes at all: every mesh where it is.
      for (std::size_t m = 0; m < doc_["meshes"].size(); ++m)
        if (auto added = add_mesh(m, Affine::Identity()); !added.ok()) return added.error();
      return std::move(out_);
    }
    for (std::size_t r : roots)
      if (auto visited = visit(r, Affine::Identity(), 0); !visited.ok()) return visited.error();
    return std::move(out_);
  }

 private:
  Result<bool> load_buffers() {
    if (!doc_.contains("buffers")) return true;
    if (!doc_["buffers"].is_array()) return invalid_argument("buffers", "must be an array");
    for (std::size_t i = 0; i < doc_["buffers"].size(); ++i) {
      const Json& b = doc_["buffers"][i];
      const std::string where = "buffers[" + std::to_string(i) + "]";
      auto length = count_of(b, "byteLength", where, 0);
      if (!length.ok()) return length.error();
      std::string data;
      if (!b.contains("uri")) {
        if (i != 0 || bin_.empty()) return invalid_argument(where, "has no uri and there is no binary chunk");
        data = bin_;
      } else {
        if (!b["uri"].is_string()) return invalid_argument(where + ".uri", "must be a string");
        const std::string uri = b["uri"].get<std::string>();
        const std::size_t comma = uri.find(',');
        if (uri.rfind("data:", 0) != 0 || comma == std::string::npos || uri.find(";base64", 0) > comma)
          return invalid_argument(where + ".uri",
                                  "external references are refused: embed the buffer as a base64 data: URI or upload a .glb");
        auto decoded = decode_base64(std::string_view(uri).substr(comma + 1), where + ".uri");
        if (!decoded.ok()) return decoded.error();
        data = std::move(decoded).value();
      }
      if (data.size() < length.value()) return invalid_argument(where, "holds fewer bytes than its byteLength");
      buffers_.push_back(std::move(data));
    }
    return true;
  }

  // Accessor `index` as doubles, `components` per element (1 or 3).
  Result<std::vector<double>> accessor(std::size_t index, std::size_t components, bool indices) {
    const std::string where = "accessors[" + std::to_string(index) + "]";
    if (!doc_.contains("accessors") || index >= doc_["accessors"].size()) return invalid_argument(where, "no such accessor");
    const Json& a = doc_["accessors"][index];
    if (a.contains("sparse")) return invalid_argument(where + ".sparse", "sparse accessors are not supported");
    const std::string type = a.value("type", "");
    if ((components == 3 && type != "VEC3") || (components == 1 && type != "SCALAR"))
      return invalid_argument(where + ".type", components == 3 ? "positions must be VEC3" : "indices must be SCALAR");
    const int component_type = a.value("componentType", 0);
    std::size_t size = 0;
    if (indices) {
      if (component_type == 5121) size = 1;
      else if (component_type == 5123) size = 2;
      else if (component_type == 5125) size = 4;
      else return invalid_argument(where + ".componentType", "indices must be unsigned byte, short or int");
    } else {
      if (component_type != 5126) return invalid_argument(where + ".componentType", "positions must be float32");
      size = 4;
    }
    auto count = count_of(a, "count", where, 0);
    if (!count.ok()) return count.error();
    auto offset = count_of(a, "byteOffset", where, 0);
    if (!offset.ok()) return offset.error();
    auto view_index = count_of(a, "bufferView", where, std::numeric_limits<std::size_t>::max());
    if (!view_index.ok()) return view_index.error();
    if (!doc_.contains("bufferViews") || view_index.value() >= doc_["bufferViews"].size())
      return invalid_argument(where + ".bufferView", "missing or out of range");
    const Json& view = doc_["bufferViews"][view_index.value()];
    const std::string vwhere = "bufferViews[" + std::to_string(view_index.value()) + "]";
    auto buffer = count_of(view, "buffer", vwhere, std::numeric_limits<std::size_t>::max());
    auto view_offset = count_of(view, "byteOffset", vwhere, 0);
    auto view_length = count_of(view, "byteLength", vwhere, 0);
    auto stride = count_of(view, "byteStride", vwhere, 0);
    for (const auto* r : {&buffer, &view_offset, &view_length, &stride})
      if (!r->ok()) return r->error();
    if (buffer.value() >= buffers_.size()) return invalid_argument(vwhere + ".buffer", "no such buffer");
    const std::string& data = buffers_[buffer.value()];
    const std::size_t element = components * size;
    const std::size_t step = stride.value() > 0 ? stride.value() : element;
    if (step < element || step > 252) return invalid_argument(vwhere + ".byteStride", "smaller than an element or above 252");
    // Bounds in overflow-free arithmetic: every element must lie inside the view, the view inside the buffer.
    if (view_offset.value() > data.size() || view_length.value() > data.size() - view_offset.value())
      return invalid_argument(vwhere, "reaches past its buffer");
    if (count.value() > 0) {
      if (offset.value() > view_length.value() || count.value() - 1 > (view_length.value() - offset.value()) / step ||
          (count.value() - 1) * step + element > view_length.value() - offset.value())
        return invalid_argument(where, "reaches past its bufferView");
    }
    std::vector<double> out;
    out.reserve(count.value() * components);
    const char* base = data.data() + view_offset.value() + offset.value();
    for (std::size_t e = 0; e < count.value(); ++e)
      for (std::size_t c = 0; c < components; ++c) {
        const char* p = base + e * step + c * size;
        if (!indices) {
          float f = 0.0f;
          std::memcpy(&f, p, 4);
          if (!std::isfinite(f)) return invalid_argument(where + "[" + std::to_string(e) + "]", "coordinate is not finite");
          out.push_back(static_cast<double>(f));  // exact
        } else if (size == 1) {
          out.push_back(static_cast<unsigned char>(*p));
        } else if (size == 2) {
          std::uint16_t v = 0;
          std::memcpy(&v, p, 2);
          out.push_back(v);
        } else {
          out.push_back(read_u32(std::string_view(p, 4), 0));
        }
      }
    return out;
  }

  Result<Affine> local_transform(const Json& node, const std::string& where) {
    Affine m = Affine::Identity();
    auto numbers = [&](const char* key, std::size_t n, std::vector<double>& v) -> Result<bool> {
      if (!node.contains(key)) return false;
      const Json& a = node[key];
      if (!a.is_array() || a.size() != n) return invalid_argument(where + "." + key, "must hold " + std::to_string(n) + " numbers");
      for (const Json& x : a) {
        if (!x.is_number() || !std::isfinite(x.get<double>())) return invalid_argument(where + "." + key, "must be finite numbers");
        v.push_back(x.get<double>());
      }
      return true;
    };
    std::vector<double> matrix, t, r, s;
    auto has_matrix = numbers("matrix", 16, matrix);
    if (!has_matrix.ok()) return has_matrix.error();
    if (has_matrix.value()) {
      for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) m(row, c) = matrix[static_cast<std::size_t>(c * 4 + row)];  // column-major
      if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0)
        return invalid_argument(where + ".matrix", "must be affine (last row 0 0 0 1)");
      return m;
    }
    for (auto [key, n, v] : {std::tuple<const char*, std::size_t, std::vector<double>*>{"translation", 3, &t},
                             {"rotation", 4, &r}, {"scale", 3, &s}}) {
      auto got = numbers(key, n, *v);
      if (!got.ok()) return got.error();
    }
    if (!r.empty()) {
      const Eigen::Quaterniond q(r[3], r[0], r[1], r[2]);  // glTF stores x, y, z, w
      if (!(q.norm() > 0.0)) return invalid_argument(where + ".rotation", "must be a non-zero quaternion");
      m.block<3, 3>(0, 0) = q.normalized().toRotationMatrix();
    }
    if (!s.empty()) m.block<3, 3>(0, 0) = m.block<3, 3>(0, 0) * Eigen::Vector3d(s[0], s[1], s[2]).asDiagonal();
    if (!t.empty()) m.block<3, 1>(0, 3) = Eigen::Vector3d(t[0], t[1], t[2]);
    return m;
  }

  Result<bool> visit(std::size_t index, const Affine& parent, int depth) {
    const std::string where = "nodes[" + std::to_string(index) + "]";
    if (depth > kMaxNodeDepth) return invalid_argument(where, "nodes nested deeper than 256 (a cycle?)");
    if (!doc_.contains("nodes") || index >= doc_["nodes"].size()) return invalid_argument(where, "no such node");
    // glTF's nodes form disjoint trees: a node reached twice (two parents, or a root that is also
    // a child) would be walked once per path, and 42 nodes that each name the next twice make
    // 2^41 paths.
    if (reached_.size() != doc_["nodes"].size()) reached_.assign(doc_["nodes"].size(), 0);
    if (reached_[index]) return invalid_argument(where, "reached twice: glTF nodes form trees (one parent at most)");
    reached_[index] = 1;
    const Json& node = doc_["nodes"][index];
    auto local = local_transform(node, where);
    if (!local.ok()) return local.error();
    const Affine world = parent * local.value();  // composed in double
    if (node.contains("mesh")) {
      auto mesh = count_of(node, "mesh", where, 0);
      if (!mesh.ok()) return mesh.error();
      if (auto added = add_mesh(mesh.value(), world); !added.ok()) return added.error();
    }
    if (node.contains("children"))
      for (const Json& c : node["children"]) {
        if (!c.is_number_unsigned()) return invalid_argument(where + ".children", "must be node indices");
        if (auto visited = visit(c.get<std::size_t>(), world, depth + 1); !visited.ok()) return visited.error();
      }
    return true;
  }

  Result<bool> add_mesh(std::size_t index, const Affine& world) {
    const std::string where = "meshes[" + std::to_string(index) + "]";
    if (!doc_.contains("meshes") || index >= doc_["meshes"].size()) return invalid_argument(where, "no such mesh");
    const Json& mesh = doc_["meshes"][index];
    if (!mesh.contains("primitives") || !mesh["primitives"].is_array()) return invalid_argument(where, "has no primitives");
    // A mirroring transform turns the triangles inside out: their winding is flipped back.
    const bool mirrored = world.block<3, 3>(0, 0).determinant() < 0.0;
    for (std::size_t p = 0; p < mesh["primitives"].size(); ++p) {
      const Json& prim = mesh["primitives"][p];
      const std::string pwhere = where + ".primitives[" + std::to_string(p) + "]";
      const int mode = prim.value("mode", 4);
      if (mode < 4) continue;  // points and lines carry no surface
      if (mode > 6) return invalid_argument(pwhere + ".mode", "unknown primitive mode");
      if (!prim.contains("attributes") || !prim["attributes"].contains("POSITION"))
        return invalid_argument(pwhere, "has no POSITION attribute");
      auto position_index = count_of(prim["attributes"], "POSITION", pwhere + ".attributes", 0);
      if (!position_index.ok()) return position_index.error();
      auto positions = accessor(position_index.value(), 3, false);
      if (!positions.ok()) return positions.error();
      const std::size_t vertex_count = positions.value().size() / 3;
      std::vector<double> idx;
      if (prim.contains("indices")) {
        auto indices_index = count_of(prim, "indices", pwhere, 0);
        if (!indices_index.ok()) return indices_index.error();
        auto read = accessor(indices_index.value(), 1, true);
        if (!read.ok()) return read.error();
        idx = std::move(read).value();
      } else {
        for (std::size_t v = 0; v < vertex_count; ++v) idx.push_back(static_cast<double>(v));
      }
      for (double i : idx)
        if (i >= static_cast<double>(vertex_count))
          return invalid_argument(pwhere + ".indices", "index outside the " + std::to_string(vertex_count) + " positions");
      // Both caps checked before anything is copied: primitives sharing one large accessor copy its
      // positions once each, and one strip or fan of small indices makes a triangle per index.
      const std::size_t triangles = mode == 4 ? idx.size() / 3 : (idx.size() >= 3 ? idx.size() - 2 : 0);
      if (out_.vertices.size() + vertex_count > kMaxInstanced)
        return invalid_argument(pwhere, "more than 20 million vertices instanced");
      if (out_.faces.size() + triangles > kMaxInstanced) return invalid_argument(pwhere, "more than 20 million triangles instanced");
      const auto base = static_cast<std::uint32_t>(out_.vertices.size());
      const std::vector<double>& pos = positions.value();
      for (std::size_t v = 0; v < vertex_count; ++v) {
        const Eigen::Vector4d q = world * Eigen::Vector4d(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], 1.0);
        out_.vertices.emplace_back(q.x(), q.y(), q.z());
      }
      auto add = [&](double i0, double i1, double i2) {
        const auto a = base + static_cast<std::uint32_t>(i0), b = base + static_cast<std::uint32_t>(i1),
                   c = base + static_cast<std::uint32_t>(i2);
        out_.faces.push_back(mirrored ? TriangleMesh::Face{a, c, b} : TriangleMesh::Face{a, b, c});
      };
      if (mode == 4) {
        for (std::size_t k = 0; k + 2 < idx.size(); k += 3) add(idx[k], idx[k + 1], idx[k + 2]);
      } else if (mode == 5) {  // strip: every other triangle reversed to keep the winding
        for (std::size_t k = 0; k + 2 < idx.size(); ++k)
          k % 2 == 0 ? add(idx[k], idx[k + 1], idx[k + 2]) : add(idx[k + 1], idx[k], idx[k + 2]);
      } else {  // fan
        for (std::size_t k = 1; k + 1 < idx.size(); ++k) add(idx[0], idx[k], idx[k + 1]);
      }
    }
    return true;
  }

  Json doc_;
  std::vector<char> reached_;  // nodes visited so far
  std::string bin_;
  std::vector<std::string> buffers_;
  RawMesh out_;
};

Result<RawMesh> read_gltf_document(std::string_view bytes) {
  std::string_view json_text = bytes;
  std::string bin;
  if (bytes.size() >= 12 && read_u32(bytes, 0) == kGlbMagic) {
    if (read_u32(bytes, 4) != 2) return invalid_argument("glb header", "only glTF 2.0 is supported");
    const std::size_t length = read_u32(bytes, 8);
    if (length > bytes.size() || length < 20) return invalid_argument("glb header", "length does not match the file");
    std::size_t at = 12;
    json_text = {};
    while (at + 8 <= length) {
      const std::size_t chunk = read_u32(bytes, at);
      const std::uint32_t type = read_u32(bytes, at + 4);
      if (chunk > length - at - 8) return invalid_argument("glb chunk at byte " + std::to_string(at), "reaches past the file");
      if (type == kChunkJson && json_text.empty()) json_text = bytes.substr(at + 8, chunk);
      else if (type == kChunkBin && bin.empty()) bin = std::string(bytes.substr(at + 8, chunk));
      at += 8 + chunk;
    }
    if (json_text.empty()) return invalid_argument("glb", "has no JSON chunk");
  }
  Json doc = Json::parse(json_text.begin(), json_text.end(), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return invalid_argument("json", "not a glTF JSON document");
  if (!doc.contains("asset") || !doc["asset"].is_object() || doc["asset"].value("version", "") != "2.0")
    return invalid_argument("asset.version", "only glTF 2.0 is supported");
  return GltfReader(std::move(doc), std::move(bin)).read();
}

}  // namespace

Result<RawMesh> read_gltf(std::string_view bytes) {
  try {
    return read_gltf_document(bytes);
  } catch (const std::exception& e) {  // a member of the wrong JSON type
    return invalid_argument("json", std::string("malformed glTF: ") + e.what());
  }
}

}  // namespace gk::mesh_io
