// The fixed-step route of the dynamics engine against known answers and against the adaptive
// ARKODE reference route (docs/dynamics.md, "Fixed-step engine"):
// - the exponential integrator functions and the exact propagation of a linear form (a damped
//   oscillator under cubic forcing against its closed-form solution);
// - contact events of a one-sided oscillator located where the closed-form trajectory crosses
//   zero penetration, by both routes;
// - equivalence with the reference route (growth rate within 0.5 %, chatter frequency within
//   0.1 %, surfaces within 1 % rms) on G1, G5, G6, G7 and a variable-speed case (the suites whose
//   names end in Accuracy);
// - faults: a model whose linear form contradicts its derivatives, a right-hand side that is not
//   a number.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/params.hpp"
#include "dynamics/fixed_step_engine.hpp"
#include "dynamics/linear_propagator.hpp"
#include "dynamics/route_agreement.hpp"
#include "models/amplitude_modulated/amplitude_modulated.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "models/torsional_coupling/torsional_coupling.hpp"
#include "models/unbalance_two_dof/unbalance_two_dof.hpp"

namespace chatterlab {
namespace {

using dynamics_detail::ForcingNodes;
using dynamics_detail::LinearPropagator;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
using Complex = std::complex<double>;

// ------------------------------------------------------------------ exponential integrator

TEST(FixedStepEngine, PhiFunctionsAgreeWithTheirClosedForms) {
  // phi_1 = (e^z - 1)/z, phi_2 = (e^z - 1 - z)/z^2, ...: closed forms are accurate away from 0;
  // at 0 the values are 1/j!.
  for (Complex z : {Complex(3.0, 4.0), Complex(-7.5, 0.0), Complex(0.0, 2.5), Complex(-1.9, 0.3)}) {
    Complex phi[5];
    dynamics_detail::phi_functions(z, phi);
    const Complex e = std::exp(z);
    const Complex expected[5] = {e, (e - 1.0) / z, (e - 1.0 - z) / (z * z), (e - 1.0 - z - z * z / 2.0) / (z * z * z),
                                 (e - 1.0 - z - z * z / 2.0 - z * z * z / 6.0) / (z * z * z * z)};
    for (int j = 0; j < 5; ++j)
      EXPECT_LT(std::abs(phi[j] - expected[j]), 1e-12 * std::abs(expected[j])) << z << " phi_" << j;
  }
  Complex phi[5];
  dynamics_detail::phi_functions(0.0, phi);
  const double factorial_inverse[5] = {1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0};
  for (int j = 0; j < 5; ++j) EXPECT_DOUBLE_EQ(phi[j].real(), factorial_inverse[j]);
  // Inside |z| <= 2 (the series): against the long double series summed to convergence.
  for (Complex z : {Complex(1e-3, -2e-3), Complex(0.2, 0.1), Complex(-0.6, 0.7), Complex(1.2, -1.5)}) {
    dynamics_detail::phi_functions(z, phi);
    for (int j = 1; j < 5; ++j) {
      const std::complex<long double> zl(z.real(), z.imag());
      std::complex<long double> term = 1.0L, sum = 0.0L;
      for (int k = 1; k <= j; ++k) term /= static_cast<long double>(k);
      for (int k = 0; k < 60; ++k) {
        sum += term;
        term *= zl / static_cast<long double>(k + j + 1);
      }
      const Complex expected(static_cast<double>(sum.real()), static_cast<double>(sum.imag()));
      EXPECT_LT(std::abs(phi[j] - expected), 4e-16 * std::abs(expected)) << z << " phi_" << j;
    }
  }
}

// x'' + 2 zeta w x' + w^2 x = g(t), g a cubic: the exact solution is the particular polynomial
// solution plus the homogeneous one; the propagator, given g's averages over the step cells, must
// reproduce it to rounding over a step and over any piece of a step.
TEST(FixedStepEngine, LinearPropagationIsExactForCubicForcing) {
  const double w = kTwoPi * 300.0, zeta = 0.05, h = 1.0 / 3000.0;
  LinearForm form;
  form.contact_matrix = {0.0, 1.0, -w * w, -2.0 * zeta * w};
  form.contact_input = {0.0, 1.0};
  form.free_matrix = form.contact_matrix;
  form.free_input = form.contact_input;
  const double scales[2] = {1.0, w};
  LinearPropagator propagator(form, 2, h, scales);
  ASSERT_TRUE(propagator.ok()) << propagator.problem();
  // g(t) = c0 + c1 t + c2 t^2 + c3 t^3; particular solution p(t) = a0 + a1 t + a2 t^2 + a3 t^3
  // from w^2 p + 2 zeta w p' + p'' = g (coefficients from the top degree down).
  const double c[4] = {2e3, -4e6, 3e9, -5e12};
  const double b = 2.0 * zeta * w, k = w * w;
  double a[4];
  a[3] = c[3] / k;
  a[2] = (c[2] - 3.0 * b * a[3]) / k;
  a[1] = (c[1] - 2.0 * b * a[2] - 6.0 * a[3]) / k;
  a[0] = (c[0] - b * a[1] - 2.0 * a[2]) / k;
  auto g = [&](double t) { return c[0] + t * (c[1] + t * (c[2] + t * c[3])); };
  // The propagator takes the forcing's averages over step-long cells: exact for a cubic.
  auto integral = [&](double t) { return t * (c[0] + t * (c[1] / 2.0 + t * (c[2] / 3.0 + t * c[3] / 4.0))); };
  auto cell = [&](double from, double to) { return (integral(to) - integral(from)) / (to - from); };
  auto p = [&](double t) { return a[0] + t * (a[1] + t * (a[2] + t * a[3])); };
  auto dp = [&](double t) { return a[1] + t * (2.0 * a[2] + t * 3.0 * a[3]); };
  // Homogeneous part from x(0) = p(0) + 1e-6, x'(0) = p'(0): e^{-zeta w t}(A cos wd t + B sin wd t).
  const double wd = w * std::sqrt(1.0 - zeta * zeta), A = 1e-6, B = zeta * w * A / wd;
  auto exact = [&](double t, double out[2]) {
    const double e = std::exp(-zeta * w * t), co = std::cos(wd * t), si = std::sin(wd * t);
    out[0] = p(t) + e * (A * co + B * si);
    out[1] = dp(t) + e * (-zeta * w * (A * co + B * si) + wd * (-A * si + B * co));
  };
  const double t_k = 5.0 * h;  // a step in the middle of a run: nodes t_k - h .. t_k + 2h
  const double nodes[4] = {cell(t_k - h, t_k), cell(t_k, t_k + h), cell(t_k + h, t_k + 2.0 * h),
                           cell(t_k + 2.0 * h, t_k + 3.0 * h)};
  double x0[2], x1[2], expected[2];
  exact(t_k, x0);
  // The propagator's time origin is the step start: forcing and solution shift with it.
  propagator.step(true, ForcingNodes::centred, x0, nodes, x1);
  exact(t_k + h, expected);
  EXPECT_NEAR(x1[0], expected[0], 1e-12 * std::abs(expected[0]));
  EXPECT_NEAR(x1[1], expected[1], 1e-10 * std::abs(expected[1]));
  double xa[2], xb[2];
  exact(t_k + 0.3 * h, xa);
  propagator.piece(true, LinearPropagator::cubic(ForcingNodes::centred, nodes, h), 0.3 * h, 0.85 * h, xa, xb);
  exact(t_k + 0.85 * h, expected);
  EXPECT_NEAR(xb[0], expected[0], 1e-12 * std::abs(expected[0]));
  EXPECT_NEAR(xb[1], expected[1], 1e-10 * std::abs(expected[1]));
  // The first step's nodes t_k .. t_k + 3h.
  const double first[4] = {cell(t_k, t_k + h), cell(t_k + h, t_k + 2.0 * h), cell(t_k + 2.0 * h, t_k + 3.0 * h),
                          cell(t_k + 3.0 * h, t_k + 4.0 * h)};
  propagator.step(true, ForcingNodes::first_step, x0, first, x1);
  exact(t_k + h, expected);
  EXPECT_NEAR(x1[0], expected[0], 1e-12 * std::abs(expected[0]));
  EXPECT_NEAR(LinearPropagator::cubic(ForcingNodes::centred, nodes, h).value(0.4 * h), g(t_k + 0.4 * h),
              1e-9 * std::abs(g(t_k)));
}

// ------------------------------------------------------------------ contact events

// One G1 mode without regeneration, pressed into the work by 1 um with no infeed: in contact it
// rings at the stiffened frequency about zero penetration, leaves the work where x crosses 0
// (penetration -x), flies free at the bare frequency and re-enters where x crosses 0 again. Both
// phases are closed-form damped oscillations, so every event time is known to rounding.
struct BouncingOscillator {
  double w = kTwoPi * 250.0, zeta = 0.05, k = 5e7, kc = 1e8;
  PlungeRegenerativeParameters parameters() const {
    PlungeRegenerativeParameters p = reference_g1_case();  // these w, zeta, k and kc
    p.wheel_regeneration = p.work_regeneration = false;
    return p;
  }
  // Times of the first `count` zero crossings of x from x(0) = -1 um, x'(0) = 0.
  std::vector<double> events(int count) const {
    std::vector<double> times;
    double t0 = 0.0, x0 = -1e-6, v0 = 0.0;
    bool contact = true;
    for (int event = 0; event < count; ++event) {
      // x'' + 2 zeta w x' + W^2 x = 0 with W^2 = w^2 (1 + kc/k) in contact, w^2 free.
      const double W = contact ? w * std::sqrt(1.0 + kc / k) : w;
      const double decay = zeta * w, wd = std::sqrt(W * W - decay * decay);
      const double A = x0, B = (v0 + decay * x0) / wd;
      auto x = [&](double s) { return std::exp(-decay * s) * (A * std::cos(wd * s) + B * std::sin(wd * s)); };
      auto v = [&](double s) {
        const double e = std::exp(-decay * s), c = std::cos(wd * s), sn = std::sin(wd * s);
        return e * (-decay * (A * c + B * sn) + wd * (-A * sn + B * c));
      };
      // The first zero after s = 0 lies within half a damped period: bisection on a bracket.
      double lo = 1e-9 / wd, hi = lo;
      while ((x(hi) > 0.0) == (x(lo) > 0.0)) hi += 0.05 / wd;
      for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        ((x(mid) > 0.0) == (x(lo) > 0.0) ? lo : hi) = mid;
      }
      const double s = 0.5 * (lo + hi);
      times.push_back(t0 + s);
      t0 += s;
      v0 = v(s);
      x0 = 0.0;
      contact = !contact;
    }
    return times;
  }
};

TEST(FixedStepEngine, ContactEventsAreLocatedWhereTheExactTrajectoryCrossesZeroPenetration) {
  const BouncingOscillator oscillator;
  const std::vector<double> exact = oscillator.events(8);
  PlungeTimeDomain model(oscillator.parameters());
  for (TimeIntegrator integrator : {TimeIntegrator::fixed_step, TimeIntegrator::explicit_runge_kutta}) {
    SCOPED_TRACE(to_string(integrator));
    SimulationSettings s;
    s.integrator = integrator;
    s.duration_s = exact.back() + 1e-4;
    s.sample_rate_hz = 20000.0;
    s.one_sided_contact = true;
    s.disturbance = {-1e-6, 0.0};
    const SimulationResult r = simulate(model, s);
    ASSERT_EQ(r.status, "completed");
    ASSERT_GE(r.contact_loss_intervals.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
      // Loss of contact at exact[2i], re-entry at exact[2i + 1].
      EXPECT_NEAR(r.contact_loss_intervals[i].first, exact[2 * i], 1e-9) << "loss " << i;
      EXPECT_NEAR(r.contact_loss_intervals[i].second, exact[2 * i + 1], 1e-9) << "re-entry " << i;
    }
  }
}

// ------------------------------------------------------------------ equivalence with the reference

using dynamics_detail::RouteAgreement;

// Runs the model by the fixed-step engine (its defaults) and by the ARKODE reference (rtol 1e-8)
// and compares growth rate and chatter frequency over [fit_from, fit_to] and the last surface
// snapshot of every regenerated rotor.
RouteAgreement compare_routes(const TimeDomainModel& model, SimulationSettings s, double fit_from, double fit_to) {
  s.snapshot_times_s = {s.duration_s};
  SimulationSettings reference = s;
  reference.integrator = TimeIntegrator::explicit_runge_kutta;
  reference.relative_tolerance = 1e-8;
  s.integrator = TimeIntegrator::fixed_step;
  const SimulationResult a = simulate(model, reference), b = simulate(model, s);
  EXPECT_EQ(a.status, "completed");
  EXPECT_EQ(b.status, "completed");
  return dynamics_detail::route_agreement(a, b, fit_from, fit_to);
}

void expect_agreement(const RouteAgreement& a) {
  EXPECT_LT(a.growth_error, 0.005) << "growth " << a.growth_per_s << " /s, reference " << a.reference_growth_per_s;
  EXPECT_LT(a.frequency_error, 0.001) << "frequency " << a.frequency_hz << " Hz, reference " << a.reference_frequency_hz;
  EXPECT_LT(a.surface_error, 0.01);
  std::printf("growth %.6g vs %.6g /s (%.3g %%), frequency %.6g vs %.6g Hz (%.3g %%), surfaces %.3g %% rms\n",
              a.growth_per_s, a.reference_growth_per_s, 100.0 * a.growth_error, a.frequency_hz,
              a.reference_frequency_hz, 100.0 * a.frequency_error, 100.0 * a.surface_error);
}

SimulationSettings growth_settings(double duration_s) {
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = 10000.0;
  s.one_sided_contact = false;
  s.disturbance = {1e-6, 0.0};
  s.divergence_limit_m = 1e6;
  return s;
}

// A grinding pass as the shipped studies run it: one-sided contact with a 15 um/s infeed, started
// by 1 um random initial surfaces alone, stopped at 1 cm.
SimulationSettings one_sided_from_waviness(double duration_s) {
  SimulationSettings s = growth_settings(duration_s);
  s.one_sided_contact = true;
  s.infeed_rate_m_per_s = 15e-6;
  s.disturbance = {0.0, 0.0};
  s.initial_waviness_m = 1e-6;
  s.divergence_limit_m = 0.01;
  return s;
}

TEST(FixedStepEngineAccuracy, G1AgreesWithTheReferenceRoute) {
  const PlungeTimeDomain model(reference_g1_case());
  expect_agreement(compare_routes(model, growth_settings(4.0), 2.0, 4.0));
}

// G8's seven modes, one-sided contact with infeed and random initial surfaces (the shipped
// studies/simulate_g8_chatter.toml): the growth phase before the wheel first leaves the work.
TEST(FixedStepEngineAccuracy, G8SevenModesAgreeWithTheReferenceRoute) {
  const PlungeTimeDomain model(g8_grinder());
  SimulationSettings s = one_sided_from_waviness(3.0);
  s.seed = 7;
  expect_agreement(compare_routes(model, s, 1.2, 3.0));
}

// Variable speed: the wheel speed modulated by +-10 % at 2 Hz (MODELS.md S2-type suppression).
TEST(FixedStepEngineAccuracy, VariableWheelSpeedAgreesWithTheReferenceRoute) {
  const PlungeTimeDomain model(reference_g1_case());
  SimulationSettings s = growth_settings(4.0);
  s.speed[static_cast<std::size_t>(Rotor::wheel)] = make_modulated_speed(1450.0, SpeedModulation::sinusoidal, 0.1, 2.0);
  expect_agreement(compare_routes(model, s, 2.0, 4.0));
}

// G6: a steady forced response (growth 0), so the forced amplitude and phase stand for the
// growth rate: the fitted amplitude at the wheel frequency agrees within 0.5 %.
TEST(FixedStepEngineAccuracy, G6ForcedResponseAgreesWithTheReferenceRoute) {
  const Json j = UnbalanceTwoDof::info().example_params;
  UnbalanceTwoDof plugin{ParamValues(j)};
  const auto model = plugin.time_domain();
  SimulationSettings s = growth_settings(1.5);
  s.disturbance = {0.0, 0.0};
  s.snapshot_times_s = {1.5};
  SimulationSettings reference = s;
  reference.integrator = TimeIntegrator::explicit_runge_kutta;
  reference.relative_tolerance = 1e-8;
  const SimulationResult a = simulate(*model, reference), b = simulate(*model, s);
  const double w = kTwoPi * 1450.0 / 60.0;
  auto amplitude = [&](const SimulationResult& r) {
    Complex sum = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < r.t_s.size(); ++i)
      if (r.t_s[i] >= 0.5) {
        sum += r.displacement_m[i] * std::exp(Complex(0.0, -w * r.t_s[i]));
        ++n;
      }
    return 2.0 * sum / static_cast<double>(n);
  };
  const Complex xa = amplitude(a), xb = amplitude(b);
  EXPECT_LT(std::abs(xb - xa), 0.005 * std::abs(xa)) << xa << " " << xb;
  const double surfaces = dynamics_detail::route_agreement(a, b, 0.5, 1.5).surface_error;
  EXPECT_LT(surfaces, 0.01);
  std::printf("G6 amplitude %.6g vs %.6g m, surfaces %.3g %% rms\n", std::abs(xb), std::abs(xa), 100.0 * surfaces);
}

