// The closest points of two faces near a starting pair, found by Levenberg–Marquardt on the
// residual S_a(u, v) − S_b(s, t) over the four parameters.
//
// Why not OCCT's Newton (Extrema_GenLocateExtSS): it solves "the gradient of the squared distance
// is zero", whose equations all vanish together when the faces touch tangentially (two spheres,
// a ball on a cylinder), so it stops wherever its tolerance is met — a few hundredths of a
// millimetre from the contact, reporting a gap of micrometres that is not there. Driving the
// residual itself to its minimum is a zero-residual least-squares problem when the faces touch,
// where Gauss–Newton keeps converging (the offset halves at every step) down to the contact.
#pragma once

#include <TopoDS_Face.hxx>
#include <gp_Pnt.hxx>

namespace gk::occt {

struct PointOnFace {
  TopoDS_Face face;
  double u = 0.0, v = 0.0;
};

struct FacePairClosest {
  bool found = false;     // converged to points inside both (trimmed) faces
  double distance_mm = 0.0;
  gp_Pnt point_a, point_b;
};

// From a and b's parameters; the faces keep their locations (points in the shapes' frame).
FacePairClosest descend_to_closest(const PointOnFace& a, const PointOnFace& b);

}  // namespace gk::occt
