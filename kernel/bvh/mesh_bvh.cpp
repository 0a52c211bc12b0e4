#include "kernel/bvh/mesh_bvh.h"

#include "kernel/bvh/binned_sah_builder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

namespace gk {

MeshBvh::~MeshBvh() = default;

Result<std::shared_ptr<MeshBvh>> MeshBvh::build(std::shared_ptr<const TriangleMesh> mesh,
                                                const BvhBuildOptions& options) {
  if (!mesh) return invalid_argument("mesh", "no mesh given");
  if (options.leaf_size < 1 || options.leaf_size > 64)
    return invalid_argument("leaf_size", "must be between 1 and 64");
  if (mesh->triangle_count() == 0) return invalid_argument("mesh", "has no triangles");
  if (mesh->triangle_count() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 2))
    return invalid_argument("mesh", "has more triangles than a tree can index");
  if (options.keys && options.keys->size() != mesh->triangle_count()) return invalid_argument("keys", "must have one key per triangle");
  std::shared_ptr<MeshBvh> bvh(new MeshBvh());
  bvh->mesh_ = std::move(mesh);
  BuiltTree tree = build_binned_sah(*bvh->mesh_, options.leaf_size, {options.keys, options.key_split_at});
  bvh->nodes_ = std::move(tree.nodes);
  bvh->ordered_to_mesh_ = std::move(tree.order);
  bvh->depth_ = tree.depth;
  bvh->slabs_at_any_size_ = options.slabs_at_any_size;
  bvh->order_triangles();
  return bvh;
}

void MeshBvh::order_triangles() {
  const auto& faces = mesh_->faces();
  const auto& vertices = mesh_->vertices();
  // In tree order already: the triangles in leaf order and the vertices numbered by first use.
  bool in_order = true;
  std::uint32_t next_vertex = 0;
  for (std::size_t k = 0; k < ordered_to_mesh_.size() && in_order; ++k) {
    if (ordered_to_mesh_[k] != k) in_order = false;
    for (std::uint32_t v : faces[k]) {
      if (v > next_vertex) in_order = false;
      if (v == next_vertex) ++next_vertex;
    }
  }
  if (in_order) {
    ordered_faces_.clear();
    ordered_faces_.shrink_to_fit();
    ordered_vertices_.clear();
    ordered_vertices_.shrink_to_fit();
    faces_in_order_ = faces.data();
    vertices_in_order_ = vertices.data();
    return;
  }
  constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> renumbered(vertices.size(), kUnset);
  ordered_faces_.clear();
  ordered_faces_.reserve(ordered_to_mesh_.size());
  ordered_vertices_.clear();
  ordered_vertices_.reserve(vertices.size());
  for (std::size_t k = 0; k < ordered_to_mesh_.size(); ++k) {
    const TriangleMesh::Face& f = faces[ordered_to_mesh_[k]];
    TriangleMesh::Face& ordered = ordered_faces_.emplace_back();
    for (int c = 0; c < 3; ++c) {
      std::uint32_t& r = renumbered[f[c]];
      if (r == kUnset) {
        r = static_cast<std::uint32_t>(ordered_vertices_.size());
        ordered_vertices_.push_back(vertices[f[c]]);
      }
      ordered[c] = r;
    }
  }
  ordered_vertices_.shrink_to_fit();
  faces_in_order_ = ordered_faces_.data();
  vertices_in_order_ = ordered_vertices_.data();
}

std::shared_ptr<MeshBvh> MeshBvh::in_tree_order() const {
  std::shared_ptr<MeshBvh> copy(new MeshBvh());
  copy->mesh_ = std::make_shared<const TriangleMesh>(mesh_->in_face_order(ordered_to_mesh_));
  copy->nodes_ = nodes_;
  copy->depth_ = depth_;
  copy->ordered_to_mesh_.resize(ordered_to_mesh_.size());
  for (std::size_t k = 0; k < ordered_to_mesh_.size(); ++k) copy->ordered_to_mesh_[k] = static_cast<std::uint32_t>(k);
  copy->order_triangles();
  return copy;
}

void MeshBvh::reload_vertices() {
  if (ordered_faces_.empty()) {  // the mesh is in tree order: its own arrays are read
    faces_in_order_ = mesh_->faces().data();
    vertices_in_order_ = mesh_->vertices().data();
    return;
  }
  const auto& faces = mesh_->faces();
  const auto& vertices = mesh_->vertices();
  for (std::size_t k = 0; k < ordered_to_mesh_.size(); ++k) {
    const TriangleMesh::Face& f = faces[ordered_to_mesh_[k]];
    for (int c = 0; c < 3; ++c) ordered_vertices_[ordered_faces_[k][c]] = vertices[f[c]];
  }
}

