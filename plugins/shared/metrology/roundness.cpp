#include "shared/metrology/roundness.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <numbers>
#include <stdexcept>

namespace chatterlab::surface {
namespace {

// Solves the small dense system m x = r in place (partial pivoting); m is n x n.
std::vector<double> solve_dense(std::vector<std::vector<double>> m, std::vector<double> r) {
  const std::size_t n = r.size();
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t p = k;
    for (std::size_t i = k + 1; i < n; ++i)
      if (std::abs(m[i][k]) > std::abs(m[p][k])) p = i;
    std::swap(m[k], m[p]);
    std::swap(r[k], r[p]);
    for (std::size_t i = k + 1; i < n; ++i) {
      const double f = m[i][k] / m[k][k];
      for (std::size_t j = k; j < n; ++j) m[i][j] -= f * m[k][j];
      r[i] -= f * r[k];
    }
  }
  std::vector<double> x(n);
  for (std::size_t i = n; i-- > 0;) {
    double s = r[i];
    for (std::size_t j = i + 1; j < n; ++j) s -= m[i][j] * x[j];
    x[i] = s / m[i][i];
  }
  return x;
}

// The three reference-circle programs, min e.x s.t. per sample one or two rows A . x >= c:
//   circumscribed: x = (t, a, b),        t + a cos + b sin >= r
//   inscribed:     x = (-t, -a, -b),    -t - a cos - b sin >= -r
//   zone:          x = (u, -l, a, b),    u + a cos + b sin >= r  and  -l - a cos - b sin >= -r
enum class Program { circumscribed, inscribed, zone };

struct Samples {
  const std::vector<double>& r;
  const std::vector<double>& cs;
  const std::vector<double>& sn;
};

// Rows of sample i (returns how many: 1 or 2), each 4 wide (unused tail 0).
int rows_of(Program program, const Samples& s, std::size_t i, double a[2][4], double c[2]) {
  switch (program) {
    case Program::circumscribed:
      a[0][0] = 1, a[0][1] = s.cs[i], a[0][2] = s.sn[i], a[0][3] = 0, c[0] = s.r[i];
      return 1;
    case Program::inscribed:
      a[0][0] = 1, a[0][1] = s.cs[i], a[0][2] = s.sn[i], a[0][3] = 0, c[0] = -s.r[i];
      return 1;
    case Program::zone:
      a[0][0] = 1, a[0][1] = 0, a[0][2] = s.cs[i], a[0][3] = s.sn[i], c[0] = s.r[i];
      a[1][0] = 0, a[1][1] = 1, a[1][2] = -s.cs[i], a[1][3] = -s.sn[i], c[1] = -s.r[i];
      return 2;
  }
  return 0;
}

struct ProgramSolution {
  std::vector<double> x;
  bool certified = false;
  double duality_gap = 0;
};

// min e.x over all samples' constraints by constraint generation: solve on a subset, add the
// most violated samples, repeat until every sample's constraints hold.
ProgramSolution solve_by_constraint_generation(Program program, const Samples& s, double scale) {
  const std::size_t samples = s.r.size();
  const std::size_t m = program == Program::zone ? 4 : 3;
  const std::vector<double> e =
      program == Program::zone ? std::vector<double>{1, 1, 0, 0} : std::vector<double>{1, 0, 0};
  std::vector<char> in_subset(samples, 0);
  std::vector<std::size_t> subset;
  auto add = [&](std::size_t i) {
    if (!in_subset[i]) {
      in_subset[i] = 1;
      subset.push_back(i);
    }
  };
  const std::size_t start = std::min<std::size_t>(samples, 72);
  for (std::size_t k = 0; k < start; ++k) add(k * samples / start);

  const double tolerance = 1e-10 * std::max(scale, 1e-300);
  double a[2][4], c[2];
  ProgramSolution out;
  for (int round = 0; round < 200; ++round) {
    std::vector<std::vector<double>> rows;
    std::vector<double> costs;
    for (std::size_t i : subset) {
      const int k = rows_of(program, s, i, a, c);
      for (int q = 0; q < k; ++q) {
        rows.emplace_back(a[q], a[q] + m);
        costs.push_back(c[q]);
      }
    }
    LinearProgramResult lp = solve_covering_lp(rows, costs, e);
    if (lp.x.empty()) {  // the subset does not surround the centre: take every sample
      if (subset.size() == samples) return out;
      for (std::size_t i = 0; i < samples; ++i) add(i);
      continue;
    }
    std::vector<std::pair<double, std::size_t>> violated;
    for (std::size_t i = 0; i < samples; ++i) {
      const int k = rows_of(program, s, i, a, c);
      double worst = 0;
      for (int q = 0; q < k; ++q) {
        double lhs = 0;
        for (std::size_t j = 0; j < m; ++j) lhs += a[q][j] * lp.x[j];
        worst = std::max(worst, c[q] - lhs);
      }
      if (worst > tolerance && !in_subset[i]) violated.emplace_back(worst, i);
    }
    out.x = lp.x;
    out.duality_gap = std::abs(lp.primal_objective - lp.dual_objective);
    if (violated.empty()) {
      out.certified = out.duality_gap <= 1e-9 * std::max(scale, 1e-300);
      return out;
    }
    const std::size_t take = std::min<std::size_t>(violated.size(), 64);
    std::partial_sort(violated.begin(), violated.begin() + static_cast<std::ptrdiff_t>(take),
                      violated.end(), std::greater<>());
    for (std::size_t k = 0; k < take; ++k) add(violated[k].second);
  }
  return out;  // not certified
}

// r_i - a cos_i - b sin_i - R with the cosines and sines already taken.
std::vector<double> limacon_deviations(const ReferenceCircle& circle, const std::vector<double>& r,
                                       const std::vector<double>& cs, const std::vector<double>& sn) {
  std::vector<double> d(r.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    d[i] = r[i] - circle.centre_x * cs[i] - circle.centre_y * sn[i] - circle.radius;
  return d;
}

void finish(ReferenceCircle& circle, const std::vector<double>& d) {
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  double mean = 0;
  for (double v : d) mean += v;
  mean /= static_cast<double>(d.size());
  double sq = 0;
  for (double v : d) sq += (v - mean) * (v - mean);
  circle.RONt = *hi - *lo;
  circle.RONp = std::max(0.0, *hi - circle.radius);
  circle.RONv = std::max(0.0, circle.radius - *lo);
  circle.RONq = std::sqrt(sq / static_cast<double>(d.size()));
}

Roundness roundness_with_trig(const std::vector<double>& radius, const std::vector<double>& cs,
                              const std::vector<double>& sn, References references);

}  // namespace

LinearProgramResult solve_covering_lp(const std::vector<std::vector<double>>& rows,
                                      const std::vector<double>& c, const std::vector<double>& e) {
  const std::size_t n = rows.size(), m = e.size(), rhs = n + m;
  // Tableau [A^T | I | e] with rows flipped where e_k < 0 so the artificial start is feasible.
  std::vector<std::vector<double>> t(m, std::vector<double>(n + m + 1, 0.0));
  std::vector<double> sign(m, 1.0);
  for (std::size_t k = 0; k < m; ++k) {
    sign[k] = e[k] < 0 ? -1.0 : 1.0;
    for (std::size_t j = 0; j < n; ++j) t[k][j] = sign[k] * rows[j][k];
    t[k][n + k] = 1.0;
    t[k][rhs] = sign[k] * e[k];
  }
  std::vector<std::size_t> basis(m);
  for (std::size_t k = 0; k < m; ++k) basis[k] = n + k;
  double cost_scale = 0;
  for (double v : c) cost_scale = std::max(cost_scale, std::abs(v));
  const double pivot_eps = 1e-11;

  auto pivot = [&](std::size_t row, std::size_t col) {
    const double p = t[row][col];
    for (double& v : t[row]) v /= p;
    for (std::size_t k = 0; k < m; ++k) {
      if (k == row || t[k][col] == 0.0) continue;
      const double f = t[k][col];
      for (std::size_t j = 0; j <= rhs; ++j) t[k][j] -= f * t[row][j];
    }
    basis[row] = col;
  };
  // Simplex with Bland's rule (no cycling on these very degenerate programs). Returns false
  // when unbounded.
  auto run = [&](const std::vector<double>& cost, std::size_t enter_limit, double eps) {
    for (int iteration = 0; iteration < 100000; ++iteration) {
      std::size_t enter = enter_limit;
      for (std::size_t j = 0; j < enter_limit; ++j) {
        double d = cost[j];
        for (std::size_t k = 0; k < m; ++k) d -= cost[basis[k]] * t[k][j];
        if (d > eps) {
          enter = j;
          break;
        }
      }
      if (enter == enter_limit) return true;
      std::size_t leave = m;
      double best = 0;
      for (std::size_t k = 0; k < m; ++k) {
        if (t[k][enter] <= pivot_eps) continue;
        const double ratio = t[k][rhs] / t[k][enter];
        if (leave == m || ratio < best - 1e-15 ||
            (ratio <= best + 1e-15 && basis[k] < basis[leave])) {
          leave = k;
          best = ratio;
        }
      }
      if (leave == m) return false;
      pivot(leave, enter);
    }
    return false;
  };

  std::vector<double> phase1(n + m, 0.0);
  for (std::size_t k = 0; k < m; ++k) phase1[n + k] = -1.0;
  run(phase1, n + m, 1e-12);
  double infeasibility = 0;
  for (std::size_t k = 0; k < m; ++k)
    if (basis[k] >= n) infeasibility += t[k][rhs];
  if (infeasibility > 1e-9) return {};
  for (std::size_t k = 0; k < m; ++k) {
    if (basis[k] < n) continue;
    for (std::size_t j = 0; j < n; ++j)
      if (std::abs(t[k][j]) > pivot_eps) {
        pivot(k, j);
        break;
      }
  }
  std::vector<double> phase2(n + m, 0.0);
  std::copy(c.begin(), c.end(), phase2.begin());
  if (!run(phase2, n, 1e-12 * std::max(cost_scale, 1e-300))) return {};

  LinearProgramResult out;
  out.x.assign(m, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    double pi_k = 0;
    for (std::size_t i = 0; i < m; ++i) pi_k += phase2[basis[i]] * t[i][n + k];
    out.x[k] = sign[k] * pi_k;
    out.primal_objective += e[k] * out.x[k];
  }
  for (std::size_t i = 0; i < m; ++i) out.dual_objective += phase2[basis[i]] * t[i][rhs];
  return out;
}

std::vector<double> equally_spaced_angles(std::size_t n) {
  std::vector<double> th(n);
  for (std::size_t i = 0; i < n; ++i)
    th[i] = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
  return th;
}

std::vector<double> deviations(const ReferenceCircle& circle, const std::vector<double>& radius,
                               const std::vector<double>& angle_rad) {
  std::vector<double> cs(radius.size()), sn(radius.size());
  for (std::size_t i = 0; i < radius.size(); ++i) {
    cs[i] = std::cos(angle_rad[i]);
    sn[i] = std::sin(angle_rad[i]);
  }
  return limacon_deviations(circle, radius, cs, sn);
}

Roundness roundness(const std::vector<double>& radius, References references) {
  const std::size_t n = radius.size();
  std::vector<double> cs(n), sn(n);
  // cos/sin of 2 pi i / N by rotation, re-anchored on the exact value every 256 samples (error
  // ~1e-14; a million trig calls per circle would cost more than the circles).
  const double step = 2 * std::numbers::pi / static_cast<double>(n);
  const double c1 = std::cos(step), s1 = std::sin(step);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 256 == 0) {
      cs[i] = std::cos(step * static_cast<double>(i));
      sn[i] = std::sin(step * static_cast<double>(i));
    } else {
      cs[i] = cs[i - 1] * c1 - sn[i - 1] * s1;
      sn[i] = sn[i - 1] * c1 + cs[i - 1] * s1;
    }
  }
  return roundness_with_trig(radius, cs, sn, references);
}

