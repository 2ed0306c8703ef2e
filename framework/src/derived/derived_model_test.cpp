// Known answers for models written once (chatterlab/derived_model.hpp): the linearisation by
// automatic differentiation against derivatives taken by hand, the derived characteristic
// function against eq 2-16 multiplied out (MODELS.md G1), the general delay-equation front end on
// DDE-BIFTOOL's neuron demo, and the time-domain adapter against the certified root (the growth
// of a simulated response).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "chatterlab/delay_equations.hpp"
#include "chatterlab/derived_model.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/roots.hpp"
#include "derived/g1_written_once.hpp"

namespace chatterlab {
namespace {

using test_support::G1Equations;
using LongComplex = std::complex<long double>;

class G1Model final : public DerivedModel<G1Equations> {
 public:
  using DerivedModel::DerivedModel;
};

TEST(DerivedModel, DualNumbersDifferentiateExactly) {
  using std::exp;
  using std::sin;
  using std::sqrt;
  auto f = [](auto x) { return sin(3.0 * x) * exp(x) / sqrt(1.0 + x * x); };
  const double x0 = 0.7;
  const Dual fx = f(Dual(x0, 1.0));
  const double analytic = (3.0 * std::cos(3.0 * x0) * std::exp(x0) + std::sin(3.0 * x0) * std::exp(x0)) / std::sqrt(1.0 + x0 * x0) -
                          std::sin(3.0 * x0) * std::exp(x0) * x0 / std::pow(1.0 + x0 * x0, 1.5);
  EXPECT_DOUBLE_EQ(fx.value, f(x0));
  EXPECT_NEAR(fx.derivative, analytic, 1e-14 * std::abs(analytic));
}

TEST(DerivedModel, G1JacobianIsTheHandDerivedOne) {
  const G1Equations eqs;
  const G1Model model(eqs);
  const JacobianMatrix j = model.jacobian({});
  ASSERT_EQ(j.rows, 6u);
  const double ks = 1.0 / (1.0 / eqs.kc + 1.0 / eqs.kg + 1.0 / eqs.kw);
  for (std::size_t i = 0; i < 2; ++i) {
    const double w = 2.0 * std::numbers::pi * eqs.modes[i][0], zeta = eqs.modes[i][1], k = eqs.modes[i][2];
    const std::size_t row = 2 * i + 1;
    for (std::size_t m = 0; m < 2; ++m) {
      // dF/dq_m = -ks for every mode (x = sum q), plus the mode's own spring.
      const double expected = w * w * (-ks / k) - (m == i ? w * w : 0.0);
      EXPECT_NEAR(j(row, 2 * m), expected, 1e-12 * std::abs(expected));
    }
    EXPECT_NEAR(j(row, row), -2.0 * zeta * w, 1e-12 * w);
    EXPECT_NEAR(j(row, 4), -w * w * ks / k, 1e-9);  // d x_i'' / d Wg(t - Tg)
  }
  EXPECT_NEAR(j(4, 4), -ks / eqs.kg, 1e-15);  // d removed_wheel / d Wg(t - Tg)
  EXPECT_NEAR(j(5, 0), -ks / eqs.kw, 1e-15);  // d removed_work / d q_1
}

TEST(DerivedModel, G1DerivedCharacteristicIsEq2_16) {
  G1Equations eqs;
  eqs.modes = {{67.56, 0.05, 3e7}, {184.08, 0.05, 5e7}, {305.6, 0.04, 8e7}};
  const G1Model model(eqs);
  auto e = model.derived_characteristic();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> re(-40.0, 30.0), im(0.0, 9000.0);
  std::optional<LongComplex> ratio;
  int compared = 0;
  for (int i = 0; i < 60; ++i) {
    const Complex s(re(rng), im(rng));
    const LongComplex reference = eqs.closed_form(LongComplex(s));
    // Away from zeros, where both are accurate relative to their size.
    if (std::abs(reference) < 1e-3L * std::abs(eqs.closed_form(LongComplex(s.real() + 50.0, s.imag())))) continue;
    const LongComplex value = LongComplex(e->evaluate(s).value) / reference;
    if (!ratio) ratio = value;
    EXPECT_LE(std::abs(value / *ratio - 1.0L), 1e-10L) << s;
    ++compared;
  }
  EXPECT_GE(compared, 40);
  // Rightmost root: a zero of eq 2-16 (long double Newton polish) and certified.
  RootSearchOptions options;
  options.max_frequency_hz = 1300.0;
  const RightmostRoot found = find_rightmost_root(*e, options);
  EXPECT_TRUE(found.certified) << found.certificate;
  LongComplex s = LongComplex(found.root);
  for (int i = 0; i < 30; ++i) {
    const long double h = 1e-7L * std::abs(s);
    const LongComplex f = eqs.closed_form(s), df = (eqs.closed_form(s + h) - eqs.closed_form(s - h)) / (2.0L * h);
    s -= f / df;
  }
  EXPECT_LE(std::abs(LongComplex(found.root) - s), 1e-12L * std::abs(s)) << found.root;
}

// DDE-BIFTOOL demo 1 ("neuron"): x1' = -kappa x1 + beta tanh(x1(t - tau_s)) + a12 tanh(x2(t - tau_2)),
// x2' = -kappa x2 + beta tanh(x2(t - tau_s)) + a21 tanh(x1(t - tau_1)), plus a constant input c
// that moves the steady state off zero (so tanh' != 1 tests the chain rule).
struct Neuron {
  double kappa = 0.5, beta = -1.0, a12 = 1.0, a21 = 0.8, tau1 = 0.2, tau2 = 0.2, tau_s = 1.5, c = 0.3;
  std::size_t state_size() const { return 2; }
  std::vector<double> delays_s() const { return {tau1, tau2, tau_s}; }
  template <class S>
  void rhs(std::span<const S> x, std::span<const std::span<const S>> d, std::span<S> out) const {
    using std::tanh;
    out[0] = -kappa * x[0] + beta * tanh(d[2][0]) + a12 * tanh(d[1][1]) + c;
    out[1] = -kappa * x[1] + beta * tanh(d[2][1]) + a21 * tanh(d[0][0]);
  }
};

TEST(DerivedModel, DelayEquationsLineariseWithTheChainRule) {
  const Neuron neuron;
  // Steady state by Newton on f(x, x, x, x) = 0 with the AD Jacobian A0 + sum A_k.
  std::vector<double> x = {0.0, 0.0};
  for (int it = 0; it < 50; ++it) {
    const LinearDelaySystem lin = linearise(neuron, x);
    Eigen::Matrix2d jac = lin.a0;
    for (const DelayTerm& t : lin.delayed) jac += t.matrix;
    std::vector<double> f(2);
    std::vector<std::span<const double>> views(3, std::span<const double>(x));
    neuron.rhs(std::span<const double>(x), std::span<const std::span<const double>>(views), std::span<double>(f));
    const Eigen::Vector2d step = jac.lu().solve(Eigen::Vector2d(f[0], f[1]));
    x[0] -= step(0);
    x[1] -= step(1);
  }
  const LinearDelaySystem lin = linearise(neuron, x);
  auto sech2 = [](double v) { return 1.0 - std::tanh(v) * std::tanh(v); };
  EXPECT_DOUBLE_EQ(lin.a0(0, 0), -neuron.kappa);
  EXPECT_NEAR(lin.delayed[2].matrix(0, 0), neuron.beta * sech2(x[0]), 1e-15);
  EXPECT_NEAR(lin.delayed[1].matrix(0, 1), neuron.a12 * sech2(x[1]), 1e-15);
  EXPECT_NEAR(lin.delayed[0].matrix(1, 0), neuron.a21 * sech2(x[0]), 1e-15);
  EXPECT_EQ(lin.delayed[0].matrix(0, 0), 0.0);
  EXPECT_NE(x[0], 0.0);
  // Its rightmost root is certified and is a root of the scalar-free 2 x 2 determinant.
  DelayCharacteristic e(lin);
  RootSearchOptions options;
  options.max_frequency_hz = 2.0;
  const RightmostRoot found = find_rightmost_root(e, options);
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_LT(std::abs(e.matrix(found.root).determinant()), 1e-12);
}

// The time-domain form the engine integrates is the same physics: a bilaterally linear G1 run
// grows at the rate of the certified rightmost root.
TEST(DerivedModelAccuracy, SimulatedGrowthMatchesTheCertifiedRoot) {
  G1Equations eqs;
  eqs.work = false;  // wheel regeneration only (G3): one lattice, a clean exponential
  eqs.kg = 3e9;
  eqs.work_rpm = 60.0;
  eqs.modes = {{180.0, 0.03, 5e7}};
  const G1Model model(eqs);
  RootSearchOptions options;
  options.max_frequency_hz = 800.0;
  const RightmostRoot root = find_rightmost_root(*model.characteristic(), options);
  ASSERT_TRUE(root.certified) << root.certificate;
  ASSERT_GT(root.root.real(), 0.5);
  SimulationSettings settings;
  settings.duration_s = 3.0;
  settings.sample_rate_hz = 10000.0;
  settings.one_sided_contact = false;
  settings.relative_tolerance = 1e-8;
  const SimulationResult run = simulate(*model.time_domain(), settings);
  const EnvelopeFit fit = fit_envelope(run.t_s, run.displacement_m, 1.5, 3.0, 50.0);
  EXPECT_NEAR(fit.growth_rate_per_s, root.root.real(), 0.02 * root.root.real())
      << "root " << root.root << ", fit residual " << fit.residual_rms;
}

}  // namespace
}  // namespace chatterlab
