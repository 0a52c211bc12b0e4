#include "kernel/predicates/exact_predicates.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace gk::exact {
namespace {

thread_local long long g_fallbacks = 0;

// Shewchuk's epsilon: half an ulp of 1.0, so that 1 + epsilon rounds to 1.
constexpr double kEpsilon = 1.1102230246251565e-16;
constexpr double kSplitter = 134217729.0;  // 2^27 + 1, splits a double into two 26-bit halves
constexpr double kCcwErrBoundA = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kO3dErrBoundA = (7.0 + 56.0 * kEpsilon) * kEpsilon;

// A floating-point expansion: a sum of non-overlapping doubles in increasing magnitude.
// The capacity covers the largest intermediate of orient3d (192 terms); only `size` terms are live.
struct Expansion {
  static constexpr std::size_t kCapacity = 256;
  double term[kCapacity];
  std::size_t size = 0;

  Expansion() = default;
  Expansion(const Expansion& other) : size(other.size) { std::copy(other.term, other.term + other.size, term); }
  Expansion& operator=(const Expansion& other) {
    size = other.size;
    std::copy(other.term, other.term + other.size, term);
    return *this;
  }
  void push_nonzero(double x) {
    if (x != 0.0) term[size++] = x;
  }
  int sign() const {
    if (size == 0) return 0;
    const double top = term[size - 1];
    return top > 0.0 ? 1 : (top < 0.0 ? -1 : 0);
  }
};

inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double b_virtual = x - a;
  const double a_virtual = x - b_virtual;
  const double b_round = b - b_virtual;
  const double a_round = a - a_virtual;
  y = a_round + b_round;
}

inline void fast_two_sum(double a, double b, double& x, double& y) {  // requires |a| >= |b|
  x = a + b;
  y = b - (x - a);
}

inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  const double b_virtual = a - x;
  const double a_virtual = x + b_virtual;
  const double b_round = b_virtual - b;
  const double a_round = a - a_virtual;
  y = a_round + b_round;
}

inline void split(double a, double& hi, double& lo) {
  const double c = kSplitter * a;
  const double a_big = c - a;
  hi = c - a_big;
  lo = a - hi;
}

inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  double ahi, alo, bhi, blo;
  split(a, ahi, alo);
  split(b, bhi, blo);
  const double err1 = x - (ahi * bhi);
  const double err2 = err1 - (alo * bhi);
  const double err3 = err2 - (ahi * blo);
  y = (alo * blo) - err3;
}

// h = e + f (Shewchuk's FAST-EXPANSION-SUM with zero elimination: merge by magnitude, then one
// pass of two-sums). h must not alias e or f.
void sum(const Expansion& e, const Expansion& f, Expansion& h) {
  h.size = 0;
  if (e.size == 0) {
    h = f;
    return;
  }
  if (f.size == 0) {
    h = e;
    return;
  }
  std::size_t ei = 0, fi = 0;
  double enow = e.term[0], fnow = f.term[0];
  double q;
  if ((fnow > enow) == (fnow > -enow)) {
    q = enow;
    enow = ++ei < e.size ? e.term[ei] : 0.0;
  } else {
    q = fnow;
    fnow = ++fi < f.size ? f.term[fi] : 0.0;
  }
  double qnew, hh;
  if (ei < e.size && fi < f.size) {
    if ((fnow > enow) == (fnow > -enow)) {
      fast_two_sum(enow, q, qnew, hh);
      enow = ++ei < e.size ? e.term[ei] : 0.0;
    } else {
      fast_two_sum(fnow, q, qnew, hh);
      fnow = ++fi < f.size ? f.term[fi] : 0.0;
    }
    q = qnew;
    h.push_nonzero(hh);
    while (ei < e.size && fi < f.size) {
      if ((fnow > enow) == (fnow > -enow)) {
        two_sum(q, enow, qnew, hh);
        enow = ++ei < e.size ? e.term[ei] : 0.0;
      } else {
        two_sum(q, fnow, qnew, hh);
        fnow = ++fi < f.size ? f.term[fi] : 0.0;
      }
      q = qnew;
      h.push_nonzero(hh);
    }
  }
  while (ei < e.size) {
    two_sum(q, enow, qnew, hh);
    enow = ++ei < e.size ? e.term[ei] : 0.0;
    q = qnew;
    h.push_nonzero(hh);
  }
  while (fi < f.size) {
    two_sum(q, fnow, qnew, hh);
    fnow = ++fi < f.size ? f.term[fi] : 0.0;
    q = qnew;
    h.push_nonzero(hh);
  }
  if (q != 0.0 || h.size == 0) h.push_nonzero(q);
}

