// Every tolerance of the project (kernel, machine models, engine), in one place, with its unit and
// meaning. Work budgets (counts of pairs, samples, iterations) stay beside the code they bound.
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

// A node slab's stored float normal: its length is at most this (a gap measured along it is
// divided by this to be a distance), and it differs from the double direction it was rounded from
// by less than kSlabNormalTurn (each component within 2^-24 of itself, relative), so a corner's
// projection moves by at most that times its distance from the node's centre. [1]
inline constexpr double kSlabNormalMaxLength = 1.0 + 1.0e-6;
inline constexpr double kSlabNormalTurn = 1.0e-7;

// Two segments whose directions' cross product is at most this fraction of the product of their
// lengths (squared: the sine of their angle below 1e-3) count as nearly parallel: their common
// perpendicular's parameters are then measured by projection, not taken from the formula. [1]
inline constexpr double kNearlyParallelSineSquared = 1.0e-6;
// A triangle whose width (twice its area over its longest edge) is below this fraction of its
// longest edge is a sliver: its closest point to a point is found in a frame of that edge, not
// by barycentric products (their rounding grows as (length / width)^2:
// 1e-10 of the length at this ratio, a millimetre on a metre-long sliver a micrometre wide).
// [dimensionless]
inline constexpr double kSliverAspect = 1.0e-3;
// ... and below this, in long double (the frame's direction error, eps (length / width) times the
// length, is 1e-10 of the length here in double). [dimensionless]
inline constexpr double kSliverLongDoubleAspect = 1.0e-6;
// A closest point on a triangle is off by at most about 1e-10 of the triangle's size and the
// distance (the slivers above measured in their own frame); a bound built on one takes off this
// fraction of those lengths, with room to spare. [relative]
inline constexpr double kClosestPointRoundingRelative = 1.0e-9;

// A rotation this close to orthonormal (max |R^T R - I| entry) is inverted by its transpose: it
// misplaces a point by at most this fraction of its distance from the origin, the relative slack
// every box test allows (kBoxSlackRelative), and every rotation built from a normalized quaternion
// or axis-angle is within it. A farther one (still accepted, below kRotationOrthonormality, e.g.
// written with 9 decimals) is inverted exactly: its transpose would misplace points 1e7 mm out by
// up to 0.01 mm. [1]
inline constexpr double kOrthonormalToRounding = 1.0e-12;

// A pose's rotation must be orthonormal to within this (max |R^T R - I| entry). [1]
inline constexpr double kRotationOrthonormality = 1.0e-9;

// A triangle whose area is at most this is reported as zero-area by mesh validation; the exact
// test (all three projected orientations zero) decides true degeneracy for queries. [mm^2]
inline constexpr double kZeroAreaMm2 = 0.0;

// Relative slack of comparisons between computed coordinates (a point on a box, a bend line on a
// plate's edge, a gap grown for rounding), times the magnitude of the coordinates involved. [1]
inline constexpr double kComparisonSlackRelative = 1.0e-9;

// Smallest cell of the uniform grids of the broad phases: boxes thinner than this share a cell. [mm]
inline constexpr double kGridMinCellMm = 1.0e-6;
// ...and of a layout session's grid (its boxes are grown by the clearance already). [mm]
inline constexpr double kLayoutGridMinCellMm = 1.0e-3;

// A penetration depth along a direction is advanced until the parts are apart by at most this. [mm]
inline constexpr double kDepthResolutionMm = 1.0e-6;

// Largest coordinate magnitude accepted in a mesh or pose (1 km beyond the biggest factory). [mm]
inline constexpr double kMaxCoordinateMm = 1.0e7;

// Largest length in a panel-bender request or machine model: a part's sizes, a flange or tab, a
// bend point, a travel or retract (100 m, far beyond any machine; larger is malformed). [mm]
inline constexpr double kMaxMachineLengthMm = 1.0e5;

// ---- machine steps (the P4 panel bender's ValidateStep) ----

// The default required clearance of a step: a moving or held body closer than this to an organ is
// a collision (seed 002 Table 1: "minimum clearance about 0.1 mm"); a request may change it. [mm]
inline constexpr double kStepClearanceMm = 0.1;

