#include "shared/metrology/roundness.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <utility>

namespace chatterlab::surface {
namespace {

constexpr double pi = std::numbers::pi;

// Independent exact method: the optimum of each program is a vertex where 3 (MC, MI) or 4 (MZ)
// constraints are active. Enumerate every such set on a small sample, solve the equalities by
// Cramer's rule, keep the feasible ones, take the best.
double det3(double a[3][3]) {
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
         a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

struct BruteForce {
  double mc = std::numeric_limits<double>::infinity();
  double mi = -std::numeric_limits<double>::infinity();
  double mz = std::numeric_limits<double>::infinity();
};

BruteForce brute_force(const std::vector<double>& r, const std::vector<double>& th) {
  const std::size_t n = r.size();
  BruteForce out;
  auto dev = [&](double a, double b, std::size_t i) { return r[i] - a * std::cos(th[i]) - b * std::sin(th[i]); };
  auto extremes = [&](double a, double b) {
    double hi = -1e300, lo = 1e300;
    for (std::size_t i = 0; i < n; ++i) {
      hi = std::max(hi, dev(a, b, i));
      lo = std::min(lo, dev(a, b, i));
    }
    return std::pair{lo, hi};
  };
  // MC / MI: three points on one circle t + a cos + b sin = r.
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k) {
        const std::size_t id[3] = {i, j, k};
        double m[3][3];
        for (int q = 0; q < 3; ++q) {
          m[q][0] = 1;
          m[q][1] = std::cos(th[id[q]]);
          m[q][2] = std::sin(th[id[q]]);
        }
        const double d = det3(m);
        if (std::abs(d) < 1e-12) continue;
        double sol[3];
        for (int col = 0; col < 3; ++col) {
          double mm[3][3];
          for (int q = 0; q < 3; ++q)
            for (int p = 0; p < 3; ++p) mm[q][p] = p == col ? r[id[q]] : m[q][p];
          sol[col] = det3(mm) / d;
        }
        const auto [lo, hi] = extremes(sol[1], sol[2]);
        if (hi <= sol[0] + 1e-9) out.mc = std::min(out.mc, sol[0]);
        if (lo >= sol[0] - 1e-9) out.mi = std::max(out.mi, sol[0]);
      }
  // MZ: a vertex of the 4-variable program (u, w, a, b) has 4 active constraints: two outer
  // and two inner samples, or three and one. Every vertex's centre bounds the zone from above;
  // the smallest is the minimum zone.
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k)
        for (std::size_t l = 0; l < n; ++l) {
          if (i == j || i == k || i == l || j == k || j == l || k == l) continue;
          auto solve4 = [&](const std::size_t pts[4], const int outer[4]) {
            double m[4][5];
            for (int q = 0; q < 4; ++q) {
              m[q][0] = outer[q] ? 1 : 0;
              m[q][1] = outer[q] ? 0 : 1;
              m[q][2] = std::cos(th[pts[q]]);
              m[q][3] = std::sin(th[pts[q]]);
              m[q][4] = r[pts[q]];
            }
            for (int c = 0; c < 4; ++c) {
              int p = c;
              for (int q = c + 1; q < 4; ++q)
                if (std::abs(m[q][c]) > std::abs(m[p][c])) p = q;
              if (std::abs(m[p][c]) < 1e-12) return;
              for (int z = 0; z < 5; ++z) std::swap(m[c][z], m[p][z]);
              for (int q = 0; q < 4; ++q) {
                if (q == c) continue;
                const double f = m[q][c] / m[c][c];
                for (int z = 0; z < 5; ++z) m[q][z] -= f * m[c][z];
              }
            }
            const double a = m[2][4] / m[2][2], b = m[3][4] / m[3][3];
            const auto [lo, hi] = extremes(a, b);
            out.mz = std::min(out.mz, hi - lo);
          };
          const std::size_t pts[4] = {i, j, k, l};
          if (i < j && k < l) {
            const int two_two[4] = {1, 1, 0, 0};
            solve4(pts, two_two);
          }
          if (i < j && j < k) {
            const int three_one[4] = {1, 1, 1, 0}, one_three[4] = {0, 0, 0, 1};
            solve4(pts, three_one);
            solve4(pts, one_three);
          }
        }
  return out;
}

TEST(Roundness, ThreeLobesAboutTheTrueCentre) {
  const std::size_t n = 360;
  std::vector<double> r(n);
  const auto th = equally_spaced_angles(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = 10.0 + std::cos(3 * th[i]) + 0.4 * std::cos(th[i]);
  const Roundness rd = roundness(r);
  for (const auto* c : {&rd.least_squares, &rd.minimum_zone, &rd.minimum_circumscribed,
                        &rd.maximum_inscribed}) {
    SCOPED_TRACE(c->name);
    EXPECT_TRUE(c->certified);
    EXPECT_NEAR(c->centre_x, 0.4, 1e-9);
    EXPECT_NEAR(c->centre_y, 0.0, 1e-9);
    EXPECT_NEAR(c->RONt, 2.0, 1e-9);
  }
  EXPECT_NEAR(rd.least_squares.RONq, std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(rd.minimum_circumscribed.radius, 11.0, 1e-9);
  EXPECT_NEAR(rd.minimum_circumscribed.RONp, 0.0, 1e-9);
  EXPECT_NEAR(rd.maximum_inscribed.radius, 9.0, 1e-9);
  EXPECT_NEAR(rd.minimum_zone.RONp, 1.0, 1e-9);
  EXPECT_NEAR(rd.minimum_zone.RONv, 1.0, 1e-9);
}

TEST(Roundness, MinimumZoneExactOnAConstructedAnnulus) {
  // Points inside a band of width 1 about centre (0.3, -0.2), with two outer points at 0 and
  // 180 deg and two inner points at 90 and 270 deg: the alternating four-point (Chebyshev)
  // condition makes this band the minimum zone, RONt = 1 exactly.
  const std::size_t n = 400;
  const auto th = equally_spaced_angles(n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> inside(-0.45, 0.45);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) {
    double d = inside(rng);
    if (i == 0 || i == 200) d = 0.5;
    if (i == 100 || i == 300) d = -0.5;
    r[i] = 5.0 + 0.3 * std::cos(th[i]) - 0.2 * std::sin(th[i]) + d;
  }
  const Roundness rd = roundness(r);
  EXPECT_TRUE(rd.minimum_zone.certified);
  EXPECT_NEAR(rd.minimum_zone.RONt, 1.0, 1e-9);
  EXPECT_NEAR(rd.minimum_zone.centre_x, 0.3, 1e-9);
  EXPECT_NEAR(rd.minimum_zone.centre_y, -0.2, 1e-9);
  EXPECT_LE(rd.minimum_zone.RONt, rd.least_squares.RONt + 1e-12);
}

TEST(Roundness, CartesianPointsBetweenTwoConcentricCircles) {
  // Known answer in the plane, not in the limacon model: points measured about a part whose true
  // centre is off the spindle axis by e = (2, -1.5) um, all between the circles of radius R and
  // R + w about that centre, with outer contacts at 0 and 180 deg and inner ones at 90 and
  // 270 deg (alternating: that pair of circles is the minimum zone, the outer one the minimum
  // circumscribed, the inner one the maximum inscribed circle). The instrument sees radii and
  // angles about the axis; the limacon linearisation then differs from the true circles by at
  // most e^2 / (2 R), which bounds every difference below.
  const double big_r = 10000.0, w = 3.0, ex = 2.0, ey = -1.5;  // um
  const double bound = (ex * ex + ey * ey) / big_r;
  const std::size_t n = 720;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> inside(0.05 * w, 0.95 * w);
  std::vector<double> r(n), th(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double phi = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
    double rho = big_r + inside(rng);
    if (i == 0 || i == n / 2) rho = big_r + w;
    if (i == n / 4 || i == 3 * n / 4) rho = big_r;
    const double x = ex + rho * std::cos(phi), y = ey + rho * std::sin(phi);
    r[i] = std::hypot(x, y) - big_r;  // radial deviation about the axis
    th[i] = std::atan2(y, x);
  }
  const Roundness rd = roundness(r, th);
  EXPECT_NEAR(rd.minimum_zone.RONt, w, bound);
  EXPECT_NEAR(rd.minimum_zone.centre_x, ex, 2 * bound);
  EXPECT_NEAR(rd.minimum_zone.centre_y, ey, 2 * bound);
  EXPECT_NEAR(rd.minimum_circumscribed.radius, w, bound);  // radius R + w, less R subtracted
  EXPECT_NEAR(rd.maximum_inscribed.radius, 0.0, bound);
  EXPECT_GT(rd.least_squares.RONt, rd.minimum_zone.RONt);  // LS is not the zone here
  EXPECT_TRUE(rd.minimum_zone.certified && rd.minimum_circumscribed.certified &&
              rd.maximum_inscribed.certified);
}

TEST(Roundness, AgreesWithBruteForceOverVertexCircles) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(trial);
    const std::size_t n = 11;
    std::vector<double> th(n), r(n);
    for (std::size_t i = 0; i < n; ++i) {
      th[i] = 2 * pi * (static_cast<double>(i) + 0.3 * u(rng)) / static_cast<double>(n);
      r[i] = 3.0 + 0.5 * u(rng) + 0.2 * std::cos(th[i]) + 0.1 * std::sin(2 * th[i]);
    }
    const Roundness rd = roundness(r, th);
    const BruteForce bf = brute_force(r, th);
    EXPECT_NEAR(rd.minimum_circumscribed.radius, bf.mc, 1e-9);
    EXPECT_NEAR(rd.maximum_inscribed.radius, bf.mi, 1e-9);
    EXPECT_NEAR(rd.minimum_zone.RONt, bf.mz, 1e-9);
    EXPECT_TRUE(rd.minimum_zone.certified && rd.minimum_circumscribed.certified &&
                rd.maximum_inscribed.certified);
  }
}

TEST(Roundness, MinimumZoneNeverExceedsLeastSquares) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t n = 500 + 37 * static_cast<std::size_t>(trial);
    std::vector<double> r(n);
    const auto th = equally_spaced_angles(n);
    for (std::size_t i = 0; i < n; ++i)
      r[i] = noise(rng) + 2 * std::cos(th[i] * 2 + 1) + std::sin(th[i] * 7);
    const Roundness rd = roundness(r);
    EXPECT_TRUE(rd.minimum_zone.certified);
    EXPECT_LE(rd.minimum_zone.RONt, rd.least_squares.RONt + 1e-12);
    EXPECT_LE(rd.minimum_zone.RONt, rd.minimum_circumscribed.RONt + 1e-12);
    EXPECT_LE(rd.minimum_zone.RONt, rd.maximum_inscribed.RONt + 1e-12);
  }
}