// G7: the periodic-coefficient (amplitude-modulated) model has no linear form: Runge-Kutta. The
// model's example (800 Hz, zeta 0.05, 5e7 N/m, kg b 5e6, kc b 1e8 N/m, Q 0.3, 1450 rpm).
TEST(FixedStepEngineAccuracy, G7AgreesWithTheReferenceRoute) {
  AmplitudeModulated plugin{ParamValues(AmplitudeModulated::info().example_params)};
  const auto model = plugin.time_domain();
  expect_agreement(compare_routes(*model, growth_settings(4.0), 2.0, 4.0));
}

// G5: speeds are states and the force depends on them (no linear form: Runge-Kutta). The
// model's example with its transverse damping lowered to 2000 N s/m, so that it chatters.
TEST(FixedStepEngineAccuracy, G5AgreesWithTheReferenceRoute) {
  Json params = TorsionalCoupling::info().example_params;
  params["damping_n_s_per_m"] = 2000.0;
  TorsionalCoupling plugin{ParamValues(params)};
  const auto model = plugin.time_domain();
  expect_agreement(compare_routes(*model, growth_settings(2.0), 1.0, 2.0));
}

// A duration that is no whole number of steps: the last step is shortened (a piece of a step),
// the run ends exactly at the duration with its last sample, and the end state agrees with the
// reference route's.
TEST(FixedStepEngine, ARunEndsExactlyAtItsDuration) {
  const PlungeTimeDomain model(reference_g1_case());
  SimulationSettings s = growth_settings(0.01234567);
  s.sample_rate_hz = 1000.0;
  const SimulationResult r = simulate(model, s);
  ASSERT_EQ(r.status, "completed");
  EXPECT_EQ(r.end_time_s, 0.01234567);
  ASSERT_EQ(r.t_s.size(), 13u);
  EXPECT_DOUBLE_EQ(r.t_s.back(), 0.012);
  EXPECT_GT(r.fixed_step_s, 0.0);
  EXPECT_NE(r.method.find("exact exponential"), std::string::npos) << r.method;
  SimulationSettings reference = s;
  reference.integrator = TimeIntegrator::explicit_runge_kutta;
  reference.relative_tolerance = 1e-10;
  const SimulationResult a = simulate(model, reference);
  ASSERT_EQ(a.end_state.size(), r.end_state.size());
  for (std::size_t i = 0; i < r.end_state.size(); i += 2)
    EXPECT_NEAR(r.end_state[i], a.end_state[i], 1e-6 * std::abs(a.end_state[i]) + 1e-15) << i;
}

