#include "kernel/mesh_bvh.h"

#include <BVH_BinnedBuilder.hxx>
#include <BVH_LinearBuilder.hxx>
#include <BVH_Set.hxx>
#include <BVH_Tree.hxx>

#include <numeric>

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
  // Small meshes (machine organs, sheet plates) build several times faster with 8 SAH bins, and
  // their trees are as good; large meshes get 32.
  if (bvh->mesh_->triangle_count() <= 512) {
    const BVH_BinnedBuilder<double, 3, 8> builder(options.leaf_size, BVH_Constants_MaxTreeDepth);
    builder.Build(bvh->impl_->set.get(), &bvh->impl_->tree, root);
  } else {
    const BVH_BinnedBuilder<double, 3, 32> builder(options.leaf_size, BVH_Constants_MaxTreeDepth);
    builder.Build(bvh->impl_->set.get(), &bvh->impl_->tree, root);
  }
  bvh->reload_corners();
  bvh->reload_node_boxes();
  return bvh;
}

void MeshBvh::refit(std::shared_ptr<const TriangleMesh> moved_mesh) {
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
int MeshBvh::depth() const { return impl_->tree.Depth(); }

Aabb MeshBvh::root_bounds() const {
  const auto& t = impl_->tree;
  const auto& lo = t.MinPoint(0);
  const auto& hi = t.MaxPoint(0);
  return {Vec3(lo.x(), lo.y(), lo.z()), Vec3(hi.x(), hi.y(), hi.z())};
}

}  // namespace gk
