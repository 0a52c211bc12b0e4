// Exact orientation predicates against an independent integer oracle.
//
// Every point is built on a lattice whose coordinates are exactly representable doubles, so the
// exact sign of each determinant can be computed with integers (__int128, or a 256-bit sum of
// products where 128 bits are not enough) and compared with the predicate's answer. No test here
// has a tolerance: every assertion is an exact sign.
#include "kernel/predicates/exact_predicates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>

namespace gk {
namespace {

__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 UInt128;

using Rng = std::mt19937_64;
using Lattice = std::array<std::int64_t, 3>;

int sign_of(Int128 v) { return (v > 0) - (v < 0); }

// ---------------------------------------------------------------------------------------------
// A 256-bit two's-complement integer, just enough to add products of an Int128 and an int64.

struct Wide {
  std::array<std::uint64_t, 4> limb{};
};

Wide add(const Wide& x, const Wide& y) {
  Wide out;
  UInt128 carry = 0;
  for (int i = 0; i < 4; ++i) {
    const UInt128 s = static_cast<UInt128>(x.limb[i]) + y.limb[i] + carry;
    out.limb[i] = static_cast<std::uint64_t>(s);
    carry = s >> 64;
  }
  return out;
}

Wide negate(const Wide& x) {
  Wide inverted;
  for (int i = 0; i < 4; ++i) inverted.limb[i] = ~x.limb[i];
  Wide one;
  one.limb[0] = 1;
  return add(inverted, one);
}

Wide product(Int128 a, std::int64_t b) {
  const bool negative = (a < 0) != (b < 0);
  const UInt128 ua = a < 0 ? UInt128{0} - static_cast<UInt128>(a) : static_cast<UInt128>(a);
  const std::uint64_t ub = b < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(b) : static_cast<std::uint64_t>(b);
  const UInt128 lo = static_cast<UInt128>(static_cast<std::uint64_t>(ua)) * ub;
  const UInt128 hi = static_cast<UInt128>(static_cast<std::uint64_t>(ua >> 64)) * ub + (lo >> 64);
  Wide out;
  out.limb = {static_cast<std::uint64_t>(lo), static_cast<std::uint64_t>(hi), static_cast<std::uint64_t>(hi >> 64), 0};
  return negative ? negate(out) : out;
}

int sign_of(const Wide& w) {
  if (w.limb[3] >> 63) return -1;
  return (w.limb[0] | w.limb[1] | w.limb[2] | w.limb[3]) != 0 ? 1 : 0;
}

TEST(ExactPredicatesOracle, WideIntegerArithmeticIsRight) {
  // The oracle itself: (2^62 * 2^62) * 2^62 - (2^62 * 2^62) * 2^62 = 0, and small known products.
  const Int128 big = static_cast<Int128>(std::int64_t{1} << 62) * (std::int64_t{1} << 62);
  const std::int64_t b = std::int64_t{1} << 62;
  EXPECT_EQ(sign_of(add(product(big, b), product(-big, b))), 0);
  EXPECT_EQ(sign_of(add(product(big, b), product(-big, b - 1))), 1);
  EXPECT_EQ(sign_of(add(product(big, -b), product(big, b - 1))), -1);
  EXPECT_EQ(sign_of(add(product(-3, -5), product(-15, 1))), 0);
  EXPECT_EQ(sign_of(add(product(-3, -5), product(-16, 1))), -1);
}

// ---------------------------------------------------------------------------------------------
// Lattice of step 2^-30 mm around a base: exact doubles for |k| < 2^31 and the bases used here.

constexpr double kStep = 0x1p-30;
constexpr double kBases[] = {0.0, 5.0e4, -7.0e3, 8.0e6};

Vec3 on_lattice(const Lattice& k, double base) {
  return Vec3(base + static_cast<double>(k[0]) * kStep, base + static_cast<double>(k[1]) * kStep,
              base + static_cast<double>(k[2]) * kStep);
}

// Sign of ((b - a) x (c - a)) . (d - a) in lattice units; differences below 2^33 keep it in 128 bits.
int oracle_orient3d(const Lattice& a, const Lattice& b, const Lattice& c, const Lattice& d) {
  Int128 u[3], v[3], w[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = b[i] - a[i];
    v[i] = c[i] - a[i];
    w[i] = d[i] - a[i];
  }
  const Int128 nx = u[1] * v[2] - u[2] * v[1];
  const Int128 ny = u[2] * v[0] - u[0] * v[2];
  const Int128 nz = u[0] * v[1] - u[1] * v[0];
  return sign_of(nx * w[0] + ny * w[1] + nz * w[2]);
}

// Sign of (b - a) x (c - a) in the plane.
int oracle_orient2d(std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by, std::int64_t cx,
                    std::int64_t cy) {
  const Int128 left = static_cast<Int128>(bx - ax) * (cy - ay);
  const Int128 right = static_cast<Int128>(by - ay) * (cx - ax);
  return sign_of(left - right);
}

bool fits_lattice(const Lattice& k) {
  constexpr std::int64_t kLimit = std::int64_t{1} << 31;
  return std::all_of(k.begin(), k.end(), [](std::int64_t x) { return x > -kLimit && x < kLimit; });
}

std::int64_t uniform(Rng& rng, std::int64_t lo, std::int64_t hi) {
  return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng);
}

Lattice random_lattice(Rng& rng, std::int64_t range) {
  return {uniform(rng, -range, range), uniform(rng, -range, range), uniform(rng, -range, range)};
}

Lattice plus(const Lattice& a, const Lattice& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }

// A case of four lattice points with the integer answer.
struct Case3 {
  Lattice a, b, c, d;
};

// d exactly on the plane of (a, b, c) (spanning vectors are multiples of 16 and d's coefficients are
// multiples of 1/16), then moved by 0 or +-1 lattice unit along a random axis. With nearly_collinear
// the triangle itself is almost degenerate: c = a + 2 (b - a) + e with e in {-1, 0, 1}^3.
Case3 near_degenerate_case(Rng& rng, bool nearly_collinear) {
  constexpr std::int64_t kRange = std::int64_t{1} << 28;
  for (;;) {
    Case3 k;
    k.a = random_lattice(rng, kRange);
    Lattice u = random_lattice(rng, kRange / 16), v = random_lattice(rng, kRange / 16);
    for (int i = 0; i < 3; ++i) {
      u[i] *= 16;
      v[i] *= 16;
    }
    if (nearly_collinear) {
      for (int i = 0; i < 3; ++i) v[i] = 2 * u[i] + uniform(rng, -1, 1);
    }
    const std::int64_t s = uniform(rng, -8, 24), t = uniform(rng, -8, 24);
    k.b = plus(k.a, u);
    k.c = plus(k.a, v);
    for (int i = 0; i < 3; ++i) k.d[i] = k.a[i] + (s * u[i]) / 16 + (nearly_collinear ? 0 : (t * v[i]) / 16);
    k.d[static_cast<std::size_t>(uniform(rng, 0, 2))] += uniform(rng, -1, 1);
    if (fits_lattice(k.b) && fits_lattice(k.c) && fits_lattice(k.d)) return k;
  }
}

// ---------------------------------------------------------------------------------------------

TEST(ExactPredicates, Orient3dConventionOnSimpleCases) {
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  EXPECT_EQ(exact::orient3d(o, x, y, z), 1);   // d on the side of the right-handed normal (x cross y = z)
  EXPECT_EQ(exact::orient3d(o, x, y, -z), -1);
  EXPECT_EQ(exact::orient3d(o, y, x, z), -1);
  EXPECT_EQ(exact::orient3d(o, x, y, Vec3(0.25, 7.5, 0)), 0);
  EXPECT_EQ(exact::orient3d(o, o, y, z), 0);  // degenerate triangle
  EXPECT_EQ(exact::orient3d(z, z, z, z), 0);
}

TEST(ExactPredicates, Orient2dConventionOnSimpleCases) {
  EXPECT_EQ(exact::orient2d(0, 0, 1, 0, 0, 1), 1);  // counter-clockwise
  EXPECT_EQ(exact::orient2d(0, 0, 0, 1, 1, 0), -1);
  EXPECT_EQ(exact::orient2d(0, 0, 1, 1, 3, 3), 0);
  EXPECT_EQ(exact::orient2d(2, 2, 2, 2, 2, 2), 0);
}

TEST(ExactPredicates, Orient3dMatchesIntegerOracleOnRandomLattice) {
  Rng rng(101);
  constexpr std::int64_t kRange = std::int64_t{1} << 30;  // 1 mm: differences up to 2 mm
  int signs[3] = {0, 0, 0};
  for (int n = 0; n < 2000; ++n) {
    const Lattice a = random_lattice(rng, kRange), b = random_lattice(rng, kRange);
    const Lattice c = random_lattice(rng, kRange), d = random_lattice(rng, kRange);
    const int expected = oracle_orient3d(a, b, c, d);
    ++signs[expected + 1];
    for (double base : kBases) {
      ASSERT_EQ(exact::orient3d(on_lattice(a, base), on_lattice(b, base), on_lattice(c, base), on_lattice(d, base)),
                expected)
          << "case " << n << " base " << base;
    }
  }
  EXPECT_GT(signs[0], 500);
  EXPECT_GT(signs[2], 500);
}

TEST(ExactPredicates, Orient3dMatchesIntegerOracleNearDegenerate) {
  Rng rng(202);
  const long long fallbacks_before = exact::exact_fallback_count();
  int signs[3] = {0, 0, 0};
  for (int n = 0; n < 600; ++n) {
    const Case3 k = near_degenerate_case(rng, n % 3 == 2);
    const int expected = oracle_orient3d(k.a, k.b, k.c, k.d);
    ++signs[expected + 1];
    for (double base : kBases) {
      const Vec3 a = on_lattice(k.a, base), b = on_lattice(k.b, base), c = on_lattice(k.c, base),
                 d = on_lattice(k.d, base);
      ASSERT_EQ(exact::orient3d(a, b, c, d), expected) << "case " << n << " base " << base;
    }
  }
  // Each outcome is well represented, and the exact fallback had to run (every coplanar case at least).
  EXPECT_GT(signs[0], 100);
  EXPECT_GT(signs[1], 100);
  EXPECT_GT(signs[2], 100);
  EXPECT_GE(exact::exact_fallback_count() - fallbacks_before, signs[1]);
}

TEST(ExactPredicates, Orient3dNearlyCollinearTrianglesNeedTheExactPath) {
  // Nearly collinear a, b, c with d one lattice unit off the plane: the determinant is tiny next to
  // its permanent, so the floating-point filter cannot decide and the exact path must be right.
  Rng rng(303);
  const long long fallbacks_before = exact::exact_fallback_count();
  int nonzero = 0;
  for (int n = 0; n < 400; ++n) {
    const Case3 k = near_degenerate_case(rng, true);
    const int expected = oracle_orient3d(k.a, k.b, k.c, k.d);
    nonzero += expected != 0;
    ASSERT_EQ(exact::orient3d(on_lattice(k.a, 5.0e4), on_lattice(k.b, 5.0e4), on_lattice(k.c, 5.0e4),
                              on_lattice(k.d, 5.0e4)),
              expected)
        << "case " << n;
  }
  EXPECT_GT(nonzero, 100);
  EXPECT_GT(exact::exact_fallback_count() - fallbacks_before, 300);
}

TEST(ExactPredicates, Orient3dPermutationParity) {
  // Swapping two points negates the sign; every permutation multiplies it by its parity.
  Rng rng(404);
  std::array<int, 4> perm = {0, 1, 2, 3};
  for (int n = 0; n < 60; ++n) {
    const Case3 k = near_degenerate_case(rng, n % 2 == 0);
    const double base = kBases[n % 4];
    const std::array<Vec3, 4> pts = {on_lattice(k.a, base), on_lattice(k.b, base), on_lattice(k.c, base),
                                     on_lattice(k.d, base)};
    const int reference = exact::orient3d(pts[0], pts[1], pts[2], pts[3]);
    ASSERT_EQ(reference, oracle_orient3d(k.a, k.b, k.c, k.d));
    std::sort(perm.begin(), perm.end());
    do {
      int inversions = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) inversions += perm[i] > perm[j];
      const int parity = inversions % 2 == 0 ? 1 : -1;
      ASSERT_EQ(exact::orient3d(pts[perm[0]], pts[perm[1]], pts[perm[2]], pts[perm[3]]), parity * reference)
          << "case " << n << " permutation " << perm[0] << perm[1] << perm[2] << perm[3];
    } while (std::next_permutation(perm.begin(), perm.end()));
  }
}

