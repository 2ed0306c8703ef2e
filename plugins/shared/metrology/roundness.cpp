#include "shared/metrology/roundness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
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

// cos and sin of the samples' angles, read in sweeps (every sample in order) and at single
// samples (the constraint-generation subset), in the same values either way.
//
// Equally spaced angles 2 pi i / N, computed when read instead of held in two arrays (16 bytes
// per sample): by rotation, re-anchored on the exact value every 256 samples (error ~1e-14; ten
// million trig calls per sweep would cost more than the circles). A sweep rotates one block into
// a small buffer before using it, so the rotation's latency chain is not interleaved with the
// work on each sample; a single sample is rotated from its anchor to the same value.
class EquallySpacedTrig {
 public:
  explicit EquallySpacedTrig(std::size_t n)
      : n_(n),
        step_(2 * std::numbers::pi / static_cast<double>(n)),
        c1_(std::cos(step_)),
        s1_(std::sin(step_)) {}

  std::size_t size() const { return n_; }

  // f(i, cos theta_i, sin theta_i) for i = 0..N-1.
  template <class F>
  void sweep(F&& f) const {
    // Two blocks at a time: their rotations are independent, so they overlap in the pipeline.
    std::array<double, 2 * block> cs{}, sn{};
    for (std::size_t first = 0; first < n_; first += 2 * block) {
      const std::size_t count = std::min(2 * block, n_ - first);
      anchor(first, cs[0], sn[0]);
      if (count > block) anchor(first + block, cs[block], sn[block]);
      for (std::size_t k = 1; k < block; ++k) {
        rotate(cs[k - 1], sn[k - 1], cs[k], sn[k]);
        rotate(cs[block + k - 1], sn[block + k - 1], cs[block + k], sn[block + k]);
      }
      for (std::size_t k = 0; k < count; ++k) f(first + k, cs[k], sn[k]);
    }
  }

  void at(std::size_t i, double& c, double& s) const {
    anchor(i - i % block, c, s);
    for (std::size_t k = 0; k < i % block; ++k) {
      double next_c, next_s;
      rotate(c, s, next_c, next_s);
      c = next_c;
      s = next_s;
    }
  }

 private:
  static constexpr std::size_t block = 256;
  void anchor(std::size_t i, double& c, double& s) const {
    c = std::cos(step_ * static_cast<double>(i));
    s = std::sin(step_ * static_cast<double>(i));
  }
  void rotate(double c, double s, double& next_c, double& next_s) const {
    next_c = c * c1_ - s * s1_;
    next_s = s * c1_ + c * s1_;
  }
  std::size_t n_;
  double step_, c1_, s1_;
};

// Arbitrary angles: tabulated once.
class TabulatedTrig {
 public:
  explicit TabulatedTrig(std::span<const double> angle_rad)
      : cs_(angle_rad.size()), sn_(angle_rad.size()) {
    for (std::size_t i = 0; i < angle_rad.size(); ++i) {
      cs_[i] = std::cos(angle_rad[i]);
      sn_[i] = std::sin(angle_rad[i]);
    }
  }
  std::size_t size() const { return cs_.size(); }
  template <class F>
  void sweep(F&& f) const {
    for (std::size_t i = 0; i < cs_.size(); ++i) f(i, cs_[i], sn_[i]);
  }
  void at(std::size_t i, double& c, double& s) const {
    c = cs_[i];
    s = sn_[i];
  }

 private:
  std::vector<double> cs_, sn_;
};

// The radii about their mean (the programs' numbers are then of the size of the form error) and
// the angles' cos and sin.
template <class Trig>
struct Samples {
  std::span<const double> radius;
  double mean;
  const Trig& trig;
  double r(std::size_t i) const { return radius[i] - mean; }
  // f(i, r_i, cos, sin) for every sample in order.
  template <class F>
  void sweep(F&& f) const {
    trig.sweep([&](std::size_t i, double c, double s) { f(i, r(i), c, s); });
  }
};

// The three reference-circle programs, min e.x s.t. per sample one or two rows A . x >= c:
//   circumscribed: x = (t, a, b),        t + a cos + b sin >= r
//   inscribed:     x = (-t, -a, -b),    -t - a cos - b sin >= -r
//   zone:          x = (u, -l, a, b),    u + a cos + b sin >= r  and  -l - a cos - b sin >= -r
enum class Program { circumscribed, inscribed, zone };

