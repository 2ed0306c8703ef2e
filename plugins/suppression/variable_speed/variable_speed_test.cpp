// variable_speed (MODELS.md S1-S3): the modulation laws integrate to the right angle/infeed, the
// random law is bounded, reproducible and has its stated rms, and bad parameters are refused.
#include "suppression/variable_speed/variable_speed.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "chatterlab/model.hpp"

namespace chatterlab {
namespace {

VariableSpeedParameters parameters(ModulationShape shape, double amplitude, double frequency,
                                   SuppressionTarget target = SuppressionTarget::wheel_speed) {
  VariableSpeedParameters p;
  p.target = target;
  p.shape = shape;
  p.amplitude_ratio = amplitude;
  p.frequency_hz = frequency;
  p.seed = 42;
  return p;
}

// Composite Simpson integral of f over [0, t] with n (even) intervals.
template <class F>
double simpson(F f, double t, int n) {
  const double h = t / n;
  double sum = f(0.0) + f(t);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(i * h);
  return sum * h / 3.0;
}

// A minimal time-domain model for installing laws (only the speeds matter here).
class TwoRotors final : public TimeDomainModel {
 public:
  explicit TwoRotors(double wheel_rpm = 1500.0) : wheel_rpm_(wheel_rpm) {}
  std::size_t state_size() const override { return 2; }
  void initial_state(const Disturbance&, std::span<double> x) const override { x[0] = x[1] = 0; }
  void state_scales(double d, std::span<double> s) const override { s[0] = s[1] = d; }
  double highest_frequency_hz() const override { return 100.0; }
  bool regenerates(Rotor) const override { return false; }
  double nominal_speed_rpm(Rotor r) const override { return r == Rotor::wheel ? wheel_rpm_ : 60.0; }
  void contact(const ContactInput&, ContactOutput&) const override {}
  void derivatives(const ContactInput&, const ContactOutput&, std::span<double> dx) const override { dx[0] = dx[1] = 0; }
  double displacement_m(std::span<const double> x) const override { return x[0]; }

 private:
  double wheel_rpm_;
};
using WheelOnly = TwoRotors;

TEST(VariableSpeed, EveryShapeIntegratesToItsAngle) {
  // The installed wheel law's angle_rad = 2 pi/60 * integral of rpm, against a midpoint-rule
  // quadrature of rpm (h = 1e-5 s; each square-wave jump costs at most jump * h/2, 15 jumps here).
  for (ModulationShape shape : {ModulationShape::sinusoidal, ModulationShape::triangular,
                                ModulationShape::square, ModulationShape::random}) {
    VariableSpeed plugin(parameters(shape, 0.3, 2.5));
    const double horizon = 3.0, mean_rpm = 1500.0;
    auto law = plugin.law(horizon);
    SimulationSettings settings;
    apply_modulation(plugin.target(), law, WheelOnly(mean_rpm), settings);
    const SpeedLaw& speed = *settings.speed[static_cast<std::size_t>(Rotor::wheel)];
    for (double t : {0.05, 0.2, 0.77, 1.6, 2.999}) {
      const auto n = static_cast<long>(std::round(t / 1e-5));
      const double h = t / static_cast<double>(n);
      double numeric = 0.0;
      for (long i = 0; i < n; ++i) numeric += speed.rpm((static_cast<double>(i) + 0.5) * h);
      numeric *= h * 2.0 * std::numbers::pi / 60.0;
      EXPECT_NEAR(speed.angle_rad(t), numeric, 1e-4 * numeric)
          << "shape " << static_cast<int>(shape) << " t " << t;
      EXPECT_NEAR(law->level_integral(t), speed.angle_rad(t) * 60.0 / (2.0 * std::numbers::pi * mean_rpm), 1e-12);
    }
    EXPECT_NEAR(law->min_level(), 0.7, 1e-12);
    EXPECT_NEAR(law->max_level(), 1.3, 1e-12);
    EXPECT_NEAR(speed.min_rpm(horizon), 0.7 * mean_rpm, 1e-9);
  }
}

TEST(VariableSpeed, SmoothShapesIntegrateToRounding) {
  // Sine, triangle and random are continuous: Simpson converges fast and the exact integral
  // must agree to ~1e-10 (a wrong constant or phase would show at 1e-2).
  for (ModulationShape shape : {ModulationShape::sinusoidal, ModulationShape::triangular, ModulationShape::random}) {
    auto law = VariableSpeed(parameters(shape, 0.45, 3.0)).law(2.0);
    const double t = 1.9;  // not on a knot or a period boundary
    const double numeric = simpson([&](double s) { return law->level(s); }, t, 200000);
    EXPECT_NEAR(law->level_integral(t), numeric, 1e-8) << static_cast<int>(shape);
  }
}

TEST(VariableSpeed, RandomLawIsBoundedReproducibleAndHasItsRms) {
  VariableSpeedParameters p = parameters(ModulationShape::random, 0.2, 10.0);
  auto a = make_modulation_law(p, 2000.0);
  auto b = make_modulation_law(p, 2000.0);
  p.seed = 43;
  auto c = make_modulation_law(p, 2000.0);
  double sum2 = 0.0, lowest = 2.0, highest = 0.0, differences = 0.0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    const double t = 0.005 * i + 0.0013;
    const double level = a->level(t);
    EXPECT_EQ(level, b->level(t));  // same seed, same law (bit for bit)
    differences += std::abs(level - c->level(t));
    const double w = (level - 1.0) / 0.2;
    sum2 += w * w;
    lowest = std::min(lowest, level);
    highest = std::max(highest, level);
  }
  EXPECT_GE(lowest, 0.8 - 1e-15);
  EXPECT_LE(highest, 1.2 + 1e-15);
  EXPECT_LT(lowest, 0.805);  // the levels do reach the bounds
  EXPECT_GT(highest, 1.195);
  EXPECT_GT(differences / n, 0.01);  // another seed, another law
  // rms of w = 1/2 (documented); 20,000 independent knots: standard error ~0.3 %.
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.5, 0.01);
  EXPECT_EQ(a->level(0.0), 1.0);  // starts at the mean
}