TEST(ExactPredicates, Orient2dMatchesIntegerOracleOnLattice) {
  Rng rng(505);
  const long long fallbacks_before = exact::exact_fallback_count();
  constexpr std::int64_t kRange = std::int64_t{1} << 28;
  int signs[3] = {0, 0, 0};
  for (int n = 0; n < 3000; ++n) {
    const std::int64_t ax = uniform(rng, -kRange, kRange), ay = uniform(rng, -kRange, kRange);
    std::int64_t bx, by, cx, cy;
    if (n % 2 == 0) {  // generic
      bx = uniform(rng, -kRange, kRange);
      by = uniform(rng, -kRange, kRange);
      cx = uniform(rng, -kRange, kRange);
      cy = uniform(rng, -kRange, kRange);
    } else {  // c on the line through a and b, then moved by 0 or +-1 unit
      const std::int64_t ux = 16 * uniform(rng, -kRange / 16, kRange / 16);
      const std::int64_t uy = 16 * uniform(rng, -kRange / 16, kRange / 16);
      const std::int64_t s = uniform(rng, -8, 24);
      bx = ax + ux;
      by = ay + uy;
      cx = ax + s * ux / 16 + uniform(rng, -1, 1);
      cy = ay + s * uy / 16 + uniform(rng, -1, 1);
    }
    const int expected = oracle_orient2d(ax, ay, bx, by, cx, cy);
    ++signs[expected + 1];
    for (double base : kBases) {
      auto at = [base](std::int64_t k) { return base + static_cast<double>(k) * kStep; };
      ASSERT_EQ(exact::orient2d(at(ax), at(ay), at(bx), at(by), at(cx), at(cy)), expected)
          << "case " << n << " base " << base;
      // Antisymmetry: swapping two points negates; a cyclic shift keeps the sign.
      ASSERT_EQ(exact::orient2d(at(bx), at(by), at(ax), at(ay), at(cx), at(cy)), -expected) << "case " << n;
      ASSERT_EQ(exact::orient2d(at(ax), at(ay), at(cx), at(cy), at(bx), at(by)), -expected) << "case " << n;
      ASSERT_EQ(exact::orient2d(at(bx), at(by), at(cx), at(cy), at(ax), at(ay)), expected) << "case " << n;
    }
  }
  EXPECT_GT(signs[0], 300);
  EXPECT_GT(signs[1], 100);
  EXPECT_GT(signs[2], 300);
  EXPECT_GE(exact::exact_fallback_count() - fallbacks_before, signs[1]);
}