TEST(Roundness, EccentricPerfectCircleIsRoundAboutEveryReference) {
  // Every sample is active at the optimum of all three programs: maximal degeneracy.
  const std::size_t n = 5000;
  const auto th = equally_spaced_angles(n);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = 7.0 + 0.3 * std::cos(th[i]) - 0.1 * std::sin(th[i]);
  const Roundness rd = roundness(r);
  for (const auto* c : {&rd.least_squares, &rd.minimum_zone, &rd.minimum_circumscribed,
                        &rd.maximum_inscribed}) {
    SCOPED_TRACE(c->name);
    EXPECT_NEAR(c->RONt, 0.0, 1e-9);
    EXPECT_NEAR(c->centre_x, 0.3, 1e-9);
    EXPECT_NEAR(c->centre_y, -0.1, 1e-9);
    EXPECT_NEAR(c->radius, 7.0, 1e-9);
  }
}

TEST(Roundness, EquallySpacedAnglesComputedOnTheFlyAgreeWithGivenAngles) {
  // The equally spaced route computes cos and sin by rotation when read (no arrays); given the
  // same angles explicitly, the other route tabulates std::cos/std::sin: the same circles to
  // rounding and the programs' own tolerance (a constraint violated by less than 1e-10 of the
  // range counts as met). An odd sample count over many rotation anchors, noise so the programs
  // need several rounds of constraint generation.
  const std::size_t n = 100003;
  const auto th = equally_spaced_angles(n);
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i)
    r[i] = 40.0 + 0.7 * std::cos(th[i] - 0.3) + 0.5 * std::sin(5 * th[i]) + noise(rng);
  const Roundness a = roundness(r), b = roundness(r, th);
  for (auto [x, y] : {std::pair{&a.least_squares, &b.least_squares},
                      std::pair{&a.minimum_zone, &b.minimum_zone},
                      std::pair{&a.minimum_circumscribed, &b.minimum_circumscribed},
                      std::pair{&a.maximum_inscribed, &b.maximum_inscribed}}) {
    SCOPED_TRACE(x->name);
    EXPECT_TRUE(x->certified);
    for (auto [u, v] : {std::pair{x->centre_x, y->centre_x}, std::pair{x->centre_y, y->centre_y},
                        std::pair{x->radius, y->radius}, std::pair{x->RONt, y->RONt},
                        std::pair{x->RONp, y->RONp}, std::pair{x->RONv, y->RONv},
                        std::pair{x->RONq, y->RONq}})
      EXPECT_NEAR(u, v, 1e-9);
  }
  EXPECT_TRUE(a.least_squares_deviations.empty());  // only on request
}