TEST(VariableSpeed, RandomLawBeyondItsHorizonContinuesTheSameLaw) {
  VariableSpeedParameters p = parameters(ModulationShape::random, 0.3, 4.0);
  auto short_law = make_modulation_law(p, 1.0);
  auto long_law = make_modulation_law(p, 10.0);
  for (double t : {0.3, 2.7, 7.9}) {
    EXPECT_DOUBLE_EQ(short_law->level(t), long_law->level(t));
    EXPECT_NEAR(short_law->level_integral(t), long_law->level_integral(t), 1e-12);
  }
}

TEST(VariableSpeed, RefusesAStoppingOrReversingSpindleAndABadFrequency) {
  EXPECT_THROW(VariableSpeed(parameters(ModulationShape::sinusoidal, 1.0, 1.0)), std::invalid_argument);
  EXPECT_THROW(VariableSpeed(parameters(ModulationShape::random, 1.5, 1.0)), std::invalid_argument);
  EXPECT_THROW(VariableSpeed(parameters(ModulationShape::random, 0.2, 0.0)), std::invalid_argument);
  try {
    VariableSpeed(parameters(ModulationShape::square, 1.0, 1.0));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("would stop or reverse"), std::string::npos) << e.what();
  }
}

TEST(VariableSpeed, InstallsItsLawOnTheTargetOnly) {
  TwoRotors model;
  for (SuppressionTarget target : {SuppressionTarget::wheel_speed, SuppressionTarget::work_speed, SuppressionTarget::feed}) {
    VariableSpeed plugin(parameters(ModulationShape::triangular, 0.25, 2.0, target));
    SimulationSettings s;
    s.infeed_rate_m_per_s = 10e-6;
    apply_modulation(plugin.target(), plugin.law(1.0), model, s);
    const double t = 0.125;  // a quarter period: the triangle at its peak
    constexpr auto wheel = static_cast<std::size_t>(Rotor::wheel), work = static_cast<std::size_t>(Rotor::work);
    EXPECT_EQ(s.speed[wheel] != nullptr, target == SuppressionTarget::wheel_speed);
    EXPECT_EQ(s.speed[work] != nullptr, target == SuppressionTarget::work_speed);
    EXPECT_EQ(s.infeed != nullptr, target == SuppressionTarget::feed);
    if (s.speed[wheel]) {
      EXPECT_NEAR(s.speed[wheel]->rpm(t), 1500.0 * 1.25, 1e-9);
      EXPECT_NEAR(s.speed[wheel]->min_rpm(1.0), 1500.0 * 0.75, 1e-9);
    }
    if (s.speed[work]) {
      EXPECT_NEAR(s.speed[work]->rpm(t), 60.0 * 1.25, 1e-9);
    }
    if (s.infeed) {
      EXPECT_NEAR(s.infeed->rate_m_per_s(t), 12.5e-6, 1e-15);
      // Over whole periods the infeed equals the mean rate times time.
      EXPECT_NEAR(s.infeed->infeed_m(1.0), 10e-6, 1e-15);
    }
  }
  SimulationSettings no_feed;
  VariableSpeed feed(parameters(ModulationShape::sinusoidal, 0.1, 1.0, SuppressionTarget::feed));
  EXPECT_THROW(apply_modulation(feed.target(), feed.law(1.0), model, no_feed), std::invalid_argument);
}

TEST(VariableSpeed, TheEngineFollowsAnInfeedLaw) {
  // SimulationSettings::infeed: the model sees u(t) and du/dt of the law (recorded infeed_m).
  TwoRotors model;
  VariableSpeed feed(parameters(ModulationShape::square, 0.4, 5.0, SuppressionTarget::feed));
  SimulationSettings s;
  s.duration_s = 0.5;
  s.sample_rate_hz = 1000.0;
  s.infeed_rate_m_per_s = 20e-6;
  apply_modulation(feed.target(), feed.law(s.duration_s), model, s);
  const SimulationResult r = simulate(model, s);
  ASSERT_EQ(r.infeed_m.size(), r.t_s.size());
  ASSERT_GT(r.t_s.size(), 400u);
  for (std::size_t i = 0; i < r.t_s.size(); ++i) EXPECT_EQ(r.infeed_m[i], s.infeed->infeed_m(r.t_s[i])) << i;
  // Square wave: 28 um/s for the first 0.1 s, then 12 um/s; over whole periods the mean rate.
  EXPECT_NEAR(s.infeed->infeed_m(0.1), 2.8e-6, 1e-15);
  EXPECT_NEAR(s.infeed->infeed_m(0.4), 8.0e-6, 1e-15);
}

TEST(VariableSpeed, TargetNamesRoundTrip) {
  for (SuppressionTarget t : {SuppressionTarget::wheel_speed, SuppressionTarget::work_speed, SuppressionTarget::feed})
    EXPECT_EQ(parse_suppression_target(to_string(t)), t);
  EXPECT_THROW(parse_suppression_target("spindle"), std::invalid_argument);
}

}  // namespace
}  // namespace chatterlab