TEST(ExactPredicates, Orient2dShewchukGridNearOneHalf) {
  // The classic failure plot of a naive orientation test: a = (0.5 + i u, 0.5 + j u) with u the ulp
  // of 0.5 (2^-53), b = (12, 12), c = (24, 24). Integer units of 2^-53 keep the oracle exact.
  constexpr double kUlp = 0x1p-53;
  const std::int64_t half = std::int64_t{1} << 52;  // 0.5 in units of 2^-53
  const std::int64_t twelve = std::int64_t{3} << 55, twenty_four = std::int64_t{3} << 56;
  int signs[3] = {0, 0, 0};
  for (int i = 0; i < 64; ++i) {
    for (int j = 0; j < 64; ++j) {
      const double ax = 0.5 + i * kUlp, ay = 0.5 + j * kUlp;
      const int expected = oracle_orient2d(half + i, half + j, twelve, twelve, twenty_four, twenty_four);
      ++signs[expected + 1];
      ASSERT_EQ(exact::orient2d(ax, ay, 12.0, 12.0, 24.0, 24.0), expected) << "i " << i << " j " << j;
      ASSERT_EQ(exact::orient2d(12.0, 12.0, ax, ay, 24.0, 24.0), -expected) << "i " << i << " j " << j;
    }
  }
  EXPECT_GT(signs[0], 1000);
  EXPECT_GE(signs[1], 64);
  EXPECT_GT(signs[2], 1000);
}