// G5's example as the model ships it: one-sided contact with infeed, 1 um random initial
// waviness (white noise at the surface samples: kinks inside every Runge-Kutta step), speeds as
// states; growing at ~0.66 /s with ~1300 contact switches in 2 s.
TEST(FixedStepEngineAccuracy, G5OneSidedWithRandomWavinessAgreesWithTheReferenceRoute) {
  TorsionalCoupling plugin{ParamValues(TorsionalCoupling::info().example_params)};
  const auto model = plugin.time_domain();
  const SimulationSettings s = one_sided_from_waviness(2.0);
  expect_agreement(compare_routes(*model, s, 1.0, 2.0));
}

// ------------------------------------------------------------------ faults

// A model whose declared linear form is not its derivatives: refused at the start of the run.
class InconsistentForm final : public TimeDomainModel {
 public:
  std::size_t state_size() const override { return 2; }
  void initial_state(const Disturbance& d, std::span<double> x) const override {
    x[0] = d.displacement_m;
    x[1] = 0.0;
  }
  void state_scales(double d, std::span<double> s) const override {
    s[0] = d;
    s[1] = d * 1000.0;
  }
  double highest_frequency_hz() const override { return 300.0; }
  bool regenerates(Rotor) const override { return false; }
  double nominal_speed_rpm(Rotor) const override { return 1000.0; }
  void contact(const ContactInput&, ContactOutput& out) const override {
    out = ContactOutput{};
    out.penetration_m = 1.0;
  }
  void derivatives(const ContactInput& in, const ContactOutput&, std::span<double> dx) const override {
    dx[0] = in.state[1];
    dx[1] = -1e6 * in.state[0];
  }
  double displacement_m(std::span<const double> x) const override { return x[0]; }
  std::optional<LinearForm> linear_form(double) const override {
    LinearForm f;
    f.contact_matrix = f.free_matrix = {0.0, 1.0, -2e6, 0.0};  // not -1e6
    f.contact_input = f.free_input = {0.0, 0.0};
    return f;
  }
};

TEST(FixedStepEngine, ALinearFormThatContradictsTheDerivativesIsRefused) {
  SimulationSettings s = growth_settings(0.01);
  try {
    simulate(InconsistentForm(), s);
    FAIL() << "no exception";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("linear_form disagrees with its derivatives"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace chatterlab
