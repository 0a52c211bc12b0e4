// Sweeping rigid bodies through a motion against machine organs, conservatively:
//  - the hull level of detail: the convex hull of the bodies' hull points at sampled motion
//    parameters, inflated by the sagitta of the arc between samples, contains the whole sweep, so
//    an organ it clears is cleared for certain;
//  - the narrow phase, conservative advancement: at parameter s the exact mesh distance d to the
//    organs bounds how far the motion may go before anything can touch (no point moves faster than
//    the motion's rate), so it never steps over a contact and stops at the first one.
#pragma once

#include "kernel/mesh_bvh.h"
#include "kernel/rigid_transform.h"
#include "machine_models/p4/machine_scene.h"

#include <memory>
#include <vector>

namespace gk::p4 {

// A rigid motion parameterised by s in [0, 1].
struct Motion {
  bool rotation = true;
  Vec3 axis_point = Vec3::Zero();
  Vec3 axis_direction = Vec3::UnitX();  // unit
  double angle_rad = 0.0;               // signed
  Vec3 travel = Vec3::Zero();           // translations

  RigidTransform at(double s) const;
  // Largest speed (mm per unit s) of any of the points.
  double rate(const std::vector<Vec3>& points) const;
};

// A body in machine coordinates at s = 0, with the hull points it is bounded by.
struct MovingBody {
  std::shared_ptr<MeshBvh> mesh;
  std::vector<Vec3> points;  // its vertices (the hull is taken over them)
};

// An organ as the sweep sees it: its mesh and its pose for this step.
struct SweepOrgan {
  int index = 0;  // in MachineScene::organs()
  const MeshBvh* mesh = nullptr;
  RigidTransform pose;
};

struct HullLodResult {
  std::vector<int> remaining;  // indices into the organ list that the hull could not clear
  double sagitta_mm = 0.0;
  int samples = 0;
};

// The hull level of detail. max_sample_step_rad bounds the angle between samples.
Result<HullLodResult> hull_lod(const std::vector<MovingBody>& bodies, const Motion& motion,
                               const std::vector<SweepOrgan>& organs, double clearance_mm, double max_sample_step_rad);

// A box containing the whole sweep (for the global box test and the broad phase).
Aabb swept_bounds(const std::vector<MovingBody>& bodies, const Motion& motion, double max_sample_step_rad);

struct SweepOutcome {
  bool collided = false;
  bool budget_exceeded = false;   // too many advancement steps: the answer is inconclusive
  double contact_s = 1.0;         // first parameter where the clearance fell to the required one
  int organ = -1;                 // index into the organ list of the organ reached
  Vec3 point_on_body = Vec3::Zero(), point_on_organ = Vec3::Zero();  // machine coordinates
  Vec3 normal = Vec3::Zero();     // at contact: from the organ towards the body, before they met
  double min_clearance_mm = std::numeric_limits<double>::infinity();  // smallest sampled clearance
  double certified_clearance_mm = std::numeric_limits<double>::infinity();  // a proven lower bound
  int min_clearance_organ = -1;
  double min_clearance_s = 0.0;
  Vec3 min_clearance_point = Vec3::Zero();
  int steps = 0;
};

struct AdvanceOptions {
  double required_clearance_mm = 0.1;  // closer than this counts as a collision
  // Advancement converges on a contact from above: within this of the required clearance it is
  // called a contact (the first-contact parameter is then exact to this distance). [mm]
  double contact_resolution_mm = 1e-3;
  double step_fraction = 0.8;          // of the proven-safe advance taken per step (certifies 1 - f)
  int max_steps = 20000;
  // When > 0, each body's own swept hull (sampled at most this far apart) first clears the organs
  // it can: only the pairs it cannot clear are advanced. [rad]
  double body_hull_step_rad = 0.0;
};

Result<SweepOutcome> conservative_advance(const std::vector<MovingBody>& bodies, const Motion& motion,
                                          const std::vector<SweepOrgan>& organs, const AdvanceOptions& options);

}  // namespace gk::p4
