// Every tolerance of the kernel, in one place, with its unit and meaning.
// Lengths are millimetres (mm), angles degrees (deg). Geometry is double precision throughout.
#pragma once

namespace gk::tolerances {

// Two meshes closer than this (but not crossing) are TOUCHING rather than CLEAR. [mm]
// Kept far below the 0.003 mm separations the product must still call CLEAR.
inline constexpr double kContactMm = 1.0e-4;

// Relative slack added to every bounding-box overlap test, times the magnitude of the coordinates
// involved, so that rounding in the box transform can never drop a pair that touches exactly. [1]
inline constexpr double kBoxSlackRelative = 1.0e-12;

// Intersection segments shorter than this count as a point contact (edge on edge, vertex on edge)
// when a pair of triangles is classified as touching or crossing. [mm]
inline constexpr double kPointContactMm = 1.0e-9;

// A pose's rotation must be orthonormal to within this (max |R^T R - I| entry). [1]
inline constexpr double kRotationOrthonormality = 1.0e-9;

// A triangle whose area is at most this is reported as zero-area by mesh validation; the exact
// test (all three projected orientations zero) decides true degeneracy for queries. [mm^2]
inline constexpr double kZeroAreaMm2 = 0.0;

// Largest coordinate magnitude accepted in a mesh or pose (1 km beyond the biggest factory). [mm]
inline constexpr double kMaxCoordinateMm = 1.0e7;

}  // namespace gk::tolerances