namespace {

// The format's version: 003 since nodes are 32-byte float boxes in pre-order (002 held OCCT's
// double node arrays; such files are rebuilt, never read as this layout).
constexpr char kSerialMagic[8] = {'G', 'K', 'B', 'V', 'H', '0', '0', '3'};

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
bool take(std::string_view in, std::size_t& at, T& value) {
  if (in.size() - at < sizeof(T)) return false;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

}  // namespace

std::string MeshBvh::serialize() const {
  std::string out;
  append_serialized(out);
  return out;
}

void MeshBvh::append_serialized(std::string& out) const {
  static_assert(std::is_trivially_copyable_v<BvhNode> && sizeof(BvhNode) == 6 * sizeof(float) + 2 * sizeof(std::int32_t),
                "a node's bytes are its fields in order, without padding");
  out.append(kSerialMagic, sizeof kSerialMagic);
  put(out, static_cast<std::uint64_t>(mesh_->triangle_count()));
  put(out, static_cast<std::int32_t>(nodes_.size()));
  put(out, static_cast<std::int32_t>(depth_));
  out.append(reinterpret_cast<const char*>(nodes_.data()), nodes_.size() * sizeof(BvhNode));
  out.append(reinterpret_cast<const char*>(ordered_to_mesh_.data()), ordered_to_mesh_.size() * sizeof(std::uint32_t));
}

Result<std::shared_ptr<MeshBvh>> MeshBvh::deserialize(std::shared_ptr<const TriangleMesh> mesh, std::string_view bytes) {
  if (!mesh) return invalid_argument("mesh", "no mesh given");
  auto bad = [](const std::string& why) { return invalid_argument("bytes", why); };
  if (bytes.size() < sizeof kSerialMagic || std::memcmp(bytes.data(), kSerialMagic, sizeof kSerialMagic) != 0)
    return bad("not a serialized BVH of this version");
  std::size_t at = sizeof kSerialMagic;
  std::uint64_t triangles = 0;
  std::int32_t nodes = 0, depth = 0;
  if (!take(bytes, at, triangles) || !take(bytes, at, nodes) || !take(bytes, at, depth)) return bad("truncated header");
  const std::size_t n_tri = mesh->triangle_count();
  if (triangles != n_tri || n_tri == 0) return bad("made for a mesh of another size");
  if (nodes < 1 || static_cast<std::size_t>(nodes) > 2 * n_tri || depth < 1 || depth > kMaxBvhDepth + 1)
    return bad("impossible node count or depth");
  const std::size_t need = static_cast<std::size_t>(nodes) * sizeof(BvhNode) + n_tri * sizeof(std::uint32_t);
  if (bytes.size() - at != need) return bad("wrong length");
  std::shared_ptr<MeshBvh> bvh(new MeshBvh());
  bvh->mesh_ = std::move(mesh);
  // Copied whole (no zeroing pass first): element by element when the bytes are aligned (a
  // mapped pack), else as bytes. BvhNode and the indices are plain data.
  auto copy_array = [&](auto& values, std::size_t count) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    const char* first = bytes.data() + at;
    if (reinterpret_cast<std::uintptr_t>(first) % alignof(T) == 0) {
      values.assign(reinterpret_cast<const T*>(first), reinterpret_cast<const T*>(first) + count);
    } else {
      values.resize(count);
      std::memcpy(values.data(), first, count * sizeof(T));
    }
    at += count * sizeof(T);
  };
  copy_array(bvh->nodes_, static_cast<std::size_t>(nodes));
  for (int i = 0; i < nodes; ++i) {
    const BvhNode& n = bvh->nodes_[static_cast<std::size_t>(i)];
    // Infinite bounds would hold every triangle but make centres NaN, and a NaN test rejects.
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(n.lo[a]) || !std::isfinite(n.hi[a])) return bad("node " + std::to_string(i) + " has a non-finite box");
    const bool leaf = n.count > 0;
    if (n.count < 0) return bad("node " + std::to_string(i) + " has a negative count");
    if (leaf ? (n.index < 0 || static_cast<std::size_t>(n.index) + static_cast<std::size_t>(n.count) > n_tri)
             : (n.index <= i + 1 || n.index >= nodes || i + 1 >= nodes))
      return bad("node " + std::to_string(i) + " points outside the tree");
  }
  copy_array(bvh->ordered_to_mesh_, n_tri);
  std::vector<char> seen(n_tri, 0);
  for (std::uint32_t k : bvh->ordered_to_mesh_) {
    if (k >= n_tri || seen[k]) return bad("the triangle order is not a permutation");
    seen[k] = 1;
  }
  bvh->depth_ = depth;
  bvh->order_triangles();
  // It must be a tree: from the root every node is reached once, no deeper than the builder goes
  // (the traversals' stacks are sized for that), and the leaves cover every triangle exactly once.
  // Every box must hold what it claims, compared in double, so a damaged coordinate can never
  // hide a triangle from a query.
  const auto& nd = bvh->nodes_;
  auto inside = [&](int node, const Vec3& p) {
    const BvhNode& b = nd[static_cast<std::size_t>(node)];
    for (int a = 0; a < 3; ++a)
      if (!(p[a] >= static_cast<double>(b.lo[a]) && p[a] <= static_cast<double>(b.hi[a]))) return false;
    return true;
  };
  std::vector<char> reached(static_cast<std::size_t>(nodes), 0);
  std::vector<char> covered(n_tri, 0);
  std::vector<std::pair<int, int>> stack{{0, 1}};  // node, its level (the root's 1)
  int deepest = 0;
  while (!stack.empty()) {
    const auto [i, level] = stack.back();
    stack.pop_back();
    if (reached[static_cast<std::size_t>(i)]) return bad("node " + std::to_string(i) + " has two parents");
    reached[static_cast<std::size_t>(i)] = 1;
    if (level > kMaxBvhDepth + 1) return bad("deeper than " + std::to_string(kMaxBvhDepth + 1) + " levels");
    deepest = std::max(deepest, level);
    const BvhNode& n = nd[static_cast<std::size_t>(i)];
    if (n.is_leaf()) {
      for (int k = n.first_triangle(); k <= n.last_triangle(); ++k) {
        if (covered[static_cast<std::size_t>(k)]) return bad("triangle " + std::to_string(k) + " in two leaves");
        covered[static_cast<std::size_t>(k)] = 1;
        for (const Vec3& p : bvh->ordered_triangle(k))
          if (!inside(i, p)) return bad("node " + std::to_string(i) + " does not bound its triangles");
      }
    } else {
      for (int child : {i + 1, n.second_child()}) {
        const BvhNode& c = nd[static_cast<std::size_t>(child)];
        if (!inside(i, c.lower()) || !inside(i, c.upper())) return bad("node " + std::to_string(i) + " does not bound its children");
        stack.push_back({child, level + 1});
      }
    }
  }
  if (std::find(covered.begin(), covered.end(), 0) != covered.end()) return bad("a triangle is in no leaf");
  if (depth < deepest) return bad("the stored depth is smaller than the tree's");
  return bvh;
}

