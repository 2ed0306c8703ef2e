// Known answers for plunge_regenerative (MODELS.md G1) and the root solver at grinding-scale
// delays. References are computed here by independent routes: long double Newton on the raw
// characteristic equation D(s) of eq 2-16 (not the solver's factored E), the G3 closed form
// (corrected eq 2-68), the imaginary-axis criterion of eq 2-21 and the published trend of fig 2-3.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "chatterlab/errors.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/roots.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"

namespace chatterlab {
namespace {

using LongComplex = std::complex<long double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

PlungeRegenerativeParameters single_mode(double contact_stiffness) {
  PlungeRegenerativeParameters p = g8_assumed_modes(contact_stiffness);
  p.modes = {{184.08, 0.05, 5.0e7}};
  return p;
}

RightmostRoot rightmost(const PlungeRegenerativeParameters& p, double band_hz = 1000.0,
                        int repair_rounds = RootSearchOptions{}.max_repair_rounds) {
  PlungeCharacteristic e(p);
  RootSearchOptions options;
  options.max_frequency_hz = band_hz;
  options.max_repair_rounds = repair_rounds;
  return find_rightmost_root(e, options);
}

// ---------------------------------------------------------------- independent references

// Raw eq 2-16, long double: D(s) = 1 + kc [ H(s) + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s})) ].
struct RawCharacteristic {
  const PlungeRegenerativeParameters& p;

