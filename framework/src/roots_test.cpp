// The root solver on characteristic functions whose zeros are known exactly (products of
// polynomial factors and delay lattices 1 - rho e^{-T s}, zeros (ln rho + 2 pi j m)/T), its
// certificate (counts in arbitrary rectangles, a deliberately missed root), failure behaviour,
// thread safety and determinism. Model plugins have their own known-answer tests.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "chatterlab/errors.hpp"
#include "chatterlab/roots.hpp"
#include "roots/contour.hpp"

namespace chatterlab {
namespace {

using roots_detail::Box;
using roots_detail::ContourSettings;
using roots_detail::ContourTracker;
using roots_detail::Evaluator;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// E(s) = prod_k (s - r_k)(s - conj r_k) [one factor for real r_k] * prod_l (1 - rho_l e^{-T_l s}).
class KnownZeros final : public CharacteristicFunction {
 public:
  struct Lattice {
    double rho, period_s;
    double real_part() const { return std::log(rho) / period_s; }
  };

  KnownZeros(std::vector<Complex> roots, std::vector<Lattice> lattices = {})
      : roots_(std::move(roots)), lattices_(std::move(lattices)) {}

  CharacteristicValue evaluate(Complex s) const override {
    Complex value = 1.0, log_derivative = 0.0;
    for (Complex r : roots_) {
      value *= s - r;
      log_derivative += 1.0 / (s - r);
      if (r.imag() != 0.0) {
        value *= s - std::conj(r);
        log_derivative += 1.0 / (s - std::conj(r));
      }
    }
    for (const Lattice& l : lattices_) {
      Complex e = l.rho * std::exp(-l.period_s * s), factor = 1.0 - e;
      value *= factor;
      log_derivative += l.period_s * e / factor;
    }
    return {value, value * log_derivative};
  }
  std::vector<Complex> neutral_roots(double) const override { return neutral_; }
  void initial_guesses(double band, std::vector<Complex>& guesses) const override {
    for (Complex r : roots_)
      if (r != withheld_) guesses.push_back(r + Complex(0.01, -0.02));
    for (const Lattice& l : lattices_)
      for (double y = 0.0; y <= band + kTwoPi / l.period_s; y += kTwoPi / l.period_s)
        guesses.emplace_back(0.0, y);
  }
  double real_part_bound() const override {
    double bound = 1.0;
    for (Complex r : roots_) bound = std::max(bound, r.real() + 1.0);
    return bound;
  }
  double natural_frequency_scale_hz() const override { return 1.0; }

  // Exact number of zeros (conjugates included) strictly inside a rectangle (mirrored when the
  // box is symmetric).
  int zeros_in(const Box& box) const {
    const double im_low = box.symmetric() ? -box.im_max : box.im_min;
    auto inside = [&](Complex z) {
      return z.real() > box.re_min && z.real() < box.re_max && z.imag() > im_low && z.imag() < box.im_max;
    };
    int n = 0;
    for (Complex r : roots_) {
      n += inside(r);
      if (r.imag() != 0.0) n += inside(std::conj(r));
    }
    for (const Lattice& l : lattices_) {
      if (!(l.real_part() > box.re_min && l.real_part() < box.re_max)) continue;
      const double spacing = kTwoPi / l.period_s;  // zeros at Im = m * spacing, all integers m
      n += static_cast<int>(std::ceil(box.im_max / spacing) - std::floor(im_low / spacing)) - 1;
    }
    return n;
  }

  std::vector<Complex> neutral_;
  Complex withheld_ = Complex(std::nan(""), 0.0);