Roundness roundness(const std::vector<double>& radius, const std::vector<double>& angle_rad,
                    References references) {
  if (angle_rad.size() != radius.size())
    throw std::invalid_argument("roundness: needs one angle per sample");
  std::vector<double> cs(radius.size()), sn(radius.size());
  for (std::size_t i = 0; i < radius.size(); ++i) {
    cs[i] = std::cos(angle_rad[i]);
    sn[i] = std::sin(angle_rad[i]);
  }
  return roundness_with_trig(radius, cs, sn, references);
}

namespace {

Roundness roundness_with_trig(const std::vector<double>& radius, const std::vector<double>& cs,
                              const std::vector<double>& sn, References references) {
  const std::size_t n = radius.size();
  if (n < 4) throw std::invalid_argument("roundness: needs >= 4 samples");
  // Work about the mean radius so the programs' numbers are of the size of the form error.
  double mean = 0;
  for (double v : radius) mean += v;
  mean /= static_cast<double>(n);
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = radius[i] - mean;
  const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
  const double scale = std::max(*hi - *lo, 1e-300);

  Roundness out;
  // Least squares: normal equations of r ~ R + a cos + b sin.
  {
    std::vector<std::vector<double>> m(3, std::vector<double>(3, 0.0));
    std::vector<double> rhs(3, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const double b[3] = {1.0, cs[i], sn[i]};
      for (int p = 0; p < 3; ++p) {
        rhs[static_cast<std::size_t>(p)] += b[p] * r[i];
        for (int q = 0; q < 3; ++q) m[static_cast<std::size_t>(p)][static_cast<std::size_t>(q)] += b[p] * b[q];
      }
    }
    const auto x = solve_dense(m, rhs);
    out.least_squares = {"least_squares", x[1], x[2], x[0]};
  }
  const Samples samples{r, cs, sn};
  auto circle = [&](const char* name, const ProgramSolution& sol, double a, double b,
                    double radius_) {
    if (sol.x.empty())
      throw std::invalid_argument(
          "roundness: the samples do not surround the centre (they must cover the whole turn)");
    ReferenceCircle c{name, a, b, radius_};
    c.certified = sol.certified;
    c.duality_gap = sol.duality_gap;
    finish(c, limacon_deviations(c, r, cs, sn));
    c.radius += mean;
    return c;
  };
  const auto mz = solve_by_constraint_generation(Program::zone, samples, scale);
  out.minimum_zone = circle("minimum_zone", mz, mz.x.empty() ? 0 : mz.x[2],
                            mz.x.empty() ? 0 : mz.x[3],
                            mz.x.empty() ? 0 : 0.5 * (mz.x[0] - mz.x[1]));
  if (references == References::all) {
    const auto mc = solve_by_constraint_generation(Program::circumscribed, samples, scale);
    const auto mi = solve_by_constraint_generation(Program::inscribed, samples, scale);
    out.minimum_circumscribed =
        circle("minimum_circumscribed", mc, mc.x.empty() ? 0 : mc.x[1], mc.x.empty() ? 0 : mc.x[2],
               mc.x.empty() ? 0 : mc.x[0]);
    out.maximum_inscribed =
        circle("maximum_inscribed", mi, mi.x.empty() ? 0 : -mi.x[1], mi.x.empty() ? 0 : -mi.x[2],
               mi.x.empty() ? 0 : -mi.x[0]);
  }
  out.least_squares_deviations = limacon_deviations(out.least_squares, r, cs, sn);
  finish(out.least_squares, out.least_squares_deviations);
  out.least_squares.radius += mean;
  return out;
}

}  // namespace

}  // namespace chatterlab::surface
