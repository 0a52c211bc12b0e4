// Real-time layout (seed 000, scenario 1): one object dragged among many static ones, answered
// per frame. Three levels keep a frame cheap:
//  1. an incremental broad phase: static boxes sit in a uniform grid (oversized ones in a short
//     list); the moving box's cell range is remapped each frame and the gathered candidates are
//     reused while it stays the same;
//  2. the separating axis of each candidate pair, cached from the previous frame: the oriented
//     boxes of both objects projected on it usually still show a gap of at least the clearance
//     (then the pair is clear without further work); otherwise all 15 box axes are tried and the
//     best one is cached;
//  3. for a pair that collided last frame, the triangle pair that crossed then: if it still
//     crosses (one exact triangle test), the pair is a COLLISION there;
//  4. the exact verdict and distance (kernel/query/contact_verdict) for the pairs left, split
//     between the calling thread and the session's second one when there are several.
#pragma once

#include "kernel/query/contact_verdict.h"
#include "kernel/mesh/oriented_box.h"
#include "engine/audits/scene_audit.h"
#include "engine/scenes/second_hand.h"
#include "kernel/broadphase/uniform_grid.h"
#include "kernel/core/stop_token.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

namespace gk::engine {

struct FrameContact {
  std::uint32_t other = 0;  // index of the static object
  Verdict verdict = Verdict::kClear;
  double distance_mm = 0.0;
  Vec3 point = Vec3::Zero(), other_point = Vec3::Zero();  // witnesses (moving, static)
};

struct FrameAnswer {
  Verdict worst = Verdict::kClear;       // over the contacts (CLEAR when none)
  std::vector<FrameContact> contacts;    // collisions, touches, and pairs closer than the clearance
  unsigned candidates = 0;               // static boxes met by the moving box (grown by the clearance)
  unsigned axis_cache_hits = 0;          // ... cleared by last frame's separating axis
  unsigned box_axis_clears = 0;          // ... cleared by a newly found box axis
  unsigned crossing_cache_hits = 0;      // ... found still colliding at last frame's crossing triangles
  unsigned exact_checks = 0;             // ... decided on the meshes
};

class LayoutSession {
 public:
  // `objects` are the scene; `moving` the one being dragged (its pose in `objects` is the start).
  static Result<std::unique_ptr<LayoutSession>> create(std::vector<AuditObject> objects, std::uint32_t moving,
                                                       double clearance_mm);
  // `stop`: a caller that gave up (deadline, cancel) ends the frame (kStopped) before its next exact check.
  Result<FrameAnswer> move_to(const RigidTransform& pose, const StopToken& stop = {});
  const AuditObject& moving() const { return objects_[moving_]; }
  std::uint32_t moving_index() const { return moving_; }
  const RigidTransform& pose_of(std::uint32_t object) const { return objects_[object].pose; }

 private:
  LayoutSession() = default;
  void gather(const GridCellRange& range);

  std::vector<AuditObject> objects_;
  std::uint32_t moving_ = 0;
  double clearance_mm_ = 0.0;
  double needed_gap_mm_ = 0.0;          // a box gap beyond this clears a pair
  std::vector<Aabb> boxes_;             // static objects' world boxes
  std::vector<OrientedBox> obbs_;       // static objects' world oriented boxes
  OrientedBox moving_local_obb_;        // in the moving mesh's frame
  std::unique_ptr<UniformGrid> grid_;    // the static objects (the moving one left out)
  GridCellRange last_range_{{1, 1, 1}, {0, 0, 0}};
  std::vector<std::uint32_t> gathered_;  // static objects in the last cell range (and oversized)
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_now_ = 0;
  std::unordered_map<std::uint32_t, Vec3> separating_axis_;  // per static object: last frame's axis
  std::unordered_map<std::uint32_t, std::pair<std::uint32_t, std::uint32_t>> crossing_;  // last frame's crossing triangles
  // A frame's pairs left for the exact verdict, and their answers (kept to reuse their storage).
  std::vector<std::uint32_t> exact_;
  std::vector<std::optional<Result<VerdictResult>>> results_;
  std::unique_ptr<SecondHand> second_hand_;  // started by the first frame with two exact checks
};

}  // namespace gk::engine