OrientedBox MeshBvh::oriented_box() const {
  std::lock_guard<std::mutex> lock(oriented_box_mutex_);
  if (!oriented_box_fitted_) {
    oriented_box_ = OrientedBox::fit(mesh_->vertices());
    oriented_box_fitted_ = true;
  }
  return oriented_box_;
}

const NodeSlab* MeshBvh::node_slabs() const {
  // A small mesh's distance queries are quick without them, and its bytes per triangle are
  // already the highest (fixed costs, unshared vertices): 20 bytes a node more would pass 100.
  if (!slabs_at_any_size_ && mesh_->triangle_count() < kMinTrianglesForSlabs) return nullptr;
  if (!slabs_fitted_.load(std::memory_order_acquire)) {
    std::lock_guard<std::mutex> lock(slabs_mutex_);
    if (!slabs_fitted_.load(std::memory_order_relaxed)) {
      slabs_ = fit_node_slabs(nodes_, [this](int k) { return ordered_triangle(k); });
      slabs_fitted_.store(true, std::memory_order_release);
    }
  }
  return slabs_.data();
}

void MeshBvh::refit(std::shared_ptr<const TriangleMesh> moved_mesh) {
  {
    std::lock_guard<std::mutex> lock(oriented_box_mutex_);
    oriented_box_fitted_ = false;
  }
  {
    // A refit is never concurrent with queries on the same tree (the caller owns it meanwhile).
    std::lock_guard<std::mutex> lock(slabs_mutex_);
    slabs_fitted_.store(false, std::memory_order_release);
    slabs_.clear();
    slabs_.shrink_to_fit();
  }
  mesh_ = std::move(moved_mesh);
  reload_vertices();
  refit_nodes(nodes_, [this](int k) { return ordered_triangle(k); });
}

}  // namespace gk