// ---------------------------------------------------------------------------------------------
// Mixed scales: coordinates either "big" (m 2^-40, |m| < 2^40) or "tiny" (j 2^-60, |j| < 2^12), so
// the differences the predicates form are NOT exact doubles and the exact path must carry their
// round-off tails. Integer units of 2^-60 stay below 2^61; the 3D oracle needs 256 bits.

constexpr double kTinyUnit = 0x1p-60;

std::int64_t mixed_coordinate(Rng& rng, bool tiny) {
  if (tiny) return uniform(rng, -(std::int64_t{1} << 12), std::int64_t{1} << 12);
  return uniform(rng, -(std::int64_t{1} << 39), std::int64_t{1} << 39) * (std::int64_t{1} << 20);
}

Vec3 from_tiny_units(const Lattice& k) {
  return Vec3(static_cast<double>(k[0]) * kTinyUnit, static_cast<double>(k[1]) * kTinyUnit,
              static_cast<double>(k[2]) * kTinyUnit);
}

int oracle_orient3d_wide(const Lattice& a, const Lattice& b, const Lattice& c, const Lattice& d) {
  std::int64_t u[3], v[3], w[3];
  for (int i = 0; i < 3; ++i) {
    u[i] = b[i] - a[i];
    v[i] = c[i] - a[i];
    w[i] = d[i] - a[i];
  }
  const Int128 nx = static_cast<Int128>(u[1]) * v[2] - static_cast<Int128>(u[2]) * v[1];
  const Int128 ny = static_cast<Int128>(u[2]) * v[0] - static_cast<Int128>(u[0]) * v[2];
  const Int128 nz = static_cast<Int128>(u[0]) * v[1] - static_cast<Int128>(u[1]) * v[0];
  return sign_of(add(add(product(nx, w[0]), product(ny, w[1])), product(nz, w[2])));
}

