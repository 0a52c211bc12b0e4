#include "machine_models/p4/motion_sweep.h"

#include "kernel/mesh/convex_hull.h"
#include "kernel/predicates/exact_predicates.h"
#include "kernel/core/tolerances.h"
#include "kernel/query/mesh_distance.h"
#include "machine_models/p4/organ_geometry.h"

#include <algorithm>
#include <cmath>

namespace gk::p4 {

RigidTransform Motion::at(double s) const {
  if (!rotation) return RigidTransform::from_translation(s * travel);
  return RigidTransform::from_translation(axis_point) * RigidTransform::from_axis_angle(axis_direction, s * angle_rad) *
         RigidTransform::from_translation(-axis_point);
}

double Motion::rate(const std::vector<Vec3>& points) const {
  if (!rotation) return travel.norm();
  double r = 0.0;
  for (const Vec3& p : points) {
    const Vec3 rel = p - axis_point;
    r = std::max(r, (rel - rel.dot(axis_direction) * axis_direction).norm());
  }
  return r * std::fabs(angle_rad);
}

namespace {

int sample_count(const Motion& motion, double max_step) {
  if (!motion.rotation) return 1;
  return std::max(1, static_cast<int>(std::ceil(std::fabs(motion.angle_rad) / max_step)));
}

// Largest distance of any body point from the rotation axis.
double reach(const std::vector<MovingBody>& bodies, const Motion& motion) {
  if (!motion.rotation) return 0.0;
  double r = 0.0;
  for (const MovingBody& b : bodies) {
    const Motion unit{true, motion.axis_point, motion.axis_direction, 1.0, Vec3::Zero()};
    r = std::max(r, unit.rate(b.points));
  }
  return r;
}

std::vector<Vec3> sampled_points(const std::vector<MovingBody>& bodies, const Motion& motion, int samples) {
  std::vector<Vec3> pts;
  for (int k = 0; k <= samples; ++k) {
    const RigidTransform t = motion.at(static_cast<double>(k) / samples);
    for (const MovingBody& b : bodies)
      for (const Vec3& p : b.points) pts.push_back(t.apply(p));
  }
  return pts;
}

double sagitta(const std::vector<MovingBody>& bodies, const Motion& motion, int samples) {
  if (!motion.rotation) return 0.0;
  const double step = std::fabs(motion.angle_rad) / samples;
  return reach(bodies, motion) * (1.0 - std::cos(0.5 * step));
}

}  // namespace

Aabb swept_bounds(const std::vector<MovingBody>& bodies, const Motion& motion, double max_sample_step_rad) {
  const int samples = sample_count(motion, max_sample_step_rad);
  Aabb box;
  for (const Vec3& p : sampled_points(bodies, motion, samples)) box.extend(p);
  return box.expanded(sagitta(bodies, motion, samples));
}

namespace {

// The largest gap between the convex organ and the sweep bounded by the convex hull of sampled
// positions, along the face normals of both (negative when none separates them): a gap along any
// unit axis, less how far the arcs between samples can stray along it, is a lower bound of their
// distance, so a gap beyond a bound proves them apart (and rules out either lying inside the
// other). Edge-edge axes are not tried: an organ they alone would separate goes on to the narrow
// phase.
double hull_gap(const HullPolytope& hull, const SweepOrgan& organ, double sagitta, const Motion& motion) {
  const TriangleMesh& om = organ.mesh->mesh();
  std::vector<Vec3> organ_points;
  organ_points.reserve(om.vertices().size());
  for (const Vec3& v : om.vertices()) organ_points.push_back(organ.pose.apply(v));
  double best = -std::numeric_limits<double>::infinity();
  // A box's twelve triangles have three directions, a prism's top and bottom one: each direction
  // (up to sign, which gives the same gap) is projected once. Skipping an axis can only weaken
  // the bound, never make it wrong.
  std::vector<Vec3> tried;
  auto separated_along = [&](const Vec3& axis) {
    for (const Vec3& a : tried)
      if (std::fabs(a.dot(axis)) > 1.0 - 1e-12) return;
    tried.push_back(axis);
    const auto [hull_lo, hull_hi] = projection(hull.corners, axis);
    const auto [organ_lo, organ_hi] = projection(organ_points, axis);
    // The sampled hull misses the arcs between samples by at most the sagitta, and only across
    // the rotation axis: along it nothing moves.
    const double along = motion.rotation ? motion.axis_direction.dot(axis) : 0.0;
    const double stray = sagitta * std::sqrt(std::max(0.0, 1.0 - along * along));
    best = std::max(best, std::max(organ_lo - hull_hi, hull_lo - organ_hi) - stray);
  };
  for (std::size_t t = 0; t < om.triangle_count(); ++t) {
    const Triangle tri = om.triangle(t);
    const Vec3 n = organ.pose.apply_direction((tri[1] - tri[0]).cross(tri[2] - tri[0]));
    if (n.norm() > 0.0) separated_along(n.normalized());
  }
  for (const auto& f : hull.faces) {
    const Vec3& a = hull.corners[f[0]];
    const Vec3 n = (hull.corners[f[1]] - a).cross(hull.corners[f[2]] - a);
    if (n.norm() > 0.0) separated_along(n.normalized());
  }
  return best;
}

// The prism over the 2D convex hull of the points projected along the rotation axis, spanning
// their range along the axis: it contains their 3D hull. Rotating bodies are sampled on circles
// around the axis, which puts hundreds of them on a few planes: this avoids the 3D hull's exact
// arithmetic on all those coplanar points, and is exact for plates aligned with the axis. Andrew's
// monotone chain with exact turn tests.
Result<HullPolytope> axial_prism_hull(const std::vector<Vec3>& points, const Vec3& origin, const Vec3& axis) {
  const Vec3 w = axis.normalized();
  const Vec3 u = (std::fabs(w.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(w).normalized();
  const Vec3 v = w.cross(u);
  std::vector<Vec2> uv;
  double w0 = std::numeric_limits<double>::infinity(), w1 = -w0;
  for (const Vec3& p : points) {
    const Vec3 r = p - origin;
    uv.emplace_back(r.dot(u), r.dot(v));
    w0 = std::min(w0, r.dot(w));
    w1 = std::max(w1, r.dot(w));
  }
  std::sort(uv.begin(), uv.end(), [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  uv.erase(std::unique(uv.begin(), uv.end()), uv.end());
  if (uv.size() < 3 || !(w1 > w0)) return invalid_argument("points", "no prism: flat or collinear footprint");
  std::vector<Vec2> ring(2 * uv.size());
  std::size_t k = 0;
  auto turn = [](const Vec2& a, const Vec2& b, const Vec2& c) { return exact::orient2d(a.x(), a.y(), b.x(), b.y(), c.x(), c.y()); };
  for (std::size_t i = 0; i < uv.size(); ++i) {  // lower chain
    while (k >= 2 && turn(ring[k - 2], ring[k - 1], uv[i]) <= 0) --k;
    ring[k++] = uv[i];
  }
  for (std::size_t i = uv.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && turn(ring[k - 2], ring[k - 1], uv[i]) <= 0) --k;
    ring[k++] = uv[i];
  }
  ring.resize(k - 1);  // counter-clockwise in (u, v); the chain repeated its first point last
  if (ring.size() < 3) return invalid_argument("points", "no prism: collinear footprint");
  // Projection rounding (a few ulps of the coordinates) is covered by widening the prism slightly.
  double scale = 1.0;
  for (const Vec2& q : ring) scale = std::max(scale, q.cwiseAbs().maxCoeff());
  const double grow = 1e-12 * scale;
  Vec2 centroid = Vec2::Zero();
  for (const Vec2& q : ring) centroid += q;
  centroid /= static_cast<double>(ring.size());
  HullPolytope prism;
  const auto n = static_cast<std::uint32_t>(ring.size());
  auto corner = [&](const Vec2& q, double along) {
    const Vec2 out = q + grow * (q - centroid).normalized();
    return Vec3(origin + out.x() * u + out.y() * v + along * w);
  };
  for (const Vec2& q : ring) prism.corners.push_back(corner(q, w0 - grow));
  for (const Vec2& q : ring) prism.corners.push_back(corner(q, w1 + grow));
  for (std::uint32_t i = 1; i + 1 < n; ++i) {
    prism.faces.push_back({n, n + i, n + i + 1});  // the +axis cap, counter-clockwise seen from +axis
    prism.faces.push_back({0, i + 1, i});          // the -axis cap
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t j = (i + 1) % n;
    prism.faces.push_back({i, j, n + j});
    prism.faces.push_back({i, n + j, n + i});
  }
  return prism;
}

}  // namespace

Result<HullLodResult> hull_lod(const std::vector<MovingBody>& bodies, const Motion& motion,
                               const std::vector<SweepOrgan>& organs, double clearance_mm, double max_sample_step_rad) {
  HullLodResult out;
  out.samples = sample_count(motion, max_sample_step_rad);
  out.sagitta_mm = sagitta(bodies, motion, out.samples);
  std::vector<char> cleared(organs.size(), 1);
  out.lower_bound_mm.assign(organs.size(), std::numeric_limits<double>::infinity());
  // One hull per body: the union of each body's sampled positions, inflated by the sagitta.
  for (const MovingBody& body : bodies) {
    const std::vector<MovingBody> one = {body};
    const std::vector<Vec3> pts = sampled_points(one, motion, out.samples);
    auto hull = motion.rotation ? axial_prism_hull(pts, motion.axis_point, motion.axis_direction) : convex_hull_polytope(pts);
    if (!hull.ok()) {  // a flat sweep has no hull: this body clears nothing here
      std::fill(cleared.begin(), cleared.end(), 0);
      continue;
    }
    Aabb hull_box;
    for (const Vec3& c : hull.value().corners) hull_box.extend(c);
    for (std::size_t i = 0; i < organs.size(); ++i) {
      if (!cleared[i]) continue;
      // Far organs are settled by their boxes (a lower bound too); near ones by separating axes.
      const double box_gap = hull_box.distance(transformed_box(organs[i].mesh->root_bounds(), organs[i].pose)) - out.sagitta_mm;
      const double gap = box_gap >= std::max(clearance_mm, tolerances::kClearanceReportWindowMm)
                             ? box_gap
                             : std::max(box_gap, hull_gap(hull.value(), organs[i], out.sagitta_mm, motion));
      cleared[i] = gap > clearance_mm ? 1 : 0;
      out.lower_bound_mm[i] = std::min(out.lower_bound_mm[i], gap);
    }
  }
  for (std::size_t i = 0; i < organs.size(); ++i)
    if (!cleared[i]) {
      out.remaining.push_back(static_cast<int>(i));
      out.lower_bound_mm[i] = 0.0;
    }
  return out;
}

namespace {

// Advancement against one organ: the parameter of the first contact (or 1 when none), with the
// smallest sampled clearance. A query only needs to look as far as the body can still move, so
// an organ farther than that is cleared for the rest of the motion in one query.
struct OrganAdvance {
  bool collided = false;
  bool budget_exceeded = false;
  double contact_s = 1.0;
  Vec3 on_body = Vec3::Zero(), on_organ = Vec3::Zero(), normal = Vec3::Zero();
  double min_clearance = std::numeric_limits<double>::infinity();
  double certified = std::numeric_limits<double>::infinity();
  double min_s = 0.0;
  Vec3 min_point = Vec3::Zero();
  int steps = 0;
};

Result<OrganAdvance> advance_one(const MovingBody& body, const Motion& motion, const SweepOrgan& organ,
                                 const AdvanceOptions& options, double stop_at_s) {
  const double rate = motion.rate(body.points);
  OrganAdvance out;
  double s = 0.0;
  Vec3 last_body = Vec3::Zero(), last_organ = Vec3::Zero();
  bool have_last = false;
  const double contact = options.required_clearance_mm + options.contact_resolution_mm;
  for (out.steps = 0; out.steps < options.max_steps; ++out.steps) {
    const RigidTransform pose = motion.at(s);
    // Nothing farther than the rest of the motion can reach matters (plus the contact band).
    const double horizon = rate * (1.0 - s) + contact;
    // A plate body and a convex organ apart along a separating axis by more than the contact band
    // advance on that lower bound alone (the steps only get shorter); the mesh query is spent
    // where they may be in contact, so that every contact is found on the exact meshes.
    if (organ.shape && !body.plates.empty()) {
      double axes_gap = std::numeric_limits<double>::infinity();
      for (const Plate& p : body.plates)
        axes_gap = std::min(axes_gap, separation_lower_bound(ConvexPolytope::plate(p.transformed(pose)), *organ.shape));
      if (axes_gap >= horizon) {  // beyond the horizon: clear for the rest of the motion
        out.certified = std::min(out.certified, axes_gap - rate * (1.0 - s));
        return out;
      }
      if (axes_gap > contact) {
        have_last = false;
        out.certified = std::min(out.certified, (1.0 - options.step_fraction) * axes_gap + options.step_fraction * options.required_clearance_mm);
        if (s >= 1.0 || s > stop_at_s) return out;
        s = std::min(1.0, s + (rate > 0.0 ? options.step_fraction * (axes_gap - options.required_clearance_mm) / rate : 1.0));
        continue;
      }
    }
    double d = std::numeric_limits<double>::infinity();
    Vec3 on_body = Vec3::Zero(), on_organ = Vec3::Zero();
    DistanceRequest req;
    req.upper_bound_mm = horizon;
    auto r = distance(*body.mesh, pose, *organ.mesh, organ.pose, req);
    if (!r.ok()) return r.error();
    if (r.value().found) {
      d = r.value().distance_mm;
      on_body = r.value().point_a;
      on_organ = r.value().point_b;
    }
    if (!std::isfinite(d)) {  // beyond the horizon: clear for the rest of the motion
      out.certified = std::min(out.certified, horizon - rate * (1.0 - s));
      return out;
    }
    if (d < out.min_clearance) {
      out.min_clearance = d;
      out.min_s = s;
      out.min_point = on_body;
    }
    if (d <= contact) {
      out.collided = true;
      out.contact_s = s;
      out.on_body = on_body;
      out.on_organ = on_organ;
      const Vec3 dir = have_last ? Vec3(last_body - last_organ) : Vec3(on_body - on_organ);
      out.normal = dir.norm() > 0.0 ? dir.normalized() : Vec3::Zero();
      return out;
    }
    have_last = true;
    last_body = on_body;
    last_organ = on_organ;
    // Between this sample and the next no point moves more than step_fraction * (d - required),
    // so the clearance stays above (1 - step_fraction) * d + step_fraction * required.
    out.certified = std::min(out.certified, (1.0 - options.step_fraction) * d + options.step_fraction * options.required_clearance_mm);
    if (s >= 1.0 || s > stop_at_s) return out;  // past an earlier contact elsewhere: no need to go on
    const double advance = rate > 0.0 ? options.step_fraction * (d - options.required_clearance_mm) / rate : 1.0;
    s = std::min(1.0, s + advance);
  }
  out.budget_exceeded = true;
  return out;
}

// The range of the points' coordinates along the motion's axis.
std::pair<double, double> axial_extent(const std::vector<Vec3>& points, const Motion& motion) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& p : points) {
    const double a = motion.axis_direction.dot(p - motion.axis_point);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  return {lo, hi};
}

}  // namespace

Result<SweepOutcome> conservative_advance(const std::vector<MovingBody>& bodies, const Motion& motion,
                                          const std::vector<SweepOrgan>& organs, const AdvanceOptions& options) {
  std::vector<SweepPair> pairs;
  for (const SweepOrgan& organ : organs)
    for (const MovingBody& body : bodies) pairs.push_back({&body, organ});
  auto out = conservative_advance(pairs, motion, options);
  if (!out.ok()) return out;
  // Report organ indices, as this overload promises.
  const auto per_organ = static_cast<int>(bodies.size());
  if (out.value().organ >= 0) out.value().organ /= per_organ;
  if (out.value().min_clearance_organ >= 0) out.value().min_clearance_organ /= per_organ;
  return out;
}

Result<SweepOutcome> conservative_advance(const std::vector<SweepPair>& pairs, const Motion& motion,
                                          const AdvanceOptions& options) {
  SweepOutcome out;
  // Each (body, organ) pair advances on its own, at the body's own speed: a far pair is settled
  // in one query, a near one takes the small steps it needs. The first contact is the answer.
  // Along a rotation's axis nothing moves: a body and an organ whose extents along the axis lie
  // apart by more than the required clearance can never meet, and need no query at all.
  std::vector<const MovingBody*> bodies;
  for (const SweepPair& p : pairs)
    if (std::find(bodies.begin(), bodies.end(), p.body) == bodies.end()) bodies.push_back(p.body);
  std::vector<std::pair<double, double>> body_axial(bodies.size());
  for (std::size_t b = 0; b < bodies.size(); ++b) body_axial[b] = axial_extent(bodies[b]->points, motion);
  // Per-body hull filter: which pairs the body's own sweep hull already clears.
  std::vector<char> cleared(pairs.size(), 0);
  // What a skipped pair is proven to keep: more than the required clearance.
  out.pair_lower_mm.assign(pairs.size(), options.required_clearance_mm);
  if (options.body_hull_step_rad > 0.0) {
    for (const MovingBody* body : bodies) {
      std::vector<SweepOrgan> organs;
      std::vector<std::size_t> which;
      for (std::size_t i = 0; i < pairs.size(); ++i)
        if (pairs[i].body == body) {
          organs.push_back(pairs[i].organ);
          which.push_back(i);
        }
      auto lod = hull_lod({*body}, motion, organs, options.required_clearance_mm, options.body_hull_step_rad);
      if (!lod.ok()) return lod.error();
      for (std::size_t k = 0; k < which.size(); ++k) cleared[which[k]] = 1;
      for (int k : lod.value().remaining) cleared[which[k]] = 0;
    }
  }
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const MovingBody& body = *pairs[i].body;
    const SweepOrgan& organ = pairs[i].organ;
    if (cleared[i]) continue;
    if (motion.rotation) {
      const std::size_t b = static_cast<std::size_t>(std::find(bodies.begin(), bodies.end(), &body) - bodies.begin());
      const Aabb& lb = organ.mesh->root_bounds();
      std::vector<Vec3> corners;
      for (int k = 0; k < 8; ++k)
        corners.push_back(organ.pose.apply(Vec3((k & 1) ? lb.max.x() : lb.min.x(), (k & 2) ? lb.max.y() : lb.min.y(),
                                                (k & 4) ? lb.max.z() : lb.min.z())));
      const auto organ_axial = axial_extent(corners, motion);
      if (organ_axial.first > body_axial[b].second + options.required_clearance_mm + options.contact_resolution_mm ||
          body_axial[b].first > organ_axial.second + options.required_clearance_mm + options.contact_resolution_mm)
        continue;
    }
    auto one = advance_one(body, motion, organ, options, out.collided ? out.contact_s : 1.0);
    if (!one.ok()) return one.error();
    const OrganAdvance& a = one.value();
    out.pair_lower_mm[i] = a.collided ? 0.0 : a.certified;
    out.steps += a.steps;
    if (a.budget_exceeded) out.budget_exceeded = true;
    if (a.collided && (!out.collided || a.contact_s < out.contact_s)) {
      out.collided = true;
      out.contact_s = a.contact_s;
      out.organ = static_cast<int>(i);
      out.point_on_body = a.on_body;
      out.point_on_organ = a.on_organ;
      out.normal = a.normal;
    }
    if (a.min_clearance < out.min_clearance_mm) {
      out.min_clearance_mm = a.min_clearance;
      out.min_clearance_organ = static_cast<int>(i);
      out.min_clearance_point = a.min_point;
      out.min_clearance_s = a.min_s;
    }
  }
  return out;
}

namespace {

// A lower bound of the clearance between the body and the convex obstacles while the motion runs
// from s0 to s1: every point's path stays within the sagitta of its chord, so the sweep lies in
// the convex hull of the body's plates at s0 and s1 inflated by the sagitta (exactly the hull for
// a translation). The hull's gap to each obstacle along separating-axis candidates (the
// obstacle's faces, the plates' faces at both ends and the measured witness
// directions: edge crosses are left out, the bound only loosens) bounds its distance from below;
// second order in the interval, where the Lipschitz bound is first order.
double hull_lower_bound(const MovingBody& body, const Motion& motion, const std::vector<ConvexPolytope>& obstacles,
                        double s0, double s1, const Vec3& dir0, const Vec3& dir1) {
  if (body.plates.empty() || obstacles.empty()) return 0.0;
  const RigidTransform pose0 = motion.at(s0), pose1 = motion.at(s1);
  ConvexPolytope hull;
  std::vector<Vec3> piece_axes;
  hull.vertices.reserve(16 * body.plates.size());
  piece_axes.reserve(6 * body.plates.size());
  for (const Plate& p : body.plates)
    for (const RigidTransform* pose : {&pose0, &pose1}) {
      const Plate q = p.transformed(*pose);
      for (const Vec3& c : q.corners()) hull.vertices.push_back(c);
      for (const Vec3& e : q.edge)
        if (e.norm() > 0.0) piece_axes.push_back(e.normalized());
    }
  double sag = 0.0;
  if (motion.rotation) {
    const Motion unit{true, motion.axis_point, motion.axis_direction, 1.0, Vec3::Zero()};
    sag = unit.rate(body.points) * (1.0 - std::cos(0.5 * std::fabs(motion.angle_rad) * (s1 - s0)));
  }
  Aabb hull_box;
  for (const Vec3& v : hull.vertices) hull_box.extend(v);
  double bound = std::numeric_limits<double>::infinity();
  for (const ConvexPolytope& o : obstacles) {
    // The boxes' distance bounds the distance from below too: an obstacle whose box is already
    // farther than the bound so far cannot lower it.
    Aabb o_box;
    for (const Vec3& v : o.vertices) o_box.extend(v);
    const double box_gap = hull_box.distance(o_box);
    if (box_gap - sag >= bound) continue;
    // Along an axis, a point's path strays from its chord by at most the sagitta times the axis's
    // component across the rotation axis: nothing along the rotation axis itself.
    double gap = box_gap - sag;
    auto try_axis = [&](const Vec3& axis) {
      const auto [h_lo, h_hi] = projection(hull.vertices, axis);
      const auto [o_lo, o_hi] = projection(o.vertices, axis);
      const double along = motion.rotation ? motion.axis_direction.dot(axis) : 0.0;
      const double stray = sag * std::sqrt(std::max(0.0, 1.0 - along * along));
      gap = std::max(gap, std::max(o_lo - h_hi, h_lo - o_hi) - stray);
    };
    // The witness directions first: near a minimum they are the separating direction itself.
    for (const Vec3& d : {dir0, dir1})
      if (d.norm() > 0.5) try_axis(d);
    for (const Vec3& n : o.face_normals)
      if (gap < bound) try_axis(n);
    for (const Vec3& n : piece_axes)
      if (gap < bound) try_axis(n);
    bound = std::min(bound, gap);
    if (bound <= 0.0) return 0.0;
  }
  return bound;
}

}  // namespace

Result<ClearanceBracket> clearance_bracket(const MovingBody& body, const Motion& motion, const std::vector<SweepOrgan>& organs,
                                           double window_mm, double tolerance_mm, double tolerance_relative, int max_queries,
                                           double known_upper_mm, const std::vector<ConvexPolytope>* obstacle_shapes) {
  const double rate = motion.rate(body.points);
  ClearanceBracket out;
  struct Sample {
    double s = 0.0;
    double d = 0.0;    // measured: some organ is this near (or the cap)
    double low = 0.0;  // proven: no organ is nearer
    Vec3 dir = Vec3::Zero();  // unit, from the organ's witness to the body's
  };
  auto tolerance_at = [&](double best) { return std::max(tolerance_mm, tolerance_relative * best); };
  // d(s) to the nearest organ, capped at the window: a query that finds nothing within it proves
  // d > window. Each organ's query is bounded by the nearest found so far (most end at the root).
  std::vector<Aabb> organ_boxes;
  for (const SweepOrgan& o : organs) organ_boxes.push_back(transformed_box(o.mesh->root_bounds(), o.pose));
  std::vector<std::pair<double, std::size_t>> order(organs.size());
  std::vector<ConvexPolytope> body_shapes;
  auto measure = [&](double s, Sample& x) -> Result<bool> {
    const RigidTransform pose = motion.at(s);
    x.s = s;
    x.d = std::min(window_mm, out.upper_mm);
    x.dir = Vec3::Zero();
    ++out.queries;
    // Nearest boxes first, and none whose box is already farther than the nearest found. Each
    // query asks only for what is nearer than that by a quarter of the bracket's tolerance: an
    // organ within that slack is left unmeasured, proven no nearer than the bound (`low`), which
    // the bracket can afford. This is what keeps a flange passing a row of equal segments from
    // paying for an exact distance to every segment at every sample.
    const double slack = 0.25 * tolerance_at(std::min({out.upper_mm, known_upper_mm, window_mm}));
    const Aabb body_box = transformed_box(body.mesh->root_bounds(), pose);
    for (std::size_t i = 0; i < organs.size(); ++i) order[i] = {body_box.distance(organ_boxes[i]), i};
    std::sort(order.begin(), order.end());
    // A plate body against a convex organ is first bounded by the separating axes (a fraction of
    // a mesh query's cost, and exact when a face normal or an edge pair separates them).
    body_shapes.clear();
    if (obstacle_shapes)
      for (const Plate& p : body.plates) body_shapes.push_back(ConvexPolytope::plate(p.transformed(pose)));
    double proven = x.d;  // no organ skipped or left unmeasured is nearer than this
    for (const auto& [box_gap, i] : order) {
      const double bound = x.d - slack;
      if (box_gap >= bound) {
        proven = std::min(proven, box_gap);
        break;
      }
      if (!body_shapes.empty()) {
        double axes_gap = std::numeric_limits<double>::infinity();
        for (const ConvexPolytope& shape : body_shapes) axes_gap = std::min(axes_gap, separation_lower_bound(shape, (*obstacle_shapes)[i]));
        if (axes_gap >= bound) {
          proven = std::min(proven, axes_gap);
          continue;
        }
      }
      DistanceRequest req;
      req.upper_bound_mm = bound;
      auto r = distance(*body.mesh, pose, *organs[i].mesh, organs[i].pose, req);
      if (!r.ok()) return r.error();
      if (!r.value().found || r.value().distance_mm >= bound) {
        proven = std::min(proven, bound);
        continue;
      }
      x.d = r.value().distance_mm;
      const Vec3 gap = r.value().point_a - r.value().point_b;
      x.dir = gap.norm() > 0.0 ? Vec3(gap.normalized()) : Vec3::Zero();
      if (x.d < out.upper_mm) {
        out.upper_mm = x.d;
        out.at_s = s;
        out.point_on_body = r.value().point_a;
        out.organ = static_cast<int>(i);
      }
    }
    x.low = std::min(proven, x.d);
    return true;
  };
  struct Interval {
    Sample a, b;
    double lower = 0.0;
  };
  auto make = [&](const Sample& a, const Sample& b) {
    Interval iv{a, b, std::max(0.0, 0.5 * (a.low + b.low - rate * (b.s - a.s)))};
    if (obstacle_shapes) iv.lower = std::max(iv.lower, hull_lower_bound(body, motion, *obstacle_shapes, a.s, b.s, a.dir, b.dir));
    return iv;
  };
  Sample first, last;
  if (auto m = measure(0.0, first); !m.ok()) return m.error();
  if (rate > 0.0) {
    if (auto m = measure(1.0, last); !m.ok()) return m.error();
  } else {
    last = first;  // nothing moves: the end pose is the start pose
    last.s = 1.0;
  }
  std::vector<Interval> open;
  if (rate > 0.0) open.push_back(make(first, last));  // nothing moves: the one measurement is the answer
  while (!open.empty()) {
    // Split the interval with the smallest lower bound, until it is close enough to the best
    // measured value, far enough, or the budget is spent.
    auto worst = std::min_element(open.begin(), open.end(), [](const Interval& x, const Interval& y) { return x.lower < y.lower; });
    const double lo = worst->lower;
    const double best = std::min({out.upper_mm, known_upper_mm, window_mm});
    if (lo >= window_mm || best - lo <= tolerance_at(best) || out.queries >= max_queries) break;
    const Interval iv = *worst;
    open.erase(worst);
    // Piyavskii-Shubert: measure where the two cones of the interval's Lipschitz bound meet.
    const double cone = 0.5 * (iv.a.s + iv.b.s) + 0.5 * (iv.a.low - iv.b.low) / rate;
    const double margin = 0.05 * (iv.b.s - iv.a.s);
    Sample mid;
    if (auto m = measure(std::clamp(cone, iv.a.s + margin, iv.b.s - margin), mid); !m.ok()) return m.error();
    open.push_back(make(iv.a, mid));
    open.push_back(make(mid, iv.b));
  }
  double lower = std::min({out.upper_mm, window_mm, first.low, last.low});
  for (const Interval& iv : open) lower = std::min(lower, iv.lower);
  out.lower_mm = lower;
  return out;
}

}  // namespace gk::p4