  std::pair<LongComplex, LongComplex> operator()(LongComplex s) const {
    const long double kc = p.contact_stiffness_n_per_m;
    LongComplex d = 1.0L, dd = 0.0L;
    for (const StructuralMode& m : p.modes) {
      const long double w = 2.0L * std::numbers::pi_v<long double> * m.frequency_hz;
      LongComplex den = s * s / (w * w) + 2.0L * m.damping_ratio * s / w + 1.0L;
      LongComplex dden = 2.0L * s / (w * w) + 2.0L * m.damping_ratio / w;
      d += kc / m.stiffness_n_per_m / den;
      dd -= kc / m.stiffness_n_per_m * dden / (den * den);
    }
    auto chain = [&](bool on, long double rpm, long double stiffness) {
      if (!on) return;
      const long double period = 60.0L / rpm;
      LongComplex e = std::exp(-period * s), a = 1.0L - e;
      d += kc / stiffness / a;
      dd -= kc / stiffness * period * e / (a * a);
    };
    chain(p.wheel_regeneration, p.wheel_speed_rpm, p.wheel_wear_stiffness_n_per_m);
    chain(p.work_regeneration, p.work_speed_rpm, p.work_removal_stiffness_n_per_m);
    return {d, dd};
  }
};

LongComplex polish(const PlungeRegenerativeParameters& p, Complex start) {
  RawCharacteristic raw{p};
  LongComplex s(start.real(), start.imag());
  for (int i = 0; i < 60; ++i) {
    auto [d, dd] = raw(s);
    LongComplex step = d / dd;
    s -= step;
    if (std::abs(step) <= 1e-18L * std::abs(s)) break;
  }
  return s;
}

// Machine compliance H(jw) [m/N], independent of the plugin.
std::complex<double> compliance(const PlungeRegenerativeParameters& p, double w) {
  std::complex<double> h = 0.0;
  for (const StructuralMode& m : p.modes) {
    const double wn = kTwoPi * m.frequency_hz, r = w / wn;
    h += 1.0 / (m.stiffness_n_per_m * std::complex<double>(1.0 - r * r, 2.0 * m.damping_ratio * r));
  }
  return h;
}

// ---------------------------------------------------------------- accuracy

TEST(PlungeRegenerative, RootsMatchLongDoubleNewtonOnEquation2_16) {
  for (double kc : {1e6, 1e7, 1e8}) {
    PlungeRegenerativeParameters p = g8_assumed_modes(kc);
    RightmostRoot found = rightmost(p);
    ASSERT_TRUE(found.certified) << found.certificate;
    LongComplex reference = polish(p, found.root);
    const Complex ref(static_cast<double>(reference.real()), static_cast<double>(reference.imag()));
    EXPECT_LE(std::abs(found.root - ref), 1e-9 * std::abs(ref)) << "kc " << kc;
    // The growth rate itself (Re s is 1e-3..1 while |s| ~ 1e3): absolute error well below 1e-9 |s|.
    EXPECT_LE(std::abs(found.root.real() - ref.real()), 1e-9 * std::abs(ref.real()) + 1e-10)
        << "kc " << kc << " root " << found.root << " reference " << ref;
    // D really vanishes there (eq 2-16), not only the solver's factored E.
    EXPECT_LT(std::abs(RawCharacteristic{p}(reference).first), 1e-12L);
  }
}

TEST(PlungeRegenerative, DerivativeAndConjugateSymmetry) {
  PlungeCharacteristic e(g8_assumed_modes(1e7));
  for (Complex s : {Complex(-0.01, 1366.0), Complex(0.5, 300.0), Complex(-2.0, 2400.0)}) {
    CharacteristicValue v = e.evaluate(s), c = e.evaluate(std::conj(s));
    EXPECT_LE(std::abs(c.value - std::conj(v.value)), 1e-14 * std::abs(v.value));
    EXPECT_LE(std::abs(c.derivative - std::conj(v.derivative)), 1e-14 * std::abs(v.derivative));
    const double h = 1e-5;
    Complex numeric = (e.evaluate(s + h).value - e.evaluate(s - h).value) / (2.0 * h);
    EXPECT_LE(std::abs(numeric - v.derivative), 1e-6 * std::abs(v.derivative)) << s;
  }
  // The reported root has Im >= 0 and its conjugate is a root too.
  RightmostRoot found = rightmost(g8_assumed_modes(1e7));
  EXPECT_GE(found.root.imag(), 0.0);
  LongComplex conjugate = polish(g8_assumed_modes(1e7), std::conj(found.root));
  EXPECT_LE(std::abs(Complex(static_cast<double>(conjugate.real()), static_cast<double>(conjugate.imag())) -
                     std::conj(found.root)),
            1e-9 * std::abs(found.root));
}

// ---------------------------------------------------------------- published behaviour

// The Newton form is E / (1 + beta - e^{-Tw s}) (value and derivative), E itself when the work
// chain is off, and the search finds the same certified rightmost root with it as with E alone.
TEST(PlungeRegenerative, NewtonFormIsEOverTheWorkChainFactorAndFindsTheSameRoots) {
  const PlungeRegenerativeParameters p = g8_assumed_modes(1e7);
  const PlungeCharacteristic e(p);
  const double tw = 60.0 / p.work_speed_rpm, beta = p.contact_stiffness_n_per_m / p.work_removal_stiffness_n_per_m;
  for (Complex s : {Complex(-0.01, 1366.0), Complex(0.5, 300.0), Complex(-2.0, 2400.0)}) {
    const Complex g = 1.0 + beta - std::exp(-tw * s);
    const CharacteristicValue f = e.newton_form(s);
    EXPECT_LE(std::abs(f.value * g - e.evaluate(s).value), 1e-13 * std::abs(e.evaluate(s).value)) << s;
    const double h = 1e-5;
    const Complex numeric = (e.newton_form(s + h).value - e.newton_form(s - h).value) / (2.0 * h);
    EXPECT_LE(std::abs(numeric - f.derivative), 1e-6 * std::abs(f.derivative)) << s;
  }
  PlungeRegenerativeParameters wheel_only = p;
  wheel_only.work_regeneration = false;
  const PlungeCharacteristic w(wheel_only);
  EXPECT_EQ(w.newton_form(Complex(0.5, 300.0)).value, w.evaluate(Complex(0.5, 300.0)).value);

  // E alone: the same function without its Newton form (the interface's default).
  struct EAlone final : CharacteristicFunction {
    explicit EAlone(const PlungeCharacteristic& full) : f(full) {}
    CharacteristicValue evaluate(Complex s) const override { return f.evaluate(s); }
    std::vector<Complex> neutral_roots(double band) const override { return f.neutral_roots(band); }
    void initial_guesses(double band, std::vector<Complex>& guesses) const override { f.initial_guesses(band, guesses); }
    double real_part_bound() const override { return f.real_part_bound(); }
    double natural_frequency_scale_hz() const override { return f.natural_frequency_scale_hz(); }
    const PlungeCharacteristic& f;
  };
  for (double kc : {1e6, 1e7, 1e8}) {
    const PlungeCharacteristic with_form(g8_assumed_modes(kc));
    RootSearchOptions options;
    options.max_frequency_hz = 1000.0;
    const RightmostRoot a = find_rightmost_root(with_form, options);
    const RightmostRoot b = find_rightmost_root(EAlone(with_form), options);
    ASSERT_TRUE(a.certified && b.certified) << a.certificate << " / " << b.certificate;
    EXPECT_LE(std::abs(a.root - b.root), 1e-12 * std::abs(b.root)) << "kc " << kc;
  }
}

TEST(PlungeRegenerative, WheelOnlyGrowthRateAgreesWithG3ClosedForm) {
  // Work regeneration off (kw -> infinity: the term of eq 2-16 vanishes): the wheel-regenerative
  // system of eq 2-66. rho = Tg sigma / (2 pi) (eq 2-67, 2-70).
  // Contact stiffnesses around the onset of wheel-regenerative chatter (|sigma| small against the
  // modal bandwidth zeta w, where evaluating Gm on the axis is a good approximation).
  for (double kc : {1.2e7, 1.5e7, 2e7, 2.5e7}) {
    PlungeRegenerativeParameters p = single_mode(kc);
    p.work_regeneration = false;
    p.wheel_wear_stiffness_n_per_m = 2e8;  // a soft wheel: wheel-regenerative chatter (G3)
    RightmostRoot found = rightmost(p);
    ASSERT_TRUE(found.certified) << found.certificate;
    const double tg = 60.0 / p.wheel_speed_rpm, kg = p.wheel_wear_stiffness_n_per_m;
    const double rho_exact = tg * found.root.real() / kTwoPi;
    // Corrected 2-68 with w = kg H + kg/kc = p (x + j y) + q; exact when H is taken at the root s.
    auto rho = [&](std::complex<double> w) {
      return -std::log(1.0 + (1.0 + 2.0 * w.real()) / std::norm(w)) / (4.0 * std::numbers::pi);
    };
    PlungeCharacteristic e(p);
    std::complex<double> w_root = kg * e.structural_compliance(found.root) + kg / kc;
    EXPECT_NEAR(rho(w_root), rho_exact, 1e-9 * std::abs(rho_exact) + 1e-12) << "kc " << kc;
    // The published closed form takes Gm at s = j w: first-order error sigma |dw/ds| |drho/dw|.
    const double w = found.root.imag();
    std::complex<double> w_axis = kg * compliance(p, w) + kg / kc;
    const double dw_ds = kg * std::abs(compliance(p, w + 1e-3) - compliance(p, w - 1e-3)) / 2e-3;
    const double drho_dw = std::abs(rho(w_axis + 1e-6) - rho(w_axis - 1e-6)) / 2e-6 +
                           std::abs(rho(w_axis + std::complex<double>(0, 1e-6)) -
                                    rho(w_axis - std::complex<double>(0, 1e-6))) / 2e-6;
    const double first_order = std::abs(found.root.real()) * dw_ds * drho_dw;
    EXPECT_LE(std::abs(rho(w_axis) - rho_exact), 2.0 * first_order + 1e-12)
        << "kc " << kc << ": closed form " << rho(w_axis) << " root " << rho_exact;
    // Beyond that error band the closed form gets the verdict (chatter or not) right.
    if (std::abs(rho_exact) > 2.0 * first_order) {
      EXPECT_EQ(rho(w_axis) > 0.0, rho_exact > 0.0) << "kc " << kc;
    }
  }
}

TEST(PlungeRegenerative, GrowthRateIncreasesWithContactStiffness) {
  // Fig 2-3: the chatter growth coefficient sigma increases with kc; lowering kc stabilises. This
  // is the root that couples with the structure (from the onset of chatter upwards). Below it the
  // rightmost root is a regeneration-chain root near Re s = 0 whose decay rate grows with kc
  // (Re s ~ -ln|1 + kc/kw ...|/Tw), checked at the end.
  double previous = -1e300;
  for (double kc = 1.05e7; kc <= 3e8; kc *= 1.6) {
    RightmostRoot found = rightmost(single_mode(kc));
    ASSERT_TRUE(found.certified) << "kc " << kc << ": " << found.certificate;
    EXPECT_GT(found.root.real(), previous) << "kc " << kc;
    previous = found.root.real();
  }
  EXPECT_GT(previous, 0.0);  // chatter at the stiff end
  RightmostRoot soft = rightmost(single_mode(1e6)), softer = rightmost(single_mode(5e5));
  EXPECT_LT(soft.root.real(), 0.0);
  EXPECT_LT(soft.root.real(), softer.root.real());
}

TEST(PlungeRegenerative, ImaginaryAxisCriterionAgreesWithTheRightmostRoot) {
  // Eq 2-21: on s = j w the process line is Re = -(1/2)(2/kc + 1/kg + 1/kw); no intersection with
  // the machine compliance circle means stable. One mode: min Re H(jw) = -1/(4 zeta (1 + zeta) k).
  PlungeRegenerativeParameters base = single_mode(1e8);
  const StructuralMode m = base.modes.front();
  const double circle_min = -1.0 / (4.0 * m.damping_ratio * (1.0 + m.damping_ratio) * m.stiffness_n_per_m);
  for (double ratio : {0.5, 0.8, 1.25, 2.0}) {  // circle_min / line
    // Choose kc so that the line sits at circle_min / ratio.
    const double line = circle_min / ratio;
    const double half_chains = 0.5 / base.wheel_wear_stiffness_n_per_m + 0.5 / base.work_removal_stiffness_n_per_m;
    PlungeRegenerativeParameters p = base;
    p.contact_stiffness_n_per_m = 1.0 / (-line - half_chains);
    ASSERT_GT(p.contact_stiffness_n_per_m, 0.0);
    for (double work_rpm : {55.0, 43.0}) {
      p.work_speed_rpm = work_rpm;
      RightmostRoot found = rightmost(p);
      ASSERT_TRUE(found.certified) << found.certificate;
      const bool intersects = ratio > 1.0;
      EXPECT_EQ(found.root.real() > 0.0, intersects)
          << "ratio " << ratio << " work " << work_rpm << " rpm: root " << found.root;
      if (!intersects) {
        EXPECT_LT(found.certified_real_part, 0.0) << found.certificate;
      }
    }
  }
}

TEST(PlungeRegenerative, RightmostRootIsContinuousAcrossGridNeighbours) {
  // A 1-D grid of contact stiffness (1 % steps) in the chattering regime of G8: neighbouring
  // growth rates may differ only by what the step explains (no jumps from a missed root).
  std::vector<double> sigma;
  for (int i = 0; i <= 30; ++i) {
    RightmostRoot found = rightmost(g8_assumed_modes(3e7 * std::pow(1.01, i)));
    ASSERT_TRUE(found.certified) << found.certificate;
    sigma.push_back(found.root.real());
  }
  std::vector<double> steps;
  for (std::size_t i = 1; i < sigma.size(); ++i) steps.push_back(std::abs(sigma[i] - sigma[i - 1]));
  std::vector<double> sorted = steps;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < steps.size(); ++i)
    EXPECT_LE(steps[i], 4.0 * median + 1e-9) << "between grid points " << i << " and " << i + 1;
  EXPECT_GT(sigma.back(), sigma.front());  // and the fig 2-3 trend across the whole grid
}

// ---------------------------------------------------------------- neutral roots, certificate

TEST(PlungeRegenerative, NeutralRootsAreTheCommonLatticePoints) {
  PlungeRegenerativeParameters p = g8_assumed_modes(1e7);
  PlungeCharacteristic e(p);
  // 1450/55 = 290/11: wheel and work lattices meet every 11 * 1450/60 = 265.83 Hz.
  std::vector<Complex> neutral = e.neutral_roots(kTwoPi * 1000.0);
  ASSERT_EQ(neutral.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(neutral[k].imag(), kTwoPi * 11.0 * 1450.0 / 60.0 * k, 1e-9 * kTwoPi * 1000.0);
    // A zero of E to rounding: compare with E a tenth of a lattice spacing away.
    const double nearby = std::abs(e.evaluate(neutral[k] + Complex(0.0, 0.5)).value);
    EXPECT_LT(std::abs(e.evaluate(neutral[k]).value), 1e-9 * nearby) << k;
  }
  RightmostRoot found = rightmost(p);
  EXPECT_GE(found.neutral_roots_excluded, 1);
  for (Complex n : neutral) EXPECT_GT(std::abs(found.root - n), 1e-3);
  // One chain alone has no neutral root.
  p.wheel_regeneration = false;
  EXPECT_TRUE(PlungeCharacteristic(p).neutral_roots(kTwoPi * 1000.0).empty());
  p.wheel_regeneration = true;
  p.wheel_speed_rpm = 1451.0;  // incommensurate: only s = 0
  EXPECT_EQ(PlungeCharacteristic(p).neutral_roots(kTwoPi * 1000.0).size(), 1u);
}

// Wraps a characteristic function and passes on only the guesses below a frequency, so that
// Newton does not find the roots above it (Newton alone may still wander up to one).
class GuessesBelow final : public CharacteristicFunction {
 public:
  GuessesBelow(const CharacteristicFunction& inner, double cutoff_rad_s) : inner_(inner), cutoff_(cutoff_rad_s) {}
  CharacteristicValue evaluate(Complex s) const override { return inner_.evaluate(s); }
  std::vector<Complex> neutral_roots(double band) const override { return inner_.neutral_roots(band); }
  void initial_guesses(double band, std::vector<Complex>& guesses) const override {
    std::vector<Complex> all;
    inner_.initial_guesses(band, all);
    for (Complex g : all)
      if (g.imag() < cutoff_) guesses.push_back(g);
  }
  double real_part_bound() const override { return inner_.real_part_bound(); }
  double natural_frequency_scale_hz() const override { return inner_.natural_frequency_scale_hz(); }

