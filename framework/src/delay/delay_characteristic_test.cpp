// Known answers for DelayCharacteristic (chatterlab/delay_system.hpp). References are computed in
// this file by independent routes: scalar quasi-polynomials in long double, Lambert W, the
// factored G1 quasi-polynomial of MODELS.md eq 2-16 written out by hand, and finite differences.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include <Eigen/Dense>

#include "chatterlab/delay_system.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/roots.hpp"
#include "unit/root_test_support.hpp"

namespace chatterlab {
namespace {

using Eigen::MatrixXd;
using LongComplex = std::complex<long double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

using testing::brute_force_rightmost;
using testing::long_double_newton;
using testing::ScalarFunction;

RightmostRoot rightmost(const CharacteristicFunction& e, double band_hz) {
  RootSearchOptions options;
  options.max_frequency_hz = band_hz;
  return find_rightmost_root(e, options);
}

void expect_close(Complex actual, LongComplex reference, double relative, const std::string& what) {
  const Complex ref(static_cast<double>(reference.real()), static_cast<double>(reference.imag()));
  EXPECT_LE(std::abs(actual - ref), relative * std::abs(ref)) << what << ": got " << actual << ", reference " << ref;
}

MatrixXd matrix(std::initializer_list<std::initializer_list<double>> rows) {
  MatrixXd m(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(rows.begin()->size()));
  Eigen::Index i = 0;
  for (const auto& row : rows) {
    Eigen::Index j = 0;
    for (double v : row) m(i, j++) = v;
    ++i;
  }
  return m;
}

// ---------------------------------------------------------------- retarded systems

TEST(DelayCharacteristic, RetardedOscillatorMatchesTheLongDoubleRoot) {
  // x'' + 0.1 x' + 1.3 x = 0.3 x(t - 10) (the linear_dde example): s^2 + 0.1 s + 1.3 - 0.3 e^{-10 s}.
  const ScalarFunction f = [](LongComplex s) {
    const LongComplex e = std::exp(-10.0L * s);
    return std::make_pair(s * s + 0.1L * s + 1.3L - 0.3L * e, 2.0L * s + 0.1L + 3.0L * e);
  };
  const auto reference = long_double_newton(f, LongComplex(0.0386, 1.122));
  ASSERT_TRUE(reference);
  LinearDelaySystem system{MatrixXd(), matrix({{0.0, 1.0}, {-1.3, -0.1}}), {{10.0, matrix({{0.0, 0.0}, {0.3, 0.0}}), {}}}};
  DelayCharacteristic e(system);
  const RightmostRoot found = rightmost(e, 1.0);
  expect_close(found.root, *reference, 1e-12, "oscillator");
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_FALSE(e.summary().neutral);
  EXPECT_GE(e.real_part_bound(), found.root.real());
  // Retarded: every root right of the contour is inside a proven disc; with a 1 Hz band it is covered.
  EXPECT_NE(found.certificate.find("global: every root with Re s >= "), std::string::npos) << found.certificate;
}

TEST(DelayCharacteristic, ScalarDelayEquationsMatchBruteForce) {
  struct Case {
    double a, b, tau;
  };
  for (Case c : {Case{-0.5, -1.0, 2.0}, Case{0.2, -1.5, 1.0}, Case{-1.0, 0.5, 3.0}}) {
    const ScalarFunction f = [c](LongComplex s) {
      const LongComplex e = std::exp(-static_cast<long double>(c.tau) * s);
      return std::make_pair(s - static_cast<long double>(c.a) - static_cast<long double>(c.b) * e,
                            1.0L + static_cast<long double>(c.b * c.tau) * e);
    };
    const LongComplex reference = brute_force_rightmost(f, kTwoPi * 2.0, -3.0, 1.0, 0.1);
    DelayCharacteristic e(LinearDelaySystem{MatrixXd(), matrix({{c.a}}), {{c.tau, matrix({{c.b}}), {}}}});
    const RightmostRoot found = rightmost(e, 2.0);
    expect_close(found.root, reference, 1e-10, "x' = a x + b x(t - tau), a = " + std::to_string(c.a));
    EXPECT_TRUE(found.certified) << found.certificate;
  }
}

TEST(DelayCharacteristic, WithoutDelaysTheBoundIsTheLogarithmicNormAndTheRootsTheEigenvalues) {
  // (s + 1)(s^2 + 0.2 s + 4) as a companion matrix: rightmost -0.1 +- i sqrt(3.99).
  DelayCharacteristic e(LinearDelaySystem{MatrixXd(), matrix({{0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {-4.0, -4.2, -1.2}}), {}});
  const RightmostRoot found = rightmost(e, 1.0);
  expect_close(found.root, LongComplex(-0.1L, std::sqrt(3.99L)), 1e-12, "ODE");
  EXPECT_TRUE(found.certified);
  // In the modal inner product the logarithmic norm is the largest real part itself.
  EXPECT_GE(e.real_part_bound(), -0.1);
  EXPECT_LT(e.real_part_bound(), -0.1 + 1e-6);
}

// ---------------------------------------------------------------- G1 as a delay-differential-algebraic system

struct G1 {
  double kc = 1e8, kg = 5e9, kw = 5e7, tg = 60.0 / 1450.0, tw = 60.0 / 55.0;
  std::vector<std::array<double, 3>> modes = {{184.08, 0.05, 5e7}, {305.6, 0.04, 8e7}};  // f, zeta, k
  bool wheel = true, work = true;

  // MODELS.md G1 time domain: modal coordinates q_i (x = sum q_i),
  //   q_i'' + 2 zeta_i w_i q_i' + w_i^2 q_i = (w_i^2 / k_i) F,
  //   0 = -Wg + Wg(t - Tg) + F/kg,   0 = -Ww + Ww(t - Tw) + F/kw,   0 = -Wg - Ww - F/kc - sum q_i.
  // Variables: q1, v1, q2, v2, ..., Wg, Ww, F. A switched-off chain keeps its variable with no
  // delay and no compliance (W = W: its equation becomes W = 0).
  LinearDelaySystem system() const {
    const auto m = static_cast<Eigen::Index>(modes.size());
    const Eigen::Index n = 2 * m + 3, wg = 2 * m, ww = wg + 1, f = ww + 1;
    MatrixXd e = MatrixXd::Zero(n, n), a0 = MatrixXd::Zero(n, n), ag = MatrixXd::Zero(n, n), aw = MatrixXd::Zero(n, n);
    for (Eigen::Index i = 0; i < m; ++i) {
      const double w = kTwoPi * modes[static_cast<std::size_t>(i)][0], zeta = modes[static_cast<std::size_t>(i)][1],
                   k = modes[static_cast<std::size_t>(i)][2];
      e(2 * i, 2 * i) = e(2 * i + 1, 2 * i + 1) = 1.0;
      a0(2 * i, 2 * i + 1) = 1.0;
      a0(2 * i + 1, 2 * i) = -w * w;
      a0(2 * i + 1, 2 * i + 1) = -2.0 * zeta * w;
      a0(2 * i + 1, f) = w * w / k;
      a0(f, 2 * i) = -1.0;
    }
    a0(wg, wg) = -1.0;
    a0(ww, ww) = -1.0;
    if (wheel) {
      ag(wg, wg) = 1.0;
      a0(wg, f) = 1.0 / kg;
    }
    if (work) {
      aw(ww, ww) = 1.0;
      a0(ww, f) = 1.0 / kw;
    }
    a0(f, wg) = a0(f, ww) = -1.0;
    a0(f, f) = -1.0 / kc;
    LinearDelaySystem s{e, a0, {}};
    if (wheel) s.delayed.push_back({tg, ag, {}});
    if (work) s.delayed.push_back({tw, aw, {}});
    return s;
  }

  // Eq 2-16 multiplied out: E = prod P_i (A B + alpha B + beta A) + A B sum_i (kc/k_i) prod_{j != i} P_j,
  // A = 1 - e^{-Tg s}, B = 1 - e^{-Tw s}, alpha = kc/kg, beta = kc/kw, P = s^2/w^2 + 2 zeta s/w + 1.
  LongComplex closed_form(LongComplex s) const {
    const LongComplex a = wheel ? 1.0L - std::exp(-static_cast<long double>(tg) * s) : 1.0L;
    const LongComplex b = work ? 1.0L - std::exp(-static_cast<long double>(tw) * s) : 1.0L;
    const long double alpha = wheel ? kc / kg : 0.0L, beta = work ? kc / kw : 0.0L;
    LongComplex product = 1.0L, coupled = 0.0L;
    for (const auto& mode : modes) {
      const long double w = static_cast<long double>(kTwoPi * mode[0]);
      const LongComplex p = s * s / (w * w) + 2.0L * static_cast<long double>(mode[1]) * s / w + 1.0L;
      coupled = coupled * p + static_cast<long double>(kc / mode[2]) * product;
      product *= p;
    }
    return product * (a * b + alpha * b + beta * a) + a * b * coupled;
  }
};

TEST(DelayCharacteristic, G1AsAlgebraicSurfacesIsTheFactoredQuasiPolynomialOfEq2_16) {
  const G1 g1;
  DelayCharacteristic e(g1.system());
  const DelaySystemSummary& summary = e.summary();
  EXPECT_EQ(summary.states, 7u);
  EXPECT_EQ(summary.differential, 4u);
  EXPECT_EQ(summary.condensed, 1u);  // the contact force
  EXPECT_TRUE(summary.neutral);
  EXPECT_NE(summary.evaluation.find("modal Schur"), std::string::npos) << summary.evaluation;
  // det Delta / E is a nonzero constant: both are entire with the same zeros.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> re(-30.0, 20.0), im(0.0, 8000.0);
  std::optional<LongComplex> ratio;
  for (int i = 0; i < 40; ++i) {
    const Complex s(re(rng), im(rng));
    const LongComplex value = LongComplex(e.evaluate(s).value) / g1.closed_form(LongComplex(s));
    if (!ratio) ratio = value;
    EXPECT_LE(std::abs(value / *ratio - 1.0L), 1e-9L) << "s = " << s;
  }
  // The cumulative-removal family (Wg = -Ww, F = 0) is the excluded root s = 0, and it repeats on
  // the common lattice of both delays; the difference operator's spectrum reaches Re s = 0.
  EXPECT_EQ(summary.family_roots_at_zero, 1);
  EXPECT_EQ(summary.family_lattice_delays_s.size(), 2u);
  EXPECT_NEAR(summary.difference_spectrum_lower, 0.0, 1e-9);
}

TEST(DelayCharacteristic, G1ModalAndDenseEvaluationsAgree) {
  G1 g1;
  g1.modes = {{67.56, 0.05, 3e7}, {102.44, 0.04, 6e7}, {184.08, 0.05, 5e7}, {305.6, 0.03, 8e7}};
  DelayCharacteristic e(g1.system());
  ASSERT_NE(e.summary().evaluation.find("modal"), std::string::npos);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> re(-50.0, 50.0), im(0.0, 10000.0);
  std::optional<Complex> ratio;
  for (int i = 0; i < 50; ++i) {
    const Complex s(re(rng), im(rng));
    const CharacteristicValue modal = e.evaluate(s), dense = e.evaluate_dense(s);
    if (!ratio) ratio = modal.value / dense.value;
    EXPECT_LE(std::abs(modal.value / dense.value / *ratio - 1.0), 1e-9) << s;
    // Logarithmic derivatives are independent of the constant.
    const Complex log_modal = modal.derivative / modal.value, log_dense = dense.derivative / dense.value;
    EXPECT_LE(std::abs(log_modal - log_dense), 1e-8 * std::max(1.0, std::abs(log_dense))) << s;
  }
}

TEST(DelayCharacteristic, DerivativeMatchesFiniteDifferences) {
  const G1 g1;
  DelayCharacteristic g(g1.system());
  LinearDelaySystem three{MatrixXd(), matrix({{-0.3, 1.0, 0.2}, {-1.0, -0.1, 0.0}, {0.4, 0.0, -2.0}}),
                          {{3.0, matrix({{0.0, 0.1, 0.0}, {0.5, 0.0, 0.0}, {0.0, 0.0, 0.3}}), {}},
                           {1.7, matrix({{0.2, 0.0, 0.0}, {0.0, 0.0, 0.1}, {0.0, 0.3, 0.0}}), matrix({{0.1, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.2}})}}};
  DelayCharacteristic d(three);
  for (const DelayCharacteristic* e : {&g, &d}) {
    for (Complex s : {Complex(0.1, 0.7), Complex(-0.4, 2.3), Complex(1.0, 0.0), Complex(-2.0, 1200.0)}) {
      const double h = 1e-7 * std::max(1.0, std::abs(s));  // truncation (tau h)^2 / 6 < 1e-8
      const Complex numeric = (e->evaluate(s + h).value - e->evaluate(s - h).value) / (2.0 * h);
      const Complex analytic = e->evaluate(s).derivative;
      EXPECT_LE(std::abs(numeric - analytic), 1e-6 * std::abs(analytic)) << s;
    }
  }
}

TEST(DelayCharacteristic, G1RootsAreRootsOfEq2_16AndCertified) {
  for (double kc : {2e7, 1e8, 3e8}) {
    G1 g1;
    g1.kc = kc;
    g1.tw = 60.0 / 300.0;  // a short work period keeps the band's root count small for this test
    DelayCharacteristic e(g1.system());
    const RightmostRoot found = rightmost(e, 1300.0);
    EXPECT_TRUE(found.certified) << found.certificate;
    // The derived root is a zero of the hand-written quasi-polynomial (polished in long double).
    const ScalarFunction f = [&](LongComplex s) {
      const long double h = 1e-7L * std::max(1.0L, std::abs(s));
      return std::make_pair(g1.closed_form(s), (g1.closed_form(s + h) - g1.closed_form(s - h)) / (2.0L * h));
    };
    const auto polished = long_double_newton(f, LongComplex(found.root));
    ASSERT_TRUE(polished);
    expect_close(found.root, *polished, 1e-12, "G1 kc = " + std::to_string(kc));
    EXPECT_NE(found.certificate.find("neutral type"), std::string::npos) << found.certificate;
  }
}

// ---------------------------------------------------------------- neutral DDE

TEST(DelayCharacteristic, NeutralScalarEquationAndItsEssentialSpectrum) {
  // x'(t) - b x'(t - tau) = a x(t): s (1 - b e^{-tau s}) = a. The chains approach
  // Re s = ln|b| / tau as |Im s| grows.
  struct Case {
    double a, b, tau;
  };
  for (Case c : {Case{-1.0, 0.5, 1.0}, Case{-0.2, -0.9, 2.0}, Case{0.3, 0.4, 1.5}}) {
    const ScalarFunction f = [c](LongComplex s) {
      const long double tau = c.tau, b = c.b;
      const LongComplex e = std::exp(-tau * s);
      return std::make_pair(s * (1.0L - b * e) - static_cast<long double>(c.a), 1.0L - b * e + b * tau * s * e);
    };
    const double band_hz = 3.0;
    const LongComplex reference = brute_force_rightmost(f, kTwoPi * band_hz, -1.5, 1.0, 0.1);
    DelayCharacteristic e(LinearDelaySystem{MatrixXd(), matrix({{c.a}}), {{c.tau, MatrixXd(), matrix({{c.b}})}}});
    EXPECT_TRUE(e.summary().neutral);
    EXPECT_NEAR(e.summary().difference_spectrum_upper, std::log(std::abs(c.b)) / c.tau, 1e-12);
    EXPECT_EQ(e.summary().difference_spectrum_lower, e.summary().difference_spectrum_upper);
    const RightmostRoot found = rightmost(e, band_hz);
    expect_close(found.root, reference, 1e-10, "neutral a = " + std::to_string(c.a));
    EXPECT_TRUE(found.certified) << found.certificate;
    EXPECT_GE(e.real_part_bound(), found.root.real());
    EXPECT_NE(found.certificate.find("difference operator's spectrum (sup Re s = "), std::string::npos)
        << found.certificate;
  }
}

// ---------------------------------------------------------------- the bound, randomized

TEST(DelayCharacteristic, ProvenBoundLiesRightOfEveryRootFound) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> entry(-1.5, 1.5), delay(0.3, 4.0);
  int checked = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::Index n = 2 + trial % 3;
    LinearDelaySystem s{MatrixXd(), MatrixXd::NullaryExpr(n, n, [&] { return entry(rng); }), {}};
    for (int k = 0; k < 1 + trial % 2; ++k)
      s.delayed.push_back({delay(rng), MatrixXd::NullaryExpr(n, n, [&] { return 0.5 * entry(rng); }), {}});
    DelayCharacteristic e(s);
    const RightmostRoot found = rightmost(e, 2.0);
    EXPECT_GE(e.real_part_bound(), found.root.real()) << "trial " << trial;
    // No zero of det Delta on a grid right of the bound (a sample of the half plane it excludes).
    for (double x = 0.0; x < 3.0; x += 0.5)
      for (double y = 0.0; y < 20.0; y += 0.7)
        EXPECT_GT(std::abs(e.matrix(Complex(e.real_part_bound() + x, y)).determinant()), 0.0);
    checked += found.certified ? 1 : 0;
  }
  EXPECT_GE(checked, 28);
}

// ---------------------------------------------------------------- bad input

std::string construction_error(const LinearDelaySystem& s) {
  try {
    DelayCharacteristic e(s);
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(DelayCharacteristic, BadSystemsAreRefusedWithTheReason) {
  EXPECT_EQ(construction_error(LinearDelaySystem{MatrixXd(), matrix({{0.0, 1.0}}), {}}),
            "delay system: A_0 is 1x2: must be square and non-empty");
  EXPECT_EQ(construction_error(LinearDelaySystem{MatrixXd(), matrix({{-1.0}}), {{0.0, matrix({{0.5}}), {}}}}),
            "delay system: delayed term 0: tau = 0 must be finite and > 0");
  EXPECT_EQ(construction_error(LinearDelaySystem{MatrixXd(), matrix({{-1.0}}), {{1.0, matrix({{0.5, 0.0}, {0.0, 1.0}}), {}}}}),
            "delay system: delayed term 0: A_k is 2x2 but A_0 is 1x1: every matrix must be n x n");
  // Index 2: the algebraic variable y appears in no algebraic equation (0 = x).
  EXPECT_NE(construction_error(LinearDelaySystem{matrix({{1.0, 0.0}, {0.0, 0.0}}), matrix({{0.0, 1.0}, {1.0, 0.0}}), {}})
                .find("the algebraic equations do not determine the algebraic variables"),
            std::string::npos);
  // A neutral term on an algebraic variable.
  EXPECT_NE(construction_error(LinearDelaySystem{matrix({{1.0, 0.0}, {0.0, 0.0}}), matrix({{-1.0, 1.0}, {1.0, -1.0}}),
                                                 {{1.0, MatrixXd(), matrix({{0.0, 0.3}, {0.0, 0.0}})}}})
                .find("the neutral term B_k acts on algebraic variables"),
            std::string::npos);
}

}  // namespace
}  // namespace chatterlab
