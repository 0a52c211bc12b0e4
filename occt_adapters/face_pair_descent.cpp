#include "occt_adapters/face_pair_descent.h"

#include <BRepAdaptor_Surface.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <GeomAPI_ProjectPointOnSurf.hxx>
#include <Geom_Surface.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace gk::occt {
namespace {

constexpr int kMaxIterations = 200;
// Stop when the squared residual stops falling by more than this fraction.
constexpr double kRelativeProgress = 1e-15;

// A face's parameter range; periodic directions wrap instead of clamping.
struct ParameterBox {
  double lo[2] = {0.0, 0.0}, hi[2] = {0.0, 0.0};
  bool periodic[2] = {false, false};
  double period[2] = {0.0, 0.0};

  explicit ParameterBox(const BRepAdaptor_Surface& s) {
    BRepTools::UVBounds(s.Face(), lo[0], hi[0], lo[1], hi[1]);
    periodic[0] = s.IsUPeriodic();
    periodic[1] = s.IsVPeriodic();
    if (periodic[0]) period[0] = s.UPeriod();
    if (periodic[1]) period[1] = s.VPeriod();
  }
  double fit(int i, double x) const {
    if (periodic[i] && period[i] > 0.0) {
      while (x < lo[i]) x += period[i];
      while (x >= lo[i] + period[i]) x -= period[i];
      return x;
    }
    return std::clamp(x, lo[i], hi[i]);
  }
};

bool inside_face(const TopoDS_Face& face, double u, double v) {
  BRepClass_FaceClassifier classifier(face, gp_Pnt2d(u, v), 1e-9);
  return classifier.State() == TopAbs_IN || classifier.State() == TopAbs_ON;
}

}  // namespace

FacePairClosest descend_to_closest(const PointOnFace& a, const PointOnFace& b) {
  const BRepAdaptor_Surface sa(a.face), sb(b.face);
  const ParameterBox box_a(sa), box_b(sb);
  Eigen::Vector4d x(box_a.fit(0, a.u), box_a.fit(1, a.v), box_b.fit(0, b.u), box_b.fit(1, b.v));

  auto evaluate = [&](const Eigen::Vector4d& p, Eigen::Vector3d& r, Eigen::Matrix<double, 3, 4>* jacobian) {
    gp_Pnt pa, pb;
    gp_Vec du_a, dv_a, du_b, dv_b;
    sa.D1(p[0], p[1], pa, du_a, dv_a);
    sb.D1(p[2], p[3], pb, du_b, dv_b);
    r = Eigen::Vector3d(pa.X() - pb.X(), pa.Y() - pb.Y(), pa.Z() - pb.Z());
    if (jacobian) {
      *jacobian << du_a.X(), dv_a.X(), -du_b.X(), -dv_b.X(),  //
          du_a.Y(), dv_a.Y(), -du_b.Y(), -dv_b.Y(),           //
          du_a.Z(), dv_a.Z(), -du_b.Z(), -dv_b.Z();
    }
  };

  // A start on a degenerate point of the parameterisation (a sphere's pole, a cone's apex: the
  // derivatives span no plane there) cannot move; start a little inside instead.
  auto off_singularity = [](const BRepAdaptor_Surface& s, const ParameterBox& box, double& u, double& v) {
    gp_Pnt p;
    gp_Vec du, dv;
    s.D1(u, v, p, du, dv);
    if (du.Crossed(dv).Magnitude() > 1e-9 * std::max(du.SquareMagnitude() + dv.SquareMagnitude(), 1e-300)) return;
    u = box.fit(0, u + 1e-3 * (0.5 * (box.lo[0] + box.hi[0]) - u) + 1e-4);
    v = box.fit(1, v + 1e-2 * (0.5 * (box.lo[1] + box.hi[1]) - v));
  };
  off_singularity(sa, box_a, x[0], x[1]);
  off_singularity(sb, box_b, x[2], x[3]);

  // A step that leaves the parameter range (past a sphere's pole, where the parameterisation
  // folds over) lands where the linear prediction of the point projects onto the surface.
  const Handle(Geom_Surface) surface_a = BRep_Tool::Surface(a.face), surface_b = BRep_Tool::Surface(b.face);
  auto land = [](const BRepAdaptor_Surface& s, const Handle(Geom_Surface)& surface, const ParameterBox& box, double u,
                 double v, double& to_u, double& to_v) {
    const double fit_u = box.fit(0, to_u), fit_v = box.fit(1, to_v);
    const bool clamped = (!box.periodic[0] && fit_u != to_u) || (!box.periodic[1] && fit_v != to_v);
    if (clamped && !surface.IsNull()) {
      gp_Pnt p;
      gp_Vec du, dv;
      s.D1(u, v, p, du, dv);
      const gp_Pnt predicted = p.Translated(du * (to_u - u) + dv * (to_v - v));
      GeomAPI_ProjectPointOnSurf projection(predicted, surface, box.lo[0], box.hi[0], box.lo[1], box.hi[1]);
      if (projection.IsDone() && projection.NbPoints() > 0) {
        projection.LowerDistanceParameters(to_u, to_v);
        to_u = box.fit(0, to_u);
        to_v = box.fit(1, to_v);
        return;
      }
    }
    to_u = fit_u;
    to_v = fit_v;
  };

  Eigen::Vector3d r;
  Eigen::Matrix<double, 3, 4> j;
  evaluate(x, r, &j);
  double cost = r.squaredNorm();
  double lambda = 1e-6;
  for (int it = 0; it < kMaxIterations && cost > 0.0; ++it) {
    const Eigen::Matrix4d normal = j.transpose() * j;
    const Eigen::Vector4d gradient = j.transpose() * r;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix4d damped = normal;
      for (int k = 0; k < 4; ++k) damped(k, k) += lambda * std::max(normal(k, k), 1e-12);
      const Eigen::Vector4d step = damped.ldlt().solve(-gradient);
      if (!step.allFinite()) break;
      Eigen::Vector4d trial = x + step;
      land(sa, surface_a, box_a, x[0], x[1], trial[0], trial[1]);
      land(sb, surface_b, box_b, x[2], x[3], trial[2], trial[3]);
      Eigen::Vector3d trial_r;
      evaluate(trial, trial_r, nullptr);
      const double trial_cost = trial_r.squaredNorm();
      if (trial_cost < cost) {
        const bool progressing = trial_cost < cost * (1.0 - kRelativeProgress);
        x = trial;
        cost = trial_cost;
        evaluate(x, r, &j);
        lambda = std::max(lambda * 0.3, 1e-12);
        improved = progressing;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }

  FacePairClosest out;
  if (!inside_face(a.face, x[0], x[1]) || !inside_face(b.face, x[2], x[3])) return out;
  out.found = true;
  out.point_a = sa.Value(x[0], x[1]);
  out.point_b = sb.Value(x[2], x[3]);
  out.distance_mm = out.point_a.Distance(out.point_b);
  return out;
}

}  // namespace gk::occt