 private:
  const CharacteristicFunction& inner_;
  double cutoff_;
};

TEST(PlungeRegenerative, CertificateCatchesARootTheGuessesMissed) {
  PlungeRegenerativeParameters p = g8_assumed_modes(1e8);
  PlungeCharacteristic e(p);
  RightmostRoot truth = rightmost(p);
  ASSERT_TRUE(truth.certified) << truth.certificate;
  GuessesBelow blind(e, 0.5 * truth.root.imag());
  RootSearchOptions options;
  options.max_frequency_hz = 1000.0;
  options.max_repair_rounds = 0;
  RightmostRoot missed = find_rightmost_root(blind, options);
  EXPECT_LT(missed.root.real(), truth.root.real());  // the guesses alone pick a wrong root...
  EXPECT_FALSE(missed.certified);                    // ...and the count says so
  EXPECT_GE(missed.zeros_right_of_contour, 1);
  EXPECT_EQ(missed.certificate.substr(0, 12), "uncertified:");
  options.max_repair_rounds = 3;
  RightmostRoot repaired = find_rightmost_root(blind, options);
  EXPECT_TRUE(repaired.certified) << repaired.certificate;
  EXPECT_GE(repaired.repaired_roots, 1);
  EXPECT_LE(std::abs(repaired.root - truth.root), 1e-9 * std::abs(truth.root));
}

TEST(PlungeRegenerative, IdenticalModesMergeInsteadOfAddingASpuriousZero) {
  PlungeRegenerativeParameters twice = single_mode(1e8), once = single_mode(1e8);
  twice.modes.push_back(twice.modes.front());
  once.modes.front().stiffness_n_per_m /= 2.0;  // two equal compliances in parallel
  RightmostRoot a = rightmost(twice), b = rightmost(once);
  EXPECT_TRUE(a.certified) << a.certificate;
  EXPECT_LE(std::abs(a.root - b.root), 1e-12 * std::abs(b.root));
}

TEST(PlungeRegenerative, RealPartBoundLiesRightOfEveryRoot) {
  // A compliant machine and a stiff contact push roots far right; the bound must still hold.
  PlungeRegenerativeParameters p = single_mode(5e9);
  p.modes.front().damping_ratio = 0.0;
  PlungeCharacteristic e(p);
  RightmostRoot found = rightmost(p);
  EXPECT_TRUE(found.certified) << found.certificate;
  EXPECT_GT(found.root.real(), 0.0);
  EXPECT_GT(e.real_part_bound(), found.root.real());
}

// ---------------------------------------------------------------- plugin surface

struct NoSources final : SourceMap {
  SourceLocation locate(std::string_view) const override { return {}; }
};

TEST(PlungeRegenerative, RegisteredWithValidExampleAndWheelPeriod) {
  const auto& entry = model_registry().at("plunge_regenerative");
  EXPECT_EQ(entry.info.models_md_ids, "G1, G3");
  Json validated = validate_params(entry.info.example_params, entry.info.params, "model", NoSources{});
  auto model = entry.create(ParamValues(validated));
  ASSERT_TRUE(model->wheel_period_s());
  EXPECT_DOUBLE_EQ(*model->wheel_period_s(), 60.0 / 1450.0);
  auto characteristic = model->characteristic();
  EXPECT_DOUBLE_EQ(characteristic->natural_frequency_scale_hz(), 305.6);
}

std::string validation_error(Json table) {
  try {
    validate_params(table, PlungeRegenerative::info().params, "model", NoSources{});
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PlungeRegenerative, BadParametersNameKeyValueAndLimit) {
  Json example = PlungeRegenerative::info().example_params;
  Json damping = example;
  damping["modes"][0]["damping_ratio"] = 1.0;
  std::string message = validation_error(damping);
  EXPECT_NE(message.find("model.modes.0.damping_ratio = 1"), std::string::npos) << message;
  EXPECT_NE(message.find("< 1"), std::string::npos) << message;
  Json stiffness = example;
  stiffness["contact_stiffness_n_per_m"] = -5.0;
  message = validation_error(stiffness);
  EXPECT_NE(message.find("model.contact_stiffness_n_per_m = -5 [N/m]"), std::string::npos) << message;
  EXPECT_NE(message.find("> 0"), std::string::npos) << message;
  Json speed = example;
  speed["work_speed_rpm"] = 0.0;
  message = validation_error(speed);
  EXPECT_NE(message.find("model.work_speed_rpm = 0 [rpm]"), std::string::npos) << message;
  Json no_modes = example;
  no_modes["modes"] = Json::array();
  message = validation_error(no_modes);
  EXPECT_NE(message.find("model.modes has 0 entries"), std::string::npos) << message;
}

}  // namespace
}  // namespace chatterlab