TEST(ExactPredicates, Orient3dMixedScalesWithInexactDifferences) {
  Rng rng(606);
  int signs[3] = {0, 0, 0};
  for (int n = 0; n < 600; ++n) {
    // All four points on the plane x[dep] = s * x[src] (s = +-1, +-2), which keeps every coordinate
    // exact whatever its scale; then d's dependent coordinate moves by 0 or +-1 unit (d's source
    // coordinate is tiny, so the moved value is still exact).
    const int src = static_cast<int>(uniform(rng, 0, 2));
    const int dep = (src + 1 + static_cast<int>(uniform(rng, 0, 1))) % 3;
    const int free_axis = 3 - src - dep;
    const std::int64_t s = std::array<std::int64_t, 4>{1, -1, 2, -2}[uniform(rng, 0, 3)];
    std::array<Lattice, 4> k;
    for (int p = 0; p < 4; ++p) {
      k[p][src] = mixed_coordinate(rng, p == 3 || uniform(rng, 0, 1) == 0);
      k[p][free_axis] = mixed_coordinate(rng, uniform(rng, 0, 1) == 0);
      k[p][dep] = s * k[p][src];
    }
    k[3][dep] += uniform(rng, -1, 1);
    const int expected = oracle_orient3d_wide(k[0], k[1], k[2], k[3]);
    ++signs[expected + 1];
    const Vec3 a = from_tiny_units(k[0]), b = from_tiny_units(k[1]), c = from_tiny_units(k[2]),
               d = from_tiny_units(k[3]);
    ASSERT_EQ(exact::orient3d(a, b, c, d), expected) << "case " << n;
    ASSERT_EQ(exact::orient3d(d, a, b, c), -expected) << "case " << n;  // odd permutation
    ASSERT_EQ(exact::orient3d(b, a, d, c), expected) << "case " << n;   // even permutation
  }
  EXPECT_GT(signs[0], 100);
  EXPECT_GT(signs[1], 100);
  EXPECT_GT(signs[2], 100);
}

