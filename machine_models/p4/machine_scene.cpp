#include "machine_models/p4/machine_scene.h"

#include "machine_models/p4/organ_geometry.h"

#include <BVH_BinnedBuilder.hxx>
#include <BVH_LinearBuilder.hxx>
#include <BVH_Set.hxx>
#include <BVH_Tree.hxx>

#include <algorithm>
#include <map>
#include <numeric>

namespace gk::p4 {
namespace {

// The organs' boxes as an OCCT BVH_Set; the builder permutes `order`.
class OrganBoxSet final : public BVH_Set<double, 3> {
 public:
  OrganBoxSet(const std::vector<Organ>& organs, std::vector<int>& order) : organs_(&organs), order_(&order) {}
  Standard_Integer Size() const override { return static_cast<Standard_Integer>(order_->size()); }
  BVH_Box<double, 3> Box(const Standard_Integer i) const override {
    const Aabb& b = (*organs_)[(*order_)[i]].box;
    return BVH_Box<double, 3>(BVH_Vec3d(b.min.x(), b.min.y(), b.min.z()), BVH_Vec3d(b.max.x(), b.max.y(), b.max.z()));
  }
  double Center(const Standard_Integer i, const Standard_Integer axis) const override {
    return (*organs_)[(*order_)[i]].box.center()[axis];
  }
  void Swap(const Standard_Integer a, const Standard_Integer b) override { std::swap((*order_)[a], (*order_)[b]); }

 private:
  const std::vector<Organ>* organs_;
  std::vector<int>* order_;
};


}  // namespace

struct MachineScene::Tree {
  BVH_Tree<double, 3> tree;
  std::vector<int> order;
  std::unique_ptr<OrganBoxSet> set;
};

MachineScene::~MachineScene() = default;

Result<std::shared_ptr<MachineScene>> MachineScene::build(const MachineModel& model) {
  std::shared_ptr<MachineScene> scene(new MachineScene());
  scene->model_ = model;
  // Segments of equal width share one mesh and one BVH.
  std::map<double, std::shared_ptr<MeshBvh>> by_width;
  for (std::size_t i = 0; i < model.aba.segment_widths_mm.size(); ++i) {
    const double w = model.aba.segment_widths_mm[i];
    auto& shared = by_width[w];
    if (!shared) {
      auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(prism_mesh(model.aba.profile_yz_mm, 0.0, w)));
      if (!bvh.ok()) return bvh.error();
      shared = bvh.value();
    }
    Organ o;
    o.name = "aba.segment." + std::to_string(i);
    o.is_aba_segment = true;
    o.relative_to_clamp = true;
    o.slot = i;
    o.mesh = shared;
    o.profile_yz = model.aba.profile_yz_mm;
    o.x_min = 0.0;
    o.x_max = w;
    scene->organs_.push_back(std::move(o));
  }
  for (const PrismOrganSpec& spec : model.organs) {
    auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(prism_mesh(spec.profile_yz_mm, spec.x_min_mm, spec.x_max_mm)));
    if (!bvh.ok()) return bvh.error();
    Organ o;
    o.name = spec.name;
    o.support = spec.support;
    o.relative_to_clamp = spec.relative_to_clamp;
    o.mesh = bvh.value();
    o.profile_yz = spec.profile_yz_mm;
    o.x_min = spec.x_min_mm;
    o.x_max = spec.x_max_mm;
    scene->organs_.push_back(std::move(o));
  }
  MachineState initial;
  initial.engaged_segments.assign(model.aba.segment_widths_mm.size(), true);
  initial.manipulator_y_mm = std::clamp(initial.manipulator_y_mm, model.manipulator.travel_y_mm[0], model.manipulator.travel_y_mm[1]);
  scene->state_ = initial;
  scene->place_organs();
  scene->rebuild_tree();
  return scene;
}

void MachineScene::place_organs() {
  std::size_t spec_index = 0;
  const auto spans = model_.slot_spans();
  for (Organ& o : organs_) {
    Vec3 offset = Vec3::Zero();
    if (o.is_aba_segment) {
      o.engaged = state_.engaged_segments.empty() || state_.engaged_segments[o.slot];
      offset = Vec3(spans[o.slot].first, 0.0, state_.clamp_z_mm + (o.engaged ? 0.0 : model_.aba.retract_z_mm));
    } else {
      const PrismOrganSpec& spec = model_.organs[spec_index++];
      if (spec.relative_to_clamp) offset.z() = state_.clamp_z_mm;
      if (spec.name == "blade.lower") offset.z() += state_.lower_blade_z_offset_mm;
    }
    o.pose = RigidTransform::from_translation(offset);
    o.box = transformed_box(o.mesh->root_bounds(), o.pose);
  }
}

void MachineScene::rebuild_tree() {
  tree_ = std::make_unique<Tree>();
  tree_->order.resize(organs_.size());
  std::iota(tree_->order.begin(), tree_->order.end(), 0);
  tree_->set = std::make_unique<OrganBoxSet>(organs_, tree_->order);
  BVH_Box<double, 3> root;
  for (const Organ& o : organs_) {
    root.Add(BVH_Vec3d(o.box.min.x(), o.box.min.y(), o.box.min.z()));
    root.Add(BVH_Vec3d(o.box.max.x(), o.box.max.y(), o.box.max.z()));
  }
  const BVH_BinnedBuilder<double, 3, 32> builder(1, BVH_Constants_MaxTreeDepth);
  builder.Build(tree_->set.get(), &tree_->tree, root);
}

Result<bool> MachineScene::apply_state(const MachineState& state) {
  auto valid = validate_state(model_, state);
  if (!valid.ok()) return valid;
  state_ = state;
  place_organs();
  // Retracted segments stay near their slot (they rise by retract_z), so the refitted boxes stay
  // tight: the tree is as good as a rebuilt one.
  BVH::UpdateBounds<double, 3>(tree_->set.get(), &tree_->tree, 0);
  return true;
}

std::vector<int> MachineScene::organs_overlapping(const Aabb& box) const {
  std::vector<int> out;
  const auto& t = tree_->tree;
  if (t.Length() == 0) return out;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int n = stack[--top];
    const auto& lo = t.MinPoint(n);
    const auto& hi = t.MaxPoint(n);
    if (hi.x() < box.min.x() || lo.x() > box.max.x() || hi.y() < box.min.y() || lo.y() > box.max.y() ||
        hi.z() < box.min.z() || lo.z() > box.max.z())
      continue;
    if (t.IsOuter(n)) {
      for (int k = t.BegPrimitive(n); k <= t.EndPrimitive(n); ++k)
        if (organs_[tree_->order[k]].box.overlaps(box)) out.push_back(tree_->order[k]);
    } else {
      stack[top++] = t.Child<0>(n);
      stack[top++] = t.Child<1>(n);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}


}  // namespace gk::p4