 private:
  std::vector<Complex> roots_;
  std::vector<Lattice> lattices_;
};

RightmostRoot search(const CharacteristicFunction& e, double band_hz = 1.0, int repair_rounds = 3) {
  RootSearchOptions options;
  options.max_frequency_hz = band_hz;
  options.max_repair_rounds = repair_rounds;
  return find_rightmost_root(e, options);
}

TEST(Roots, RightmostRootOfAPolynomialIsFoundAndCertified) {
  KnownZeros e({{-1.0, 0.0}, {-0.5, 2.0}, {-0.2, 5.0}, {0.3, 1.0}, {-0.05, 3.0}});
  RightmostRoot found = search(e);
  EXPECT_LE(std::abs(found.root - Complex(0.3, 1.0)), 1e-13);
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_GT(found.certified_real_part, 0.3);
  EXPECT_LT(found.certified_real_part, 0.3 + 1e-3);
  EXPECT_EQ(found.zeros_right_of_contour, 0);
  EXPECT_GE(found.roots_found, 1);  // roots that cannot be the rightmost need not be polished
  EXPECT_EQ(found.certificate.substr(0, 3), "ok:");
}

TEST(Roots, OnlyTheBandCountsAndRealRootsAreReal) {
  // 0.5 + 10i lies beyond |Im s| <= 2 pi * 1 Hz: the rightmost root in the band is the real one.
  KnownZeros e({{0.5, 10.0}, {-0.1, 1.0}, {0.05, 0.0}});
  RightmostRoot found = search(e);
  EXPECT_EQ(found.root, Complex(0.05, 0.0));
  EXPECT_TRUE(found.certified) << found.certificate;
}

TEST(Roots, NeutralRootsAreExcludedAndCountedOut) {
  KnownZeros e({{0.0, 0.0}, {-0.2, 1.0}, {-0.7, 3.0}});
  e.neutral_ = {Complex(0.0, 0.0)};  // like s = 0 of G1
  RightmostRoot found = search(e);
  EXPECT_LE(std::abs(found.root - Complex(-0.2, 1.0)), 1e-13);
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_LT(found.certified_real_part, 0.0);  // the contour encloses s = 0 and subtracts it
  EXPECT_GE(found.neutral_roots_excluded, 1);
}

TEST(Roots, CertificateFailsWhenTheRightmostRootIsMissedAndRepairFindsIt) {
  KnownZeros e({{-0.3, 1.0}, {0.2, 4.0}, {-0.1, 2.0}});
  e.withheld_ = Complex(0.2, 4.0);  // no guess near the rightmost root
  RightmostRoot missed = search(e, 1.0, 0);
  EXPECT_LE(std::abs(missed.root - Complex(-0.1, 2.0)), 1e-12);
  EXPECT_FALSE(missed.certified);
  EXPECT_EQ(missed.zeros_right_of_contour, 2);  // the withheld pair
  RightmostRoot repaired = search(e, 1.0, 3);
  EXPECT_LE(std::abs(repaired.root - Complex(0.2, 4.0)), 1e-12);
  EXPECT_TRUE(repaired.certified) << repaired.certificate;
  // The pair is located from the count's first two moments (a root outside the box may be met
  // on the way); the same count, now fully known, certifies it: no second contour.
  EXPECT_GE(repaired.repaired_roots, 1);
  EXPECT_NE(repaired.certificate.find("located by the repair"), std::string::npos) << repaired.certificate;
  EXPECT_LT(repaired.function_evaluations, missed.function_evaluations + 60) << repaired.certificate;
}

// The contour's moments: the sums of the zeros and of their squares inside a box (the estimates
// the repair starts Newton from), on a box holding a conjugate pair and a real zero.
TEST(Roots, ContourMomentsEstimateTheZerosInside) {
  KnownZeros e({{0.2, 4.0}, {0.5, 0.0}, {-0.3, 1.0}});
  Evaluator evaluate(e, 1'000'000);
  ContourTracker tracker(evaluate, ContourSettings{});
  const Box box{0.0, 2.0, 0.0, 6.0};  // mirrored: 0.2 +- 4i and 0.5 inside
  const auto count = tracker.count(box);
  ASSERT_TRUE(count.ok);
  EXPECT_EQ(count.zeros, 3);
  const Complex sum = 0.2 * 2.0 + 0.5, squares = 2.0 * (0.04 - 16.0) + 0.25;
  EXPECT_LT(std::abs(count.root_sum - sum), 0.05 * std::abs(sum)) << count.root_sum;
  EXPECT_LT(std::abs(count.root_square_sum - squares), 0.05 * std::abs(squares)) << count.root_square_sum;
}

TEST(Roots, LatticeHuggingTheAxisIsCertified) {
  // A work-like chain (Tw = 1.09 s, roots 9e-4 /s left of the axis, 1150 of them in 1 kHz), a
  // wheel-like chain and a structural pair that is the rightmost root.
  KnownZeros e({{-4e-4, 2000.0}}, {{0.999, 60.0 / 55.0}, {0.98, 60.0 / 1450.0}});
  RightmostRoot found = search(e, 1000.0);
  EXPECT_LE(std::abs(found.root - Complex(-4e-4, 2000.0)), 1e-9 * 2000.0);
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_LT(found.certified_real_part, 0.0);
  EXPECT_GT(found.certified_real_part, -4e-4);
}

// Counts of the adaptive contour against exact counts, on rectangles whose left edge passes a
// dense lattice at distances from 1e-7 to 1 /s.
TEST(Roots, ContourCountsMatchExactCountsOnRandomRectangles) {
  KnownZeros e({{-0.3, 700.0}, {-2e-3, 2500.0}, {0.4, 0.0}},
               {{0.999, 60.0 / 55.0}, {0.995, 60.0 / 1450.0}, {0.9, 0.9}});
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double lattice_re = std::log(0.999) * 55.0 / 60.0;
  for (int trial = 0; trial < 40; ++trial) {
    const double offset = std::pow(10.0, -7.0 + 7.0 * unit(random)) * (unit(random) < 0.5 ? -1.0 : 1.0);
    const double top = 100.0 + 3000.0 * unit(random);
    Box box{lattice_re + offset, 2.0, trial % 2 ? 0.0 : 3000.0 * unit(random) * 0.3, top};
    if (box.im_min >= box.im_max) continue;
    Evaluator evaluate(e, 10'000'000);
    ContourTracker tracker(evaluate, ContourSettings{});
    auto count = tracker.count(box);
    ASSERT_TRUE(count.ok) << "trial " << trial;
    EXPECT_EQ(count.zeros, e.zeros_in(box)) << "trial " << trial << " left edge offset " << offset;
  }
}

// A non-product function of the G1 type (two delay chains coupled through a structural mode):
// production contour settings against very conservative ones on random rectangles.
class CoupledChains final : public CharacteristicFunction {
 public:
  CharacteristicValue evaluate(Complex s) const override {
    const double w = 1200.0, zeta = 0.03, tg = 60.0 / 1450.0, tw = 60.0 / 55.0;
    Complex p = s * s / (w * w) + 2.0 * zeta * s / w + 1.0, dp = 2.0 * s / (w * w) + 2.0 * zeta / w;
    Complex eg = std::exp(-tg * s), ew = std::exp(-tw * s), a = 1.0 - eg, b = 1.0 - ew;
    Complex da = tg * eg, db = tw * ew;
    // E = P A B (1 + alpha + ...) + A B kappa + alpha B P + beta A P  (G1 with one mode)
    const double alpha = 0.002, beta = 0.6, kappa = 1.5;
    Complex value = p * (a * b + alpha * b + beta * a) + kappa * a * b;
    Complex derivative = dp * (a * b + alpha * b + beta * a) + p * (da * b + a * db + alpha * db + beta * da) +
                         kappa * (da * b + a * db);
    return {value, derivative};
  }
  void initial_guesses(double, std::vector<Complex>&) const override {}
  double real_part_bound() const override { return 2000.0; }
  double natural_frequency_scale_hz() const override { return 1200.0 / kTwoPi; }
};

TEST(Roots, ContourCountsAgreeWithConservativeSettings) {
  CoupledChains e;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ContourSettings conservative{0.15, 0.5, 0.02, 1.0, 0.5};
  for (int trial = 0; trial < 12; ++trial) {
    Box box{-0.05 + 0.1 * unit(random), 2000.0, trial % 2 ? 0.0 : 1000.0 * unit(random), 1500.0 + 1500.0 * unit(random)};
    Evaluator fast_evaluate(e, 50'000'000), safe_evaluate(e, 50'000'000);
    ContourTracker fast(fast_evaluate, ContourSettings{}), safe(safe_evaluate, conservative);
    auto fast_count = fast.count(box), safe_count = safe.count(box);
    ASSERT_TRUE(fast_count.ok && safe_count.ok) << "trial " << trial;
    EXPECT_EQ(fast_count.zeros, safe_count.zeros) << "trial " << trial;
    EXPECT_LT(fast_evaluate.count(), safe_evaluate.count());
  }
}

// A warm start from a neighbouring parameter set's roots: the same certified root with fewer
// evaluations; from useless guesses, the search falls back to the model's own and still finds it.
TEST(Roots, WarmStartGivesTheSameCertifiedRoot) {
  KnownZeros near({{-4e-4, 2000.0}}, {{0.999, 60.0 / 55.0}, {0.98, 60.0 / 1450.0}});
  // As neighbouring feed_risk groups: the same speeds (delays), slightly different process
  // stiffnesses (lattice depths) and structural root.
  KnownZeros e({{-3e-4, 2001.0}}, {{0.9985, 60.0 / 55.0}, {0.981, 60.0 / 1450.0}});
  RootSearchOptions options;
  options.max_frequency_hz = 1000.0;
  options.keep_approximate_roots = true;
  const RightmostRoot neighbour = find_rightmost_root(near, options);
  ASSERT_TRUE(neighbour.certified);
  ASSERT_GT(neighbour.approximate_roots.size(), 1000u);
  const RightmostRoot cold = find_rightmost_root(e, options);
  options.warm_start = &neighbour.approximate_roots;
  const RightmostRoot warm = find_rightmost_root(e, options);
  ASSERT_TRUE(cold.certified && warm.certified) << warm.certificate;
  EXPECT_TRUE(warm.warm_started);
  EXPECT_LE(std::abs(warm.root - cold.root), 1e-12 * std::abs(cold.root));
  EXPECT_LE(std::abs(warm.root - Complex(-3e-4, 2001.0)), 1e-9 * 2001.0);
  EXPECT_LT(warm.function_evaluations, cold.function_evaluations);
  const std::vector<Complex> useless = {Complex(-50.0, 10.0)};
  options.warm_start = &useless;
  options.max_repair_rounds = 0;  // no repair of the warm search: its certificate fails
  const RightmostRoot fallback = find_rightmost_root(e, options);
  EXPECT_TRUE(fallback.certified) << fallback.certificate;
  EXPECT_FALSE(fallback.warm_started);
  EXPECT_LE(std::abs(fallback.root - cold.root), 1e-12 * std::abs(cold.root));
}

// ---------------------------------------------------------------- failures and threads

class Throwing final : public CharacteristicFunction {
 public:
  explicit Throwing(std::function<CharacteristicValue(Complex)> f) : f_(std::move(f)) {}
  CharacteristicValue evaluate(Complex s) const override { return f_(s); }
  void initial_guesses(double, std::vector<Complex>& guesses) const override { guesses = {{0.0, 1.0}}; }
  double real_part_bound() const override { return 1.0; }
  double natural_frequency_scale_hz() const override { return 1.0; }