// Rows of a sample (radius r, angle cos cs, sin sn; returns how many: 1 or 2), each 4 wide
// (unused tail 0).
int rows_of(Program program, double r, double cs, double sn, double a[2][4], double c[2]) {
  switch (program) {
    case Program::circumscribed:
      a[0][0] = 1, a[0][1] = cs, a[0][2] = sn, a[0][3] = 0, c[0] = r;
      return 1;
    case Program::inscribed:
      a[0][0] = 1, a[0][1] = cs, a[0][2] = sn, a[0][3] = 0, c[0] = -r;
      return 1;
    case Program::zone:
      a[0][0] = 1, a[0][1] = 0, a[0][2] = cs, a[0][3] = sn, c[0] = r;
      a[1][0] = 0, a[1][1] = 1, a[1][2] = -cs, a[1][3] = -sn, c[1] = -r;
      return 2;
  }
  return 0;
}

// How far a sample's rows are from holding at x: max(0, c - A . x) over its rows (rows_of
// written out: this runs for every sample in every round).
inline double violation(Program program, const std::vector<double>& x, double r, double cs,
                        double sn) {
  switch (program) {
    case Program::circumscribed:
      return std::max(0.0, r - (x[0] + cs * x[1] + sn * x[2]));
    case Program::inscribed:
      return std::max(0.0, -r - (x[0] + cs * x[1] + sn * x[2]));
    case Program::zone:
      return std::max({0.0, r - (x[0] + cs * x[2] + sn * x[3]),
                       -r - (x[1] - cs * x[2] - sn * x[3])});
  }
  return 0.0;
}

struct ProgramSolution {
  std::vector<double> x;
  bool certified = false;
  double duality_gap = 0;
};

// The `capacity` largest (violation, sample) pairs seen, in descending order by sorted(): what a
// partial sort of every violated sample would give, in constant memory (a rough start can
// violate half the samples of a 10^7-sample revolution).
class LargestViolations {
 public:
  explicit LargestViolations(std::size_t capacity) : capacity_(capacity) {}
  void add(double violation, std::size_t sample) {
    ++seen_;
    const std::pair<double, std::size_t> entry{violation, sample};
    if (heap_.size() < capacity_) {
      heap_.push_back(entry);
      std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
    } else if (entry > heap_.front()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<>());
      heap_.back() = entry;
      std::push_heap(heap_.begin(), heap_.end(), std::greater<>());
    }
  }
  bool empty() const { return seen_ == 0; }
  std::vector<std::pair<double, std::size_t>> sorted() && {
    std::sort(heap_.begin(), heap_.end(), std::greater<>());
    return std::move(heap_);
  }

 private:
  std::size_t capacity_, seen_ = 0;
  std::vector<std::pair<double, std::size_t>> heap_;  // min-heap of the largest
};

// min e.x over all samples' constraints by constraint generation: solve on a subset, add the
// most violated samples, repeat until every sample's constraints hold.
template <class Trig>
ProgramSolution solve_by_constraint_generation(Program program, const Samples<Trig>& s,
                                               double scale) {
  const std::size_t samples = s.radius.size();
  const std::size_t m = program == Program::zone ? 4 : 3;
  const std::vector<double> e =
      program == Program::zone ? std::vector<double>{1, 1, 0, 0} : std::vector<double>{1, 0, 0};
  std::vector<char> in_subset(samples, 0);
  // The subset's rows, made once when a sample joins (the subset only grows).
  std::vector<std::vector<double>> rows;
  std::vector<double> costs;
  double a[2][4], c[2];
  std::size_t subset_size = 0;
  auto add = [&](std::size_t i) {
    if (in_subset[i]) return;
    in_subset[i] = 1;
    ++subset_size;
    double cs, sn;
    s.trig.at(i, cs, sn);
    const int k = rows_of(program, s.r(i), cs, sn, a, c);
    for (int q = 0; q < k; ++q) {
      rows.emplace_back(a[q], a[q] + m);
      costs.push_back(c[q]);
    }
  };
  const std::size_t start = std::min<std::size_t>(samples, 72);
  for (std::size_t k = 0; k < start; ++k) add(k * samples / start);

  const double tolerance = 1e-10 * std::max(scale, 1e-300);
  ProgramSolution out;
  for (int round = 0; round < 200; ++round) {
    LinearProgramResult lp = solve_covering_lp(rows, costs, e);
    if (lp.x.empty()) {  // the subset does not surround the centre: take every sample
      if (subset_size == samples) return out;
      for (std::size_t i = 0; i < samples; ++i) add(i);
      continue;
    }
    LargestViolations violated(64);
    const std::vector<double>& x = lp.x;
    s.sweep([&](std::size_t i, double r, double cs, double sn) {
      const double worst = violation(program, x, r, cs, sn);
      if (worst > tolerance && !in_subset[i]) violated.add(worst, i);
    });
    out.x = lp.x;
    out.duality_gap = std::abs(lp.primal_objective - lp.dual_objective);
    if (violated.empty()) {
      out.certified = out.duality_gap <= 1e-9 * std::max(scale, 1e-300);
      return out;
    }
    for (const auto& [violation, i] : std::move(violated).sorted()) add(i);
  }
  return out;  // not certified
}

