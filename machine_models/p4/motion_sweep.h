// Sweeping rigid bodies through a motion against machine organs, conservatively:
//  - the hull level of detail: the convex hull of the bodies' hull points at sampled motion
//    parameters, inflated by the sagitta of the arc between samples, contains the whole sweep, so
//    an organ it clears is cleared for certain;
//  - the narrow phase, conservative advancement: at parameter s the exact mesh distance d to the
//    organs bounds how far the motion may go before anything can touch (no point moves faster than
//    the motion's rate), so it never steps over a contact and stops at the first one.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "machine_models/p4/convex_polytope.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/sheet_part.h"
#include "kernel/core/tolerances.h"

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
  std::vector<Plate> plates; // the boxes it is made of (empty for a surface), for penetration depths
};

// An organ as the sweep sees it: its mesh and its pose for this step.
struct SweepOrgan {
  int index = 0;  // in MachineScene::organs()
  const MeshBvh* mesh = nullptr;
  RigidTransform pose;
  // The organ's vertices as a convex polytope in machine coordinates, when known: separating axes
  // against a plate body bound the distance from below before a mesh query is spent.
  const ConvexPolytope* shape = nullptr;
};

struct HullLodResult {
  std::vector<int> remaining;  // indices into the organ list that the hull could not clear
  // Per organ: a proven lower bound of its distance from the sweep (0 for those remaining). [mm]
  std::vector<double> lower_bound_mm;
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
  int organ = -1;                 // index into the organ (or pair) list of the organ reached
  Vec3 point_on_body = Vec3::Zero(), point_on_organ = Vec3::Zero();  // machine coordinates
  Vec3 normal = Vec3::Zero();     // at contact: from the organ towards the body, before they met
  double min_clearance_mm = std::numeric_limits<double>::infinity();  // smallest sampled clearance
  int min_clearance_organ = -1;   // index into the organ (or pair) list
  double min_clearance_s = 0.0;
  Vec3 min_clearance_point = Vec3::Zero();
  int steps = 0;
  // Per pair (the pairs overload): a proven lower bound of that pair's clearance over the motion
  // (up to where its advancement stopped). [mm]
  std::vector<double> pair_lower_mm;
};

struct AdvanceOptions {
  double required_clearance_mm = 0.1;  // closer than this counts as a collision
  // Advancement converges on a contact from above: within this of the required clearance it is
  // called a contact (the first-contact parameter is then exact to this distance). [mm]
  double contact_resolution_mm = tolerances::kStepContactResolutionMm;
  double step_fraction = 0.8;          // of the proven-safe advance taken per step (certifies 1 - f)
  int max_steps = 20000;
  // When > 0, each body's own swept hull (sampled at most this far apart) first clears the organs
  // it can: only the pairs it cannot clear are advanced. [rad]
  double body_hull_step_rad = 0.0;
};

Result<SweepOutcome> conservative_advance(const std::vector<MovingBody>& bodies, const Motion& motion,
                                          const std::vector<SweepOrgan>& organs, const AdvanceOptions& options);

// One body against one organ: the sweep checks exactly the pairs it is given (a step decides which
// version of a body meets which organ, e.g. only what hangs below a support's top face).
struct SweepPair {
  const MovingBody* body = nullptr;
  SweepOrgan organ;
};
// The same advancement over explicit pairs; the outcome's organ indices are pair indices.
Result<SweepOutcome> conservative_advance(const std::vector<SweepPair>& pairs, const Motion& motion,
                                          const AdvanceOptions& options);

// The smallest clearance over the whole motion between one body and the nearest of the organs,
// bracketed:
// `lower_mm` is proven (the distance is 1-Lipschitz in the points' positions, which move at most
// `rate` per unit of s), `upper_mm` was measured at `at_s`. Intervals are split (where their two
// Lipschitz cones meet: Piyavskii-Shubert) until the lower bound is within tolerance_mm (or
// tolerance_relative of it, whichever is larger) of the smaller of `upper_mm` and known_upper_mm (a clearance measured elsewhere: this body cannot hold
// the minimum then), reaches window_mm (farther does not matter) or max_queries were made. With
// the organ's convex pieces (obstacle_shapes, machine coordinates) and a body made of plates, an
// interval is also bounded by its swept hull, which converges much faster near a minimum.
struct ClearanceBracket {
  double lower_mm = 0.0;
  double upper_mm = std::numeric_limits<double>::infinity();
  double at_s = 0.0;
  Vec3 point_on_body = Vec3::Zero();
  int organ = -1;   // index into the organ list of the nearest one at the measured minimum
  int queries = 0;  // samples of s measured (each against every organ)
};
Result<ClearanceBracket> clearance_bracket(const MovingBody& body, const Motion& motion, const std::vector<SweepOrgan>& organs,
                                           double window_mm, double tolerance_mm, double tolerance_relative, int max_queries,
                                           double known_upper_mm = std::numeric_limits<double>::infinity(),
                                           const std::vector<ConvexPolytope>* obstacle_shapes = nullptr);

}  // namespace gk::p4