 private:
  std::function<CharacteristicValue(Complex)> f_;
};

std::string point_failure_of(const CharacteristicFunction& e, double band_hz) {
  try {
    search(e, band_hz);
  } catch (const PointFailure& failure) {
    return failure.what();
  }
  return "(no PointFailure)";
}

TEST(Roots, OnlyPointFailureLeavesTheSolver) {
  Throwing throws([](Complex) -> CharacteristicValue { throw std::runtime_error("model blew up"); });
  EXPECT_EQ(point_failure_of(throws, 1.0), "root search failed: model blew up");
  Throwing nan([](Complex) { return CharacteristicValue{Complex(std::nan(""), 0.0), 1.0}; });
  EXPECT_NE(point_failure_of(nan, 1.0).find("no characteristic root found"), std::string::npos);
  KnownZeros fine(std::vector<Complex>{{-0.1, 1.0}});
  EXPECT_NE(point_failure_of(fine, 0.0).find("max_frequency_hz = 0"), std::string::npos);
  EXPECT_NE(point_failure_of(fine, std::nan("")).find("must be finite and > 0"), std::string::npos);
}

TEST(Roots, ExhaustedBudgetIsUncertifiedOrAFailure) {
  KnownZeros e({{-0.3, 1.0}, {0.2, 4.0}}, {{0.99, 10.0}});
  RootSearchOptions options;
  options.max_frequency_hz = 1.0;
  options.max_function_evaluations = 40;  // Newton finds roots, the contour runs out
  RightmostRoot found = find_rightmost_root(e, options);
  EXPECT_FALSE(found.certified);
  EXPECT_NE(found.certificate.find("budget"), std::string::npos) << found.certificate;
  options.max_function_evaluations = 1;
  EXPECT_THROW(find_rightmost_root(e, options), PointFailure);
}

TEST(Roots, ConcurrentSearchesAreIdenticalToASerialOne) {
  KnownZeros e({{-4e-4, 2000.0}, {-0.2, 300.0}}, {{0.999, 60.0 / 55.0}, {0.98, 60.0 / 1450.0}});
  RightmostRoot serial = search(e, 500.0);
  std::vector<RightmostRoot> results(4);
  std::vector<std::thread> threads;
  for (auto& r : results) threads.emplace_back([&e, &r] { r = search(e, 500.0); });
  for (auto& t : threads) t.join();
  for (const RightmostRoot& r : results) {
    EXPECT_EQ(r.root, serial.root);  // bit for bit
    EXPECT_EQ(r.certified_real_part, serial.certified_real_part);
    EXPECT_EQ(r.function_evaluations, serial.function_evaluations);
    EXPECT_EQ(r.certificate, serial.certificate);
  }
}

}  // namespace
}  // namespace chatterlab