// r_i - a cos_i - b sin_i - R.
double limacon_deviation(const ReferenceCircle& circle, double r, double cs, double sn) {
  return r - circle.centre_x * cs - circle.centre_y * sn - circle.radius;
}

// The circle's RONt, RONp, RONv, RONq from its deviations, which for_each(f) passes to f in order
// (twice: the rms is about their mean).
template <class ForEach>
void finish(ReferenceCircle& circle, std::size_t n, const ForEach& for_each) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, mean = 0;
  for_each([&](double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    mean += v;
  });
  mean /= static_cast<double>(n);
  double sq = 0;
  for_each([&](double v) { sq += (v - mean) * (v - mean); });
  circle.RONt = hi - lo;
  circle.RONp = std::max(0.0, hi - circle.radius);
  circle.RONv = std::max(0.0, circle.radius - lo);
  circle.RONq = std::sqrt(sq / static_cast<double>(n));
}

template <class Trig>
Roundness roundness_with_trig(std::span<const double> radius, const Trig& trig,
                              References references, Deviations deviations);

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

std::vector<double> deviations(const ReferenceCircle& circle, std::span<const double> radius,
                               std::span<const double> angle_rad) {
  std::vector<double> d(radius.size());
  for (std::size_t i = 0; i < radius.size(); ++i)
    d[i] = limacon_deviation(circle, radius[i], std::cos(angle_rad[i]), std::sin(angle_rad[i]));
  return d;
}

Roundness roundness(std::span<const double> radius, References references,
                    Deviations deviations) {
  return roundness_with_trig(radius, EquallySpacedTrig(radius.size()), references, deviations);
}

Roundness roundness(std::span<const double> radius, std::span<const double> angle_rad,
                    References references, Deviations deviations) {
  if (angle_rad.size() != radius.size())
    throw std::invalid_argument("roundness: needs one angle per sample");
  return roundness_with_trig(radius, TabulatedTrig(angle_rad), references, deviations);
}

namespace {

template <class Trig>
Roundness roundness_with_trig(std::span<const double> radius, const Trig& trig,
                              References references, Deviations deviations) {
  const std::size_t n = radius.size();
  if (n < 4) throw std::invalid_argument("roundness: needs >= 4 samples");
  // Work about the mean radius so the programs' numbers are of the size of the form error.
  double mean = 0;
  for (double v : radius) mean += v;
  mean /= static_cast<double>(n);
  const Samples<Trig> samples{radius, mean, trig};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    lo = std::min(lo, samples.r(i));
    hi = std::max(hi, samples.r(i));
  }
  const double scale = std::max(hi - lo, 1e-300);

  Roundness out;
  // Least squares: normal equations of r ~ R + a cos + b sin.
  {
    std::vector<std::vector<double>> m(3, std::vector<double>(3, 0.0));
    std::vector<double> rhs(3, 0.0);
    samples.sweep([&](std::size_t, double r, double cs, double sn) {
      const double b[3] = {1.0, cs, sn};
      for (int p = 0; p < 3; ++p) {
        rhs[static_cast<std::size_t>(p)] += b[p] * r;
        for (int q = 0; q < 3; ++q) m[static_cast<std::size_t>(p)][static_cast<std::size_t>(q)] += b[p] * b[q];
      }
    });
    const auto x = solve_dense(m, rhs);
    out.least_squares = {"least_squares", x[1], x[2], x[0]};
  }
  // The deviations from `c`, computed as they are read.
  auto finish_streaming = [&](ReferenceCircle& c) {
    finish(c, n, [&](auto&& f) {
      samples.sweep([&](std::size_t, double r, double cs, double sn) {
        f(limacon_deviation(c, r, cs, sn));
      });
    });
  };
  auto circle = [&](const char* name, const ProgramSolution& sol, double a, double b,
                    double radius_) {
    if (sol.x.empty())
      throw std::invalid_argument(
          "roundness: the samples do not surround the centre (they must cover the whole turn)");
    ReferenceCircle c{name, a, b, radius_};
    c.certified = sol.certified;
    c.duality_gap = sol.duality_gap;
    finish_streaming(c);
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
  if (deviations == Deviations::least_squares) {
    auto& d = out.least_squares_deviations;
    d.resize(n);
    samples.sweep([&](std::size_t i, double r, double cs, double sn) {
      d[i] = limacon_deviation(out.least_squares, r, cs, sn);
    });
    finish(out.least_squares, n, [&](auto&& f) {
      for (double v : d) f(v);
    });
  } else {
    finish_streaming(out.least_squares);
  }
  out.least_squares.radius += mean;
  return out;
}

}  // namespace

}  // namespace chatterlab::surface
