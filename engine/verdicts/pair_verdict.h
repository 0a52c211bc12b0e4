// The verdict on two posed parts, derived once for every caller (ClearanceQuery, an object's
// contacts, drags, audits): the kernel decides on the triangles; where a CAD part's tessellation is
// too coarse to tell (its answer within the deflections), the exact faces decide.
//
//  mesh answer                       CAD pair: decided by
//  CLEAR, farther than the window    the triangles (distance within the deflections)
//  CLEAR within the window, TOUCHING the exact faces: distance (BRepExtrema on the face pairs the
//                                    tessellation puts within reach), a point of either solid
//                                    inside the other (nesting), and for boundaries that meet, a
//                                    Boolean common: shared volume = COLLISION, none = TOUCHING
//  COLLISION, INCONCLUSIVE           a point of one part's exact surface (a tessellation vertex of a
//                                    contact) classified inside the other solid proves COLLISION;
//                                    failing that, as above
// A CAD part against a mesh: the exact faces are measured against the mesh's triangles there; when
// they meet and no point of the mesh lies inside the solid, the answer is INCONCLUSIVE
// (TESSELLATION_UNRESOLVED). A failed exact-face decision is INCONCLUSIVE (BREP_UNDECIDED), never
// CLEAR; a CLEAR answer's distance always exceeds its error bound.
#pragma once

#include "engine/parts/part_geometry.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/core/stop_token.h"

#include <optional>

namespace gk::engine {

struct PairVerdictOptions {
  VerdictOptions mesh;  // for the kernel's verdict on the triangles
  // Whether the pair is closer than this matters to the caller [mm]: a CAD pair whose mesh distance
  // is within the deflections of it is measured on the exact faces.
  double clearance_mm = 0.0;
  // CAD pairs apart: measure the distance and witnesses on the exact faces whenever the face pairs
  // within reach are few enough (ClearanceQuery's certified distance).
  bool measure_on_brep = false;
};

struct PairVerdict {
  VerdictResult result;          // the final verdict, reason, distance and witnesses (mesh contacts kept)
  double error_bound_mm = 0.0;   // the true distance is within this of result.distance_mm
  bool decided_on_brep = false;  // verdict and distance come from the exact faces
  int face_a = 0, face_b = 0;    // 1-based faces of the exact witnesses (0: none)
  double brep_ms = 0.0;          // time spent on the exact faces
};

Result<PairVerdict> decide_pair(const PosedPart& a, const PosedPart& b, const PairVerdictOptions& options = {});

// A pair the triangles alone report as a contact (or closer than clearance_mm), decided again
// where a CAD part's tessellation cannot tell (decide_pair with the mesh distance bounded by the
// clearance); nullopt when it is no contact after all. One rule for moves, drags and audits.
Result<std::optional<PairVerdict>> decide_contact(const PosedPart& a, const PosedPart& b, double clearance_mm,
                                                  const StopToken& stop = {});

// The window [mm] around a mesh distance within which two parts' tessellations cannot tell the true
// distance (the sum of their deflections).
double deflection_window(const PosedPart& a, const PosedPart& b);

}  // namespace gk::engine