// Advancement converges on a first contact from above: a clearance within this of the required
// one is called a contact, so a step is denied conservatively up to this much beyond it. [mm]
inline constexpr double kStepContactResolutionMm = 1.0e-3;

// Intended contact: a part resting on a support's top face, or pressed by an engaged ABA segment
// on its upper face, may cross that face by at most this much; deeper is a collision. What lies
// within this of the face plane is not checked against that organ (it is the contact itself). [mm]
inline constexpr double kIntendedContactMm = 1.0e-2;

// Fixture assembly between frames: an element the assembling element already touches cannot be
// swept by conservative advancement (it is met at once), so the motion is checked against it at
// poses no farther apart than this for any point of the assembling element. An element thinner
// than this, passed through while sliding in contact with it, could go unseen. The poses start a
// contact distance apart and the gap doubles up to this, so a motion that pushes into what it
// touches is met within twice the contact distance, however thin that is. [mm]
inline constexpr double kTouchingSweepStepMm = 0.5;
// ... and at most this many such poses per element and frame; a longer motion in contact is
// INCONCLUSIVE for that element (a denial), never assumed clear.
inline constexpr int kTouchingSweepMaxPoses = 1000;
// Fixture features (engine/fixtures/feature_fits.h): their triangles may lie at most this fraction
// of the radius (a slot: of half its width) from the surface they are declared on - a 10-sided
// polygon's chords lie 4.9 % inside its circle. Farther, they are not that surface (a stray
// triangle in a hole's list, a blind hole's floor, would make whatever meets it "intended").
// [relative]
inline constexpr double kMaxFeatureDeviationRelative = 0.05;
// ... but their corners lie on it within this fraction of the radius (a slot: of half its width;
// a slot's walls are planes, so their triangles have no sag at all): the allowance above is for
// the facets' sag between corners, not for a size the mesh does not have (a bore meshed at r 9.6
// declared r 10 let a pin 0.35 mm into its wall count as the fit's). [relative]
inline constexpr double kMaxFeatureCornerOffRelative = 1.0e-3;
// A fixture mate's fit lets the pin be pressed into its hole's or slot's wall by half its tolerance
// less its clearance (an interference, or sizes that may fall short of the clearance): at most this
// fraction of the pin's diameter. A bound against absurd numbers, not a fit standard (the
// benchmark's loosest mate, a bolt leaning in a T-slot, allows 4.2 %); a
// mate beyond it is refused, not trusted - a review's mate with a 50 mm interference or a 1e300
// tolerance made a pin 9 mm into a block's wall "intended". The mate's tolerance and clearance
// are each at most the pin's diameter. [relative]
inline constexpr double kMaxFitPressOfDiameter = 0.05;
// A pose computed between two frames (kernel/query/rigid_sweep: pose_between) places points to
// within this fraction of their coordinates' magnitude (64 rounding units of a double): a crossing
// found there that a shift this large frees is the interpolation's own rounding (a part tipped
// over an edge it rests on), not a collision. It stays far below half the contact distance for
// every coordinate the product accepts (about 6e-7 mm at 1e7 mm): 1e-12 forgave 5e-5 mm there, and
// a part passed through a 0.1 mm plate between frames unseen (found by an adversarial review).
// [relative]
inline constexpr double kInterpolatedPoseRelative = 1.5e-14;

// A step is clamped when the engaged ABA segments press at least this much of the part's upper
// face (the sheet under the blankholder). [mm^2]
inline constexpr double kMinClampedAreaMm2 = 1.0;

// A CLEAR step reports its smallest clearance over the whole motion as a proven bracket, refined
// (within a budget of distance queries) until it is this narrow, or this fraction of the
// clearance, whichever is larger... [mm], [1]
inline constexpr double kClearanceBracketMm = 5.0e-3;
inline constexpr double kClearanceBracketRelative = 1.0e-2;
// ...for clearances below this; farther ones are reported as a lower bound only. [mm]
inline constexpr double kClearanceReportWindowMm = 10.0;