TEST(ExactPredicates, Orient2dMixedScalesWithInexactDifferences) {
  Rng rng(707);
  int signs[3] = {0, 0, 0};
  for (int n = 0; n < 2000; ++n) {
    // Three points on the line y = s x, the last with a tiny x, then its y moved by 0 or +-1 unit.
    const std::int64_t s = std::array<std::int64_t, 4>{1, -1, 2, -2}[uniform(rng, 0, 3)];
    std::int64_t x[3], y[3];
    for (int p = 0; p < 3; ++p) {
      x[p] = mixed_coordinate(rng, p == 2 || uniform(rng, 0, 1) == 0);
      y[p] = s * x[p];
    }
    y[2] += uniform(rng, -1, 1);
    const int expected = oracle_orient2d(x[0], y[0], x[1], y[1], x[2], y[2]);
    ++signs[expected + 1];
    auto v = [](std::int64_t k) { return static_cast<double>(k) * kTinyUnit; };
    ASSERT_EQ(exact::orient2d(v(x[0]), v(y[0]), v(x[1]), v(y[1]), v(x[2]), v(y[2])), expected) << "case " << n;
    ASSERT_EQ(exact::orient2d(v(x[2]), v(y[2]), v(x[1]), v(y[1]), v(x[0]), v(y[0])), -expected) << "case " << n;
    // Swapping the axes mirrors the plane, which also negates the sign.
    ASSERT_EQ(exact::orient2d(v(y[0]), v(x[0]), v(y[1]), v(x[1]), v(y[2]), v(x[2])), -expected) << "case " << n;
  }
  EXPECT_GT(signs[0], 300);
  EXPECT_GT(signs[1], 300);
  EXPECT_GT(signs[2], 300);
}

TEST(ExactPredicates, CollinearMatchesIntegerOracle) {
  Rng rng(808);
  constexpr std::int64_t kRange = std::int64_t{1} << 28;
  int collinear_count = 0, total = 0;
  for (int n = 0; n < 1500; ++n) {
    const Lattice a = random_lattice(rng, kRange);
    Lattice u = random_lattice(rng, kRange / 16);
    if (n % 5 == 0) u[static_cast<std::size_t>(uniform(rng, 0, 2))] = 0;  // lines in a coordinate plane
    if (n % 7 == 0) u = {0, 0, uniform(rng, 1, kRange / 16)};             // lines along an axis
    for (int i = 0; i < 3; ++i) u[i] *= 16;
    const std::int64_t s = uniform(rng, -8, 24);
    const Lattice b = plus(a, u);
    Lattice c;
    for (int i = 0; i < 3; ++i) c[i] = a[i] + s * u[i] / 16;
    if (n % 2 == 1) c[static_cast<std::size_t>(uniform(rng, 0, 2))] += uniform(rng, -1, 1);
    // Collinear exactly when (b - a) x (c - a) vanishes.
    const Int128 ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const Int128 vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const bool expected = uy * vz - uz * vy == 0 && uz * vx - ux * vz == 0 && ux * vy - uy * vx == 0;
    collinear_count += expected;
    ++total;
    for (double base : kBases) {
      const Vec3 pa = on_lattice(a, base), pb = on_lattice(b, base), pc = on_lattice(c, base);
      ASSERT_EQ(exact::collinear(pa, pb, pc), expected) << "case " << n << " base " << base;
      ASSERT_EQ(exact::collinear(pc, pa, pb), expected) << "case " << n << " base " << base;
      ASSERT_EQ(exact::collinear(pb, pa, pc), expected) << "case " << n << " base " << base;
    }
  }
  EXPECT_GT(collinear_count, 400);
  EXPECT_GT(total - collinear_count, 400);
  // Coincident points are collinear.
  EXPECT_TRUE(exact::collinear(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(4, -5, 6)));
  EXPECT_TRUE(exact::collinear(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)));
}

}  // namespace
}  // namespace gk
