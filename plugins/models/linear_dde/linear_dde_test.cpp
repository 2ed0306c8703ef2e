// Known answers for linear_dde and the root solver: every reference below is computed in this
// file by an independent route (scalar quasi-polynomials in long double, Lambert W by Halley's
// iteration, closed-form eigenvalues), sharing no code with the solver or the plugin.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/delay_system.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/roots.hpp"
#include "models/linear_dde/linear_dde.hpp"
#include "unit/root_test_support.hpp"

namespace chatterlab {
namespace {

using LongComplex = std::complex<long double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// ---------------------------------------------------------------- independent references

// Scalar quasi-polynomials f(s), f'(s) in long double and their brute-force roots.
using testing::brute_force_rightmost;
using testing::long_double_newton;
using testing::ScalarFunction;

// x'' + 2 zeta x' + x = -sum_k K_k (x - x(t - tau_k)): f(s) = s^2 + 2 zeta s + 1 + sum K_k
// - sum K_k e^{-tau_k s}.
ScalarFunction oscillator(long double zeta, std::vector<std::pair<long double, long double>> gain_delay) {
  return [=](LongComplex s) {
    LongComplex value = s * s + 2.0L * zeta * s + 1.0L, derivative = 2.0L * s + 2.0L * zeta;
    for (auto [gain, delay] : gain_delay) {
      LongComplex e = std::exp(-delay * s);
      value += gain - gain * e;
      derivative += gain * delay * e;
    }
    return std::make_pair(value, derivative);
  };
}

// Principal branch of Lambert W (w e^w = z) by Halley's iteration, long double.
LongComplex lambert_w0(LongComplex z) {
  // Start: the branch-point series near z = -1/e, else log z - log log z.
  LongComplex p = std::sqrt(2.0L * (std::exp(1.0L) * z + 1.0L));
  LongComplex w = std::abs(z + std::exp(-1.0L)) < 0.3L ? -1.0L + p - p * p / 3.0L
                                                        : std::log(z) - std::log(std::log(z));
  for (int i = 0; i < 100; ++i) {
    LongComplex ew = std::exp(w), f = w * ew - z;
    LongComplex step = f / (ew * (w + 1.0L) - (w + 2.0L) * f / (2.0L * w + 2.0L));
    w -= step;
    if (std::abs(step) <= 1e-19L * std::abs(w)) break;
  }
  return w;
}

// ---------------------------------------------------------------- helpers

LinearDdeParameters oscillator_parameters(double zeta, std::vector<std::pair<double, double>> gain_delay) {
  double total_gain = 0.0;
  LinearDdeParameters p;
  for (auto [gain, delay] : gain_delay) {
    total_gain += gain;
    p.delayed.push_back({delay, {{0.0, 0.0}, {gain, 0.0}}, {}});
  }
  p.a0 = {{0.0, 1.0}, {-(1.0 + total_gain), -2.0 * zeta}};
  return p;
}

RightmostRoot rightmost(const LinearDdeParameters& p, double band_hz) {
  LinearDde model(p);
  auto characteristic = model.characteristic();
  RootSearchOptions options;
  options.max_frequency_hz = band_hz;
  return find_rightmost_root(*characteristic, options);
}

void expect_close(Complex actual, LongComplex reference, double relative, const std::string& what) {
  const double ref_re = static_cast<double>(reference.real()), ref_im = static_cast<double>(reference.imag());
  const double scale = std::hypot(ref_re, ref_im);
  EXPECT_LE(std::abs(actual - Complex(ref_re, ref_im)), relative * scale)
      << what << ": got " << actual << ", reference (" << ref_re << ", " << ref_im << ")";
}

// ---------------------------------------------------------------- known answers

// DDE-BIFTOOL-style oscillator, zeta = 0.05, K = 0.3, tau = 10 (issue: "near 0.03856 + 1.1222i").
// Pinned value from long double Newton on the scalar quasi-polynomial (recomputed below too):
constexpr double kOscillatorRe = 0.038562247054131914793, kOscillatorIm = 1.1222499565638464615;

TEST(LinearDde, OscillatorRightmostRootMatchesLongDoubleReference) {
  const ScalarFunction f = oscillator(0.05L, {{0.3L, 10.0L}});
  const double band_hz = 1.0;
  // The pinned constant is a root (to long double precision) and the rightmost one in the band.
  auto polished = long_double_newton(f, LongComplex(kOscillatorRe, kOscillatorIm));
  ASSERT_TRUE(polished);
  EXPECT_LT(std::abs(*polished - LongComplex(kOscillatorRe, kOscillatorIm)), 1e-15L);
  LongComplex brute = brute_force_rightmost(f, kTwoPi * band_hz, -0.5, 0.3);
  EXPECT_LT(std::abs(brute - *polished), 1e-12L);

  RightmostRoot found = rightmost(oscillator_parameters(0.05, {{0.3, 10.0}}), band_hz);
  expect_close(found.root, *polished, 1e-9, "oscillator");
  EXPECT_NEAR(found.root.real(), kOscillatorRe, 1e-9 * kOscillatorRe);  // the growth rate itself
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_GE(found.certified_real_part, found.root.real());
  EXPECT_EQ(found.zeros_right_of_contour, 0);
}

TEST(LinearDde, TwoDelaysMatchBruteForceLongDouble) {
  for (auto [k1, k2] : {std::pair{0.2, 0.15}, std::pair{0.05, 0.4}}) {
    const ScalarFunction f = oscillator(0.05L, {{k1, 10.0L}, {k2, 4.3L}});
    const double band_hz = 1.0;
    LongComplex reference = brute_force_rightmost(f, kTwoPi * band_hz, -0.5, 0.3);
    RightmostRoot found = rightmost(oscillator_parameters(0.05, {{k1, 10.0}, {k2, 4.3}}), band_hz);
    expect_close(found.root, reference, 1e-9, "two delays");
    EXPECT_TRUE(found.certified) << found.certificate;
  }
}

TEST(LinearDde, ScalarDelayEquationMatchesLambertW) {
  // x' = a x + b x(t - tau): s = a + W_0(b tau e^{-a tau}) / tau is the rightmost root
  // (principal branch; Shinozaki & Mori 2006).
  struct Case {
    double a, b, tau;
  };
  for (Case c : {Case{-0.5, -1.0, 2.0}, Case{0.2, -1.5, 1.0}, Case{-1.0, 0.5, 3.0}, Case{0.1, -0.3, 7.0}}) {
    LongComplex z = static_cast<long double>(c.b * c.tau) * std::exp(-static_cast<long double>(c.a * c.tau));
    LongComplex w = lambert_w0(z);
    ASSERT_LT(std::abs(w * std::exp(w) - z), 1e-15L * std::abs(z));
    ASSERT_LT(std::abs(w.imag()), std::numbers::pi);  // principal branch
    LongComplex reference = static_cast<long double>(c.a) + w / static_cast<long double>(c.tau);
    reference = LongComplex(reference.real(), std::abs(reference.imag()));

    LinearDdeParameters p;
    p.a0 = {{c.a}};
    p.delayed = {{c.tau, {{c.b}}, {}}};
    RightmostRoot found = rightmost(p, 2.0);
    expect_close(found.root, reference, 1e-9, "scalar DDE a=" + std::to_string(c.a));
    EXPECT_TRUE(found.certified) << found.certificate;
  }
}

TEST(LinearDde, WithoutDelaysTheRootsAreTheEigenvalues) {
  // Companion matrix of (s + 1)(s^2 + 0.2 s + 4) = s^3 + 1.2 s^2 + 4.2 s + 4: eigenvalues -1 and
  // -0.1 +- i sqrt(3.99). Three states: the general determinant path.
  LinearDdeParameters p;
  p.a0 = {{0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {-4.0, -4.2, -1.2}};
  RightmostRoot found = rightmost(p, 1.0);
  expect_close(found.root, LongComplex(-0.1L, std::sqrt(3.99L)), 1e-12, "ODE");
  EXPECT_TRUE(found.certified) << found.certificate;
  // Real rightmost root: a stable node and a real unstable one.
  LinearDdeParameters q;
  q.a0 = {{0.5, 0.0}, {1.0, -2.0}};
  RightmostRoot real_root = rightmost(q, 1.0);
  EXPECT_DOUBLE_EQ(real_root.root.imag(), 0.0);
  EXPECT_NEAR(real_root.root.real(), 0.5, 1e-12);
  EXPECT_TRUE(real_root.certified) << real_root.certificate;
}

TEST(LinearDde, DerivativeMatchesFiniteDifferencesForThreeStatesAndTwoDelays) {
  LinearDdeParameters p;
  p.a0 = {{-0.3, 1.0, 0.2}, {-1.0, -0.1, 0.0}, {0.4, 0.0, -2.0}};
  p.delayed = {{3.0, {{0.0, 0.1, 0.0}, {0.5, 0.0, 0.0}, {0.0, 0.0, 0.3}}, {}},
               {1.7, {{0.2, 0.0, 0.0}, {0.0, 0.0, 0.1}, {0.0, 0.3, 0.0}}, {}}};
  LinearDdeCharacteristic e(p);
  for (Complex s : {Complex(0.1, 0.7), Complex(-0.4, 2.3), Complex(1.0, 0.0)}) {
    const double h = 1e-6;
    Complex numeric = (e.evaluate(s + h).value - e.evaluate(s - h).value) / (2.0 * h);
    Complex analytic = e.evaluate(s).derivative;
    EXPECT_LE(std::abs(numeric - analytic), 1e-7 * std::max(1.0, std::abs(analytic))) << s;
  }
}

TEST(LinearDde, RealPartBoundHoldsForAnUnstableSystem) {
  // x' = 2 x + 0.5 x(t - 1): one real root right of 2; the bound must lie beyond it.
  LinearDdeParameters p;
  p.a0 = {{2.0}};
  p.delayed = {{1.0, {{0.5}}, {}}};
  LinearDdeCharacteristic e(p);
  RightmostRoot found = rightmost(p, 1.0);
  EXPECT_GT(found.root.real(), 2.0);
  EXPECT_GT(e.real_part_bound(), found.root.real());
  EXPECT_TRUE(found.certified) << found.certificate;
}

// ---------------------------------------------------------------- registration and bad input

TEST(LinearDde, RegisteredExampleRunsAndIsTheOscillator) {
  const auto& entry = model_registry().at("linear_dde");
  EXPECT_EQ(entry.info.thread_safety, ThreadSafety::shareable);
  auto model = entry.create(ParamValues(entry.info.example_params));
  auto characteristic = model->characteristic();
  ASSERT_NE(characteristic, nullptr);
  RootSearchOptions options;
  options.max_frequency_hz = 1.0;
  RightmostRoot found = find_rightmost_root(*characteristic, options);
  EXPECT_NEAR(found.root.real(), kOscillatorRe, 1e-9);
  EXPECT_NEAR(found.root.imag(), kOscillatorIm, 1e-9);
}

std::string construction_error(const Json& table) {
  try {
    LinearDde model{ParamValues(table)};
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(LinearDde, SizeMismatchesNameTheKeyAndBothSizes) {
  Json table = {{"a0", {{0.0, 1.0}, {-1.0, -0.1}}},
                {"delayed", {Json{{"delay_s", 1.0}, {"matrix", {{0.0, 0.0}, {0.1, 0.0}}}},
                             Json{{"delay_s", 2.0}, {"matrix", {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}}}}}};
  EXPECT_EQ(construction_error(table),
            "model.delayed.1.matrix is 3x3 but model.a0 is 2x2: every delayed matrix must be square "
            "with the size of a0");
  Json not_square = {{"a0", {{0.0, 1.0, 2.0}, {-1.0, -0.1, 0.0}}}, {"delayed", Json::array()}};
  EXPECT_EQ(construction_error(not_square), "model.a0 is 2x3: the state matrix A0 must be square (n x n)");
  Json delay = {{"a0", {{-1.0}}}, {"delayed", {Json{{"delay_s", 0.0}, {"matrix", {{0.1}}}}}}};
  EXPECT_EQ(construction_error(delay), "model.delayed.0.delay_s = 0: must be finite and > 0");
}

// ---------------------------------------------------------------- mass matrix and neutral terms

// MODELS.md G1 in its G3 setting (wheel regeneration only, one mode) typed in as matrices, with
// the wheel surface S an algebraic variable (mass row 0):
//   F = (-q - S(t - T)) / C,  C = 1/kc + 1/kg,
//   q'' = -w^2 q - 2 zeta w q' + (w^2/k) F,    0 = -S + S(t - T) + F/kg,
// must have plunge_regenerative's rightmost root (its hand-written eq 2-16), at three wheel speeds.
TEST(LinearDde, G1TypedAsMatricesHasPlungeRegenerativesRoot) {
  const double f = 180.0, zeta = 0.03, k = 5e7, kc = 1e8, kg = 3e9, w = kTwoPi * f, c = 1.0 / kc + 1.0 / kg;
  for (double rpm : {1300.0, 1450.0, 1600.0}) {
    const Json matrices = {
        {"mass", {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 0.0}}},
        {"a0", {{0.0, 1.0, 0.0}, {-w * w - w * w / (k * c), -2.0 * zeta * w, 0.0}, {-1.0 / (kg * c), 0.0, -1.0}}},
        {"delayed", {Json{{"delay_s", 60.0 / rpm},
                          {"matrix", {{0.0, 0.0, 0.0}, {0.0, 0.0, -w * w / (k * c)}, {0.0, 0.0, 1.0 - 1.0 / (kg * c)}}}}}}};
    const Json g1 = {{"wheel_speed_rpm", rpm}, {"work_speed_rpm", 60.0}, {"contact_stiffness_n_per_m", kc},
                     {"wheel_wear_stiffness_n_per_m", kg}, {"work_removal_stiffness_n_per_m", 5e7},
                     {"work_regeneration", false},
                     {"modes", {Json{{"frequency_hz", f}, {"damping_ratio", zeta}, {"stiffness_n_per_m", k}}}}};
    RootSearchOptions options;
    options.max_frequency_hz = 800.0;
    const auto typed = model_registry().at("linear_dde").create(ParamValues(matrices));
    const auto reference = model_registry().at("plunge_regenerative").create(ParamValues(g1));
    const RightmostRoot a = find_rightmost_root(*typed->characteristic(), options);
    const RightmostRoot b = find_rightmost_root(*reference->characteristic(), options);
    ASSERT_TRUE(a.certified) << a.certificate;
    ASSERT_TRUE(b.certified) << b.certificate;
    EXPECT_NEAR(a.root.real(), b.root.real(), 1e-9 * std::abs(b.root)) << rpm << ": " << a.root << " vs " << b.root;
    EXPECT_NEAR(a.root.imag(), b.root.imag(), 1e-9 * std::abs(b.root)) << rpm;
  }
}

// A scalar neutral equation x'(t) - b x'(t - tau) = -a x(t) - g x(t - tau): its rightmost root is
// a zero of s (1 - b e^{-s tau}) + a + g e^{-s tau}, refined independently in long double, and
// its root chains accumulate at Re s = ln|b| / tau (the difference operator x - b x(t - tau)),
// which the certificate brackets.
TEST(LinearDde, NeutralScalarEquationMatchesItsQuasiPolynomial) {
  const long double a = 1.0L, g = 0.6L, b = 0.5L, tau = 1.0L;
  const Json table = {{"a0", {{-static_cast<double>(a)}}},
                      {"delayed", {Json{{"delay_s", static_cast<double>(tau)},
                                        {"matrix", {{-static_cast<double>(g)}}},
                                        {"neutral_matrix", {{static_cast<double>(b)}}}}}}};
  const LinearDde model{ParamValues(table)};
  const auto e = model.characteristic();
  RootSearchOptions options;
  options.max_frequency_hz = 5.0;
  const RightmostRoot found = find_rightmost_root(*e, options);
  ASSERT_TRUE(found.certified) << found.certificate;
  const ScalarFunction quasi = [&](LongComplex s) {
    const LongComplex z = std::exp(-s * tau);
    return std::make_pair(s * (1.0L - b * z) + a + g * z, 1.0L - b * z + s * b * tau * z - g * tau * z);
  };
  const auto refined = long_double_newton(quasi, LongComplex(found.root.real(), found.root.imag()));
  ASSERT_TRUE(refined);
  EXPECT_NEAR(found.root.real(), static_cast<double>(refined->real()), 1e-12 * std::abs(found.root));
  EXPECT_NEAR(found.root.imag(), static_cast<double>(refined->imag()), 1e-12 * std::abs(found.root));
  const auto* general = dynamic_cast<const DelayCharacteristic*>(e.get());
  ASSERT_NE(general, nullptr);
  const double chains = std::log(static_cast<double>(b)) / static_cast<double>(tau);
  EXPECT_TRUE(general->summary().neutral);
  EXPECT_LE(general->summary().difference_spectrum_lower, chains + 1e-9);
  EXPECT_GE(general->summary().difference_spectrum_upper, chains - 1e-9);
  EXPECT_GE(found.root.real(), chains);  // the rightmost root lies right of the chains here
}

TEST(LinearDde, MassAndNeutralErrorsNameTheKey) {
  Json mass = {{"a0", {{-1.0, 0.0}, {0.0, -1.0}}}, {"mass", {{1.0}}}, {"delayed", Json::array()}};
  EXPECT_EQ(construction_error(mass),
            "model.mass is 1x1 but model.a0 is 2x2: the mass matrix must be square with the size of a0");
  Json neutral = {{"a0", {{-1.0}}},
                  {"delayed", {Json{{"delay_s", 1.0}, {"matrix", {{0.1}}}, {"neutral_matrix", {{0.1, 0.0}}}}}}};
  EXPECT_EQ(construction_error(neutral),
            "model.delayed.0.neutral_matrix is 1x2 but model.a0 is 1x1: every neutral matrix must be square "
            "with the size of a0");
  // An algebraic row that does not determine its variable (index > 1).
  Json index2 = {{"a0", {{-1.0, 1.0}, {1.0, 0.0}}}, {"mass", {{1.0, 0.0}, {0.0, 0.0}}},
                 {"delayed", {Json{{"delay_s", 1.0}, {"matrix", {{0.0, 0.0}, {0.0, 0.0}}}}}}};
  const std::string e = construction_error(index2);
  EXPECT_EQ(e.rfind("model (mass / neutral_matrix): ", 0), 0u) << e;
}

}  // namespace
}  // namespace chatterlab
