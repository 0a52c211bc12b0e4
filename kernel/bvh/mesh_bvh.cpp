#include "kernel/bvh/mesh_bvh.h"

#include <BVH_BinnedBuilder.hxx>
#include <BVH_LinearBuilder.hxx>
#include <BVH_Set.hxx>
#include <BVH_Tree.hxx>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <string>

namespace gk {
namespace {

// The triangles as an OCCT BVH_Set: the builder reorders it through Swap(), and we keep the
// permutation to map tree order back to mesh triangle indices.
class TriangleSet final : public BVH_Set<double, 3> {
 public:
  TriangleSet(const TriangleMesh& mesh, std::vector<std::uint32_t>& order) : mesh_(&mesh), order_(&order) {}
  void set_mesh(const TriangleMesh& mesh) { mesh_ = &mesh; }

  Standard_Integer Size() const override { return static_cast<Standard_Integer>(order_->size()); }

  BVH_Box<double, 3> Box(const Standard_Integer index) const override {
    const TriangleMesh::Face& f = mesh_->faces()[(*order_)[index]];
    BVH_Box<double, 3> box;
    for (std::uint32_t v : f) {
      const Vec3& p = mesh_->vertices()[v];
      box.Add(BVH_Vec3d(p.x(), p.y(), p.z()));
    }
    return box;
  }

  double Center(const Standard_Integer index, const Standard_Integer axis) const override {
    const TriangleMesh::Face& f = mesh_->faces()[(*order_)[index]];
    const auto& v = mesh_->vertices();
    return (v[f[0]][axis] + v[f[1]][axis] + v[f[2]][axis]) / 3.0;
  }

  void Swap(const Standard_Integer a, const Standard_Integer b) override { std::swap((*order_)[a], (*order_)[b]); }

