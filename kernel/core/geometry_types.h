// Basic double-precision geometry types shared by the kernel.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>

namespace gk {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Triangle = std::array<Vec3, 3>;

}  // namespace gk