// h = e * b (Shewchuk's SCALE-EXPANSION with zero elimination).
void scale(const Expansion& e, double b, Expansion& h) {
  h.size = 0;
  if (e.size == 0 || b == 0.0) return;
  double q, hh;
  two_product(e.term[0], b, q, hh);
  h.push_nonzero(hh);
  for (std::size_t i = 1; i < e.size; ++i) {
    double p1, p0, s;
    two_product(e.term[i], b, p1, p0);
    two_sum(q, p0, s, hh);
    h.push_nonzero(hh);
    fast_two_sum(p1, s, q, hh);
    h.push_nonzero(hh);
  }
  h.push_nonzero(q);
}

// h = e * f.
void product(const Expansion& e, const Expansion& f, Expansion& h) {
  Expansion part, next;
  h.size = 0;
  for (std::size_t j = 0; j < f.size; ++j) {
    scale(e, f.term[j], part);
    sum(h, part, next);
    h = next;
  }
}

void negate(Expansion& e) {
  for (std::size_t i = 0; i < e.size; ++i) e.term[i] = -e.term[i];
}

Expansion exact_difference(double a, double b) {
  Expansion e;
  double x, y;
  two_diff(a, b, x, y);
  e.push_nonzero(y);
  e.push_nonzero(x);
  return e;
}

// (p * q) - (r * s) for exact two-term operands.
Expansion cross_term(const Expansion& p, const Expansion& q, const Expansion& r, const Expansion& s) {
  Expansion pq, rs, out;
  product(p, q, pq);
  product(r, s, rs);
  negate(rs);
  sum(pq, rs, out);
  return out;
}

int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  ++g_fallbacks;
  const Expansion acx = exact_difference(ax, cx), acy = exact_difference(ay, cy);
  const Expansion bcx = exact_difference(bx, cx), bcy = exact_difference(by, cy);
  return cross_term(acx, bcy, acy, bcx).sign();
}

// Shewchuk's orient3d determinant: positive when d lies below the plane of (a, b, c) seen with
// a, b, c counter-clockwise from above; the public function flips it.
int shewchuk_orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  ++g_fallbacks;
  const Expansion adx = exact_difference(a.x(), d.x()), ady = exact_difference(a.y(), d.y()),
                  adz = exact_difference(a.z(), d.z());
  const Expansion bdx = exact_difference(b.x(), d.x()), bdy = exact_difference(b.y(), d.y()),
                  bdz = exact_difference(b.z(), d.z());
  const Expansion cdx = exact_difference(c.x(), d.x()), cdy = exact_difference(c.y(), d.y()),
                  cdz = exact_difference(c.z(), d.z());
  Expansion ta, tb, tc, ab, abc;
  product(adx, cross_term(bdy, cdz, bdz, cdy), ta);
  product(bdx, cross_term(cdy, adz, cdz, ady), tb);
  product(cdx, cross_term(ady, bdz, adz, bdy), tc);
  sum(ta, tb, ab);
  sum(ab, tc, abc);
  return abc.sign();
}

}  // namespace

int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const double detleft = (ax - cx) * (by - cy);
  const double detright = (ay - cy) * (bx - cx);
  const double det = detleft - detright;
  const double errbound = kCcwErrBoundA * (std::fabs(detleft) + std::fabs(detright));
  if (det > errbound) return 1;
  if (-det > errbound) return -1;
  return orient2d_exact(ax, ay, bx, by, cx, cy);
}

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double adx = a.x() - d.x(), bdx = b.x() - d.x(), cdx = c.x() - d.x();
  const double ady = a.y() - d.y(), bdy = b.y() - d.y(), cdy = c.y() - d.y();
  const double adz = a.z() - d.z(), bdz = b.z() - d.z(), cdz = c.z() - d.z();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
  const double errbound = kO3dErrBoundA * permanent;
  // Shewchuk's sign convention is the opposite of ours (see the header).
  if (det > errbound) return -1;
  if (-det > errbound) return 1;
  return -shewchuk_orient3d_exact(a, b, c, d);
}

bool collinear(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Test the projection with the largest area first: for a proper triangle it settles the answer
  // in the floating-point filter, and the exact path runs only for (nearly) degenerate ones.
  const Vec3 n = (b - a).cross(c - a).cwiseAbs();
  int first = 0;
  if (n.y() > n[first]) first = 1;
  if (n.z() > n[first]) first = 2;
  for (int k = 0; k < 3; ++k) {
    const int axis = (first + k) % 3;  // projection dropping this axis
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    if (orient2d(a[u], a[v], b[u], b[v], c[u], c[v]) != 0) return false;
  }
  return true;
}

long long exact_fallback_count() { return g_fallbacks; }

}  // namespace gk::exact