TEST(Roundness, LeastSquaresDeviationsOnRequest) {
  const std::size_t n = 2000;
  const auto th = equally_spaced_angles(n);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = 3.0 + 0.2 * std::cos(th[i]) + 0.1 * std::cos(4 * th[i]);
  const Roundness rd = roundness(r, References::least_squares_and_zone, Deviations::least_squares);
  const auto& d = rd.least_squares_deviations;
  ASSERT_EQ(d.size(), n);
  const auto expected = deviations(rd.least_squares, r, th);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(d[i], expected[i], 1e-12);
  for (std::size_t i = 0; i < n; i += 50) EXPECT_NEAR(d[i], 0.1 * std::cos(4 * th[i]), 1e-12);
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  EXPECT_NEAR(*hi - *lo, rd.least_squares.RONt, 1e-15);
  EXPECT_TRUE(rd.minimum_circumscribed.name.empty());  // not asked for
}

TEST(Roundness, CoveringLpSolvesASmallProgram) {
  // min x0 + x1 s.t. x0 >= 1, x1 >= 2, x0 + x1 >= 4  -> 4
  const auto lp = solve_covering_lp({{1, 0}, {0, 1}, {1, 1}}, {1, 2, 4}, {1, 1});
  ASSERT_EQ(lp.x.size(), 2u);
  EXPECT_NEAR(lp.primal_objective, 4.0, 1e-12);
  EXPECT_NEAR(lp.dual_objective, 4.0, 1e-12);
  EXPECT_GE(lp.x[0], 1 - 1e-12);
  EXPECT_GE(lp.x[1], 2 - 1e-12);
}

}  // namespace
}  // namespace chatterlab::surface