// The deepest penetration over a colliding motion is searched to within this. [mm]
inline constexpr double kStepDepthResolutionMm = 1.0e-3;

// Lengths compared in a machine model and its steps (a flange within its edge, a plate on the held
// side of a bend line, a segment within a span, a shift within its range) agree within this. [mm]
inline constexpr double kMachineLengthSlackMm = 1.0e-9;

// A RETRACT correction pulls the manipulator back in steps of this, the smallest that clears. [mm]
inline constexpr double kRetractResolutionMm = 8.0;

// ---- the engine's queries ----

// CAD parts are tessellated at this chordal deflection for every query (it enters the error
// bounds; one value, so a part is tessellated and its tree built once). [mm]
inline constexpr double kPartDeflectionMm = 0.05;

// A tessellation's deviation from its surface, measured at its triangles' edge midpoints and
// centroids (occt_adapters/shape_mesher), is widened by this before it enters the deflection
// window: the measure is exact for a surface that is its second-order expansion over each
// triangle, and the margin covers the higher orders on triangles small against the curvature. [1]
inline constexpr double kTessellationDeviationMargin = 1.25;

// ClearanceQuery: the pairs closer than the gap this near each other form one region, unless the
// request says otherwise. [mm]
inline constexpr double kRegionMergeMm = 10.0;
// ClearanceQuery's penetration depth is advanced to within this of the first free position... [mm]
inline constexpr double kClearanceDepthResolutionMm = 1.0e-4;
// ...and an audit's (thousands of pairs) to within this. [mm]
inline constexpr double kAuditDepthResolutionMm = 1.0e-3;

// ---- exact faces of CAD parts (decided on the B-Rep when the tessellation cannot tell) ----

// A distance measured on the exact faces (OCCT's BRepExtrema, in a frame local to the contact) is
// within this of the true one; checked against analytic solids in tests/engine. [mm]
inline constexpr double kBrepDistanceErrorMm = 1.0e-6;

// Exact boundaries whose Boolean common has a larger volume than this cross (COLLISION); a smaller
// or empty common is a touching contact. Two R50 spheres overlapping by 1e-4 mm share 8e-7 mm^3. [mm^3]
inline constexpr double kBrepOverlapVolumeMm3 = 1.0e-9;
// ...or whose common is at least this thick on average (twice its volume over its area: a slab's
// thickness, half the depth of a lens-shaped overlap), so that a lens deeper than kContactMm
// crosses whatever its volume: a 1.5 mm ball 12 micrometres into a torus shares only 7e-10 mm^3. [mm]
inline constexpr double kBrepCrossingThicknessMm = 0.5 * kContactMm;
// Curved CAD faces crossing deeper than this are found crossing (COLLISION) by the Boolean common
// or, where it comes back empty, by the section's surface points classified inside; between
// kContactMm and this a small lens can be lost by both and answered TOUCHING (never CLEAR).
// Measured: a 1.5 mm ball in a torus at nine spots, 2e-4 mm missed at one, 5e-4 mm found at all. [mm]
inline constexpr double kCurvedCrossingDetectedMm = 5.0e-4;

// The volume of an exact solid (a Boolean common) is checked against its own tessellation at this
// deflection, relative to the solid's thickness 2V/A; the bound then carries a band of 2 A times
// the deflection, about 1 % of the volume (occt_adapters/solid_volume). Ten times finer took
// BRepMesh 5-15 s on a lens of two R10 balls. [1]
inline constexpr double kVolumeCheckDeflectionRelative = 2.5e-3;
// ...and never finer than this: BRepMesh takes minutes on a small curved face meshed much finer
// (a 0.001 mm lens at 2.5e-7 mm). [mm]
inline constexpr double kVolumeCheckFinestDeflectionMm = 1e-5;

// A CAD part is tessellated no finer than this fraction of its box diagonal (its requested
// deflection otherwise): this bounds the triangles of a huge part; the exact faces decide within
// its wider deflection window. [1]
inline constexpr double kCadDeflectionRelative = 1.0e-5;

}  // namespace gk::tolerances
