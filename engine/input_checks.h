// What a client may name things: checked before anything is stored.
#pragma once

#include "engine/scenes/scene_store.h"
#include "kernel/core/status.h"

#include <cstddef>
#include <string>

namespace gk::engine {

// Ids a client names (objects, machines): 1-128 of [A-Za-z0-9-_.:], so that nothing stored is
// truncated or ambiguous (a NUL byte ended an id in storage). Names, categories and groups: at most
// 256 bytes, no control characters.
inline constexpr std::size_t kMaxIdLength = 128;
inline constexpr std::size_t kMaxLabelLength = 256;
Result<bool> check_id(const std::string& id, const std::string& field);
Result<bool> check_label(const std::string& text, const std::string& field);

// A rotation angle larger than this is a client's mistake (2,778 turns), not a pose. [deg]
inline constexpr double kMaxAngleDeg = 1.0e6;

// A pose as a client gives it: a translation [mm] and a rotation of angle_deg about an axis (any
// finite non-zero vector; ignored when the angle is 0). Refused, naming field.translation,
// .rotation_axis or .rotation_deg: anything not finite, a translation beyond 1e7 mm, an angle
// beyond kMaxAngleDeg, an axis that gives no rigid rotation. The axis is kept scaled so that its
// largest component is 1.
Result<StoredPose> checked_pose(const Vec3& translation, const Vec3& axis, double angle_deg, const std::string& field);

}  // namespace gk::engine
