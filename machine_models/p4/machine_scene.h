// The machine's organs placed for a state, under an OCCT BVH_Tree of their boxes that is refitted
// (BVH::UpdateBounds), never rebuilt, when the state changes.
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/machine_state.h"

#include <memory>
#include <string>
#include <vector>

namespace gk::p4 {

struct Organ {
  std::string name;               // e.g. "aba.segment.12", "bed", "tower.left"
  bool is_aba_segment = false;
  std::size_t slot = 0;           // ABA slot, for segments
  bool support = false;           // intended contact: the part rests on it
  bool relative_to_clamp = false; // rises with the blankholder (ABA segments, upper beam)
  bool engaged = true;            // ABA segments: clamping (false: retracted upwards)
  std::shared_ptr<MeshBvh> mesh;  // in the organ's own frame
  std::vector<Vec2> profile_yz;   // convex profile of the prism, in the organ's frame
  double x_min = 0.0, x_max = 0.0;
  RigidTransform pose;            // organ frame -> machine frame, for the current state
  Aabb box;                       // machine-frame bounds for the current state
};

class MachineScene {
 public:
  static Result<std::shared_ptr<MachineScene>> build(const MachineModel& model);

  // Places every organ for the state and refits the organ tree (topology unchanged).
  Result<bool> apply_state(const MachineState& state);
  // Rebuilds the tree from scratch (for tests that compare refit with rebuild).
  void rebuild_tree();

  const MachineModel& model() const { return model_; }
  const MachineState& state() const { return state_; }
  const std::vector<Organ>& organs() const { return organs_; }
  // Organs whose box overlaps the query box (by a tree traversal), ascending index order.
  std::vector<int> organs_overlapping(const Aabb& box) const;

  struct Tree;
  ~MachineScene();
  MachineScene(const MachineScene&) = delete;
  MachineScene& operator=(const MachineScene&) = delete;

 private:
  MachineScene() = default;
  void place_organs();

  MachineModel model_;
  MachineState state_;
  std::vector<Organ> organs_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace gk::p4
