// Units and constants used across the project: lengths are millimetres, angles degrees at every
// interface and radians inside the maths.
#pragma once

namespace gk {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace gk