 private:
  const TriangleMesh* mesh_;
  std::vector<std::uint32_t>* order_;
};

// Up to this many triangles a mesh's tree is built by median splits (see MeshBvh::build).
constexpr std::size_t kMedianSplitMaxTriangles = 192;

// Pre-order: every node's children come after it, as in the trees OCCT's builders make. Returns
// the depth as OCCT counts it (levels, the root's being 1).
int build_by_median_split(const TriangleMesh& mesh, int leaf_size, std::vector<std::uint32_t>& order, BVH_Tree<double, 3>& tree) {
  const std::size_t n = order.size();
  std::vector<Aabb> boxes(n);
  std::vector<Vec3> centres(n);
  for (std::size_t t = 0; t < n; ++t) {
    for (std::uint32_t v : mesh.faces()[t]) boxes[t].extend(mesh.vertices()[v]);
    centres[t] = boxes[t].center();
  }
  tree.Clear();
  tree.Reserve(static_cast<int>(2 * n));
  int depth = 0;
  struct Builder {
    const std::vector<Aabb>& boxes;
    const std::vector<Vec3>& centres;
    std::vector<std::uint32_t>& order;
    BVH_Tree<double, 3>& tree;
    int leaf_size;
    int& depth;
    int build(std::size_t lo, std::size_t hi, int level) {
      depth = std::max(depth, level);
      Aabb box, spread;
      for (std::size_t i = lo; i < hi; ++i) {
        box.extend(boxes[order[i]]);
        spread.extend(centres[order[i]]);
      }
      const BVH_Vec3d bmin(box.min.x(), box.min.y(), box.min.z()), bmax(box.max.x(), box.max.y(), box.max.z());
      const Vec3 extent = spread.max - spread.min;
      int axis = 0;
      extent.maxCoeff(&axis);
      if (hi - lo <= static_cast<std::size_t>(leaf_size) || level >= BVH_Constants_MaxTreeDepth - 1 || !(extent[axis] > 0.0)) {
        const int leaf = tree.AddLeafNode(bmin, bmax, static_cast<int>(lo), static_cast<int>(hi) - 1);
        tree.NodeInfoBuffer()[leaf].w() = level;
        return leaf;
      }
      const int node = tree.AddInnerNode(bmin, bmax, 0, 0);
      tree.NodeInfoBuffer()[node].w() = level;
      const std::size_t mid = lo + (hi - lo) / 2;
      std::nth_element(order.begin() + static_cast<std::ptrdiff_t>(lo), order.begin() + static_cast<std::ptrdiff_t>(mid),
                       order.begin() + static_cast<std::ptrdiff_t>(hi),
                       [&](std::uint32_t a, std::uint32_t b) { return centres[a][axis] < centres[b][axis]; });
      const int left = build(lo, mid, level + 1);
      const int right = build(mid, hi, level + 1);
      tree.ChangeChild<0>(node) = left;
      tree.ChangeChild<1>(node) = right;
      return node;
    }
  } builder{boxes, centres, order, tree, leaf_size, depth};
  builder.build(0, n, 0);
  return depth + 1;
}

}  // namespace

struct MeshBvh::Impl {
  BVH_Tree<double, 3> tree;
  std::unique_ptr<TriangleSet> set;
};

MeshBvh::~MeshBvh() = default;

Result<std::shared_ptr<MeshBvh>> MeshBvh::build(std::shared_ptr<const TriangleMesh> mesh,
                                                const BvhBuildOptions& options) {
  if (!mesh) return invalid_argument("mesh", "no mesh given");
  if (options.leaf_size < 1 || options.leaf_size > 64)
    return invalid_argument("leaf_size", "must be between 1 and 64");
  std::shared_ptr<MeshBvh> bvh(new MeshBvh());
  bvh->mesh_ = std::move(mesh);
  bvh->impl_ = std::make_unique<Impl>();
  bvh->ordered_to_mesh_.resize(bvh->mesh_->triangle_count());
  std::iota(bvh->ordered_to_mesh_.begin(), bvh->ordered_to_mesh_.end(), 0u);
  bvh->impl_->set = std::make_unique<TriangleSet>(*bvh->mesh_, bvh->ordered_to_mesh_);

  BVH_Box<double, 3> root;
  const Aabb bounds = bvh->mesh_->bounds();
  root.Add(BVH_Vec3d(bounds.min.x(), bounds.min.y(), bounds.min.z()));
  root.Add(BVH_Vec3d(bounds.max.x(), bounds.max.y(), bounds.max.z()));
  // Tiny meshes (the boxes of a machine's bodies, rebuilt for every step) are split at the median
  // directly into OCCT's tree: the SAH builder's queue and bins cost more than the queries they
  // save. Small meshes (machine organs, sheet plates) build several times faster with 8 SAH
  // bins, and their trees are as good; large meshes get 32.
  if (bvh->mesh_->triangle_count() > 0 && bvh->mesh_->triangle_count() <= kMedianSplitMaxTriangles) {
    bvh->depth_ = build_by_median_split(*bvh->mesh_, options.leaf_size, bvh->ordered_to_mesh_, bvh->impl_->tree);
    bvh->reload_corners();
    bvh->reload_node_boxes();
    return bvh;
  }
  if (bvh->mesh_->triangle_count() <= 512) {
    const BVH_BinnedBuilder<double, 3, 8> builder(options.leaf_size, BVH_Constants_MaxTreeDepth);
    builder.Build(bvh->impl_->set.get(), &bvh->impl_->tree, root);
  } else {
    const BVH_BinnedBuilder<double, 3, 32> builder(options.leaf_size, BVH_Constants_MaxTreeDepth);
    builder.Build(bvh->impl_->set.get(), &bvh->impl_->tree, root);
  }
  bvh->depth_ = bvh->impl_->tree.Depth();
  bvh->reload_corners();
  bvh->reload_node_boxes();
  return bvh;
}

namespace {

// The format's version: 002 since trees have 4 triangles per leaf (a file of 001 holds a valid
// tree of 1 per leaf, but is rebuilt rather than kept slower).
constexpr char kSerialMagic[8] = {'G', 'K', 'B', 'V', 'H', '0', '0', '2'};

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
bool take(const std::string& in, std::size_t& at, T& value) {
  if (in.size() - at < sizeof(T)) return false;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

}  // namespace

std::string MeshBvh::serialize() const {
  const auto& t = impl_->tree;
  std::string out(kSerialMagic, sizeof kSerialMagic);
  put(out, static_cast<std::uint64_t>(mesh_->triangle_count()));
  put(out, static_cast<std::int32_t>(t.Length()));
  put(out, static_cast<std::int32_t>(depth_));
  for (int i = 0; i < t.Length(); ++i) {
    const auto& lo = t.MinPoint(i);
    const auto& hi = t.MaxPoint(i);
    const auto& info = t.NodeInfoBuffer()[i];
    for (double v : {lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()}) put(out, v);
    for (int v : {info.x(), info.y(), info.z(), info.w()}) put(out, static_cast<std::int32_t>(v));
  }
  for (std::uint32_t k : ordered_to_mesh_) put(out, k);
  return out;
}

Result<std::shared_ptr<MeshBvh>> MeshBvh::deserialize(std::shared_ptr<const TriangleMesh> mesh, const std::string& bytes) {
  if (!mesh) return invalid_argument("mesh", "no mesh given");
  auto bad = [](const std::string& why) { return invalid_argument("bytes", why); };
  if (bytes.size() < sizeof kSerialMagic || std::memcmp(bytes.data(), kSerialMagic, sizeof kSerialMagic) != 0)
    return bad("not a serialized BVH of this version");
  std::size_t at = sizeof kSerialMagic;
  std::uint64_t triangles = 0;
  std::int32_t nodes = 0, depth = 0;
  if (!take(bytes, at, triangles) || !take(bytes, at, nodes) || !take(bytes, at, depth)) return bad("truncated header");
  const std::size_t n_tri = mesh->triangle_count();
  if (triangles != n_tri) return bad("made for a mesh of another size");
  if (nodes < 1 || static_cast<std::size_t>(nodes) > 2 * n_tri + 1 || depth < 0 || depth > 1024) return bad("impossible node count or depth");
  const std::size_t need = static_cast<std::size_t>(nodes) * (6 * sizeof(double) + 4 * sizeof(std::int32_t)) + n_tri * sizeof(std::uint32_t);
  if (bytes.size() - at != need) return bad("wrong length");
  std::shared_ptr<MeshBvh> bvh(new MeshBvh());
  bvh->mesh_ = std::move(mesh);
  bvh->impl_ = std::make_unique<Impl>();
  auto& t = bvh->impl_->tree;
  t.Reserve(nodes);
  for (int i = 0; i < nodes; ++i) {
    double v[6] = {};
    std::int32_t info[4] = {};
    for (double& x : v) take(bytes, at, x);
    for (std::int32_t& x : info) take(bytes, at, x);
    for (double x : v)
      if (!std::isfinite(x)) return bad("non-finite box");
    const bool leaf = info[0] != 0;
    if (leaf ? (info[1] < 0 || info[2] < info[1] || static_cast<std::size_t>(info[2]) >= n_tri)
             : (info[1] <= i || info[2] <= i || info[1] >= nodes || info[2] >= nodes))
      return bad("node " + std::to_string(i) + " points outside the tree");
    const BVH_Vec3d lo(v[0], v[1], v[2]), hi(v[3], v[4], v[5]);
    if (leaf) t.AddLeafNode(lo, hi, info[1], info[2]);
    else t.AddInnerNode(lo, hi, info[1], info[2]);
    t.NodeInfoBuffer().back().w() = info[3];
  }
  bvh->ordered_to_mesh_.resize(n_tri);
  std::vector<char> seen(n_tri, 0);
  for (std::uint32_t& k : bvh->ordered_to_mesh_) {
    take(bytes, at, k);
    if (k >= n_tri || seen[k]) return bad("the triangle order is not a permutation");
    seen[k] = 1;
  }
  bvh->impl_->set = std::make_unique<TriangleSet>(*bvh->mesh_, bvh->ordered_to_mesh_);
  bvh->depth_ = depth;
  bvh->reload_corners();
  // It must be a tree: from the root every node is reached once, no deeper than OCCT builds (the
  // traversals' stacks are sized for that), and the leaves cover every triangle exactly once.
  // Every box must hold what it claims (the builder's boxes are exact minima and maxima), so a
  // damaged coordinate can never hide a triangle from a query.
  auto inside = [&](int node, const Vec3& p) {
    const auto& lo = t.MinPoint(node);
    const auto& hi = t.MaxPoint(node);
    return p.x() >= lo.x() && p.y() >= lo.y() && p.z() >= lo.z() && p.x() <= hi.x() && p.y() <= hi.y() && p.z() <= hi.z();
  };
  std::vector<char> reached(static_cast<std::size_t>(nodes), 0);
  std::vector<char> covered(n_tri, 0);
  std::vector<std::pair<int, int>> stack{{0, 0}};  // node, its depth
  int deepest = 0;
  while (!stack.empty()) {
    const auto [i, level] = stack.back();
    stack.pop_back();
    if (reached[i]) return bad("node " + std::to_string(i) + " has two parents");
    reached[i] = 1;
    if (level > BVH_Constants_MaxTreeDepth) return bad("deeper than " + std::to_string(BVH_Constants_MaxTreeDepth) + " levels");
    deepest = std::max(deepest, level);
    const auto& info = t.NodeInfoBuffer()[i];
    if (info.x() != 0) {
      for (int k = info.y(); k <= info.z(); ++k) {
        if (covered[k]) return bad("triangle " + std::to_string(k) + " in two leaves");
        covered[k] = 1;
        for (const Vec3& p : bvh->ordered_corners_[k])
          if (!inside(i, p)) return bad("node " + std::to_string(i) + " does not bound its triangles");
      }
    } else {
      for (int child : {info.y(), info.z()}) {
        const auto& lo = t.MinPoint(child);
        const auto& hi = t.MaxPoint(child);
        if (!inside(i, Vec3(lo.x(), lo.y(), lo.z())) || !inside(i, Vec3(hi.x(), hi.y(), hi.z())))
          return bad("node " + std::to_string(i) + " does not bound its children");
        stack.push_back({child, level + 1});
      }
    }
  }
  if (std::find(covered.begin(), covered.end(), 0) != covered.end()) return bad("a triangle is in no leaf");
  if (depth < deepest) return bad("the stored depth is smaller than the tree's");
  bvh->reload_node_boxes();
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

void MeshBvh::refit(std::shared_ptr<const TriangleMesh> moved_mesh) {
  {
    std::lock_guard<std::mutex> lock(oriented_box_mutex_);
    oriented_box_fitted_ = false;
  }
  mesh_ = std::move(moved_mesh);
  impl_->set->set_mesh(*mesh_);
  if (impl_->tree.Length() > 0) BVH::UpdateBounds<double, 3>(impl_->set.get(), &impl_->tree, 0);
  reload_corners();
  reload_node_boxes();
}

void MeshBvh::reload_node_boxes() {
  const auto& t = impl_->tree;
  const int n = t.Length();
  node_center_.resize(n);
  node_half_.resize(n);
  for (int i = 0; i < n; ++i) {
    const auto& lo = t.MinPoint(i);
    const auto& hi = t.MaxPoint(i);
    node_center_[i] = Vec3(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), 0.5 * (lo.z() + hi.z()));
    node_half_[i] = Vec3(0.5 * (hi.x() - lo.x()), 0.5 * (hi.y() - lo.y()), 0.5 * (hi.z() - lo.z()));
  }
}

void MeshBvh::reload_corners() {
  ordered_corners_.resize(ordered_to_mesh_.size());
  for (std::size_t k = 0; k < ordered_to_mesh_.size(); ++k) ordered_corners_[k] = mesh_->triangle(ordered_to_mesh_[k]);
}

MeshBvh::NodeView MeshBvh::nodes() const {
  const auto& t = impl_->tree;
  return {t.MinPointBuffer().data(), t.MaxPointBuffer().data(), t.NodeInfoBuffer().data()};
}

int MeshBvh::node_count() const { return impl_->tree.Length(); }
int MeshBvh::depth() const { return depth_; }

Aabb MeshBvh::root_bounds() const {
  const auto& t = impl_->tree;
  const auto& lo = t.MinPoint(0);
  const auto& hi = t.MaxPoint(0);
  return {Vec3(lo.x(), lo.y(), lo.z()), Vec3(hi.x(), hi.y(), hi.z())};
}

}  // namespace gk
