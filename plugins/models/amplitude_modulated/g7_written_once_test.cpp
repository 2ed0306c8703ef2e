// MODELS.md G7 written once (issue 17 item 5): the amplitude-modulated wheel-regenerative
// oscillator of floquet_growth.hpp as templated equations, its periodic linearisation taken by
// automatic differentiation (derived_model.hpp) and its Floquet growth by the framework's
// semi-discretisation of the delay-differential-algebraic system (floquet.hpp): an independent
// route against the hand-written G7 monodromy (floquet_growth.cpp).
//
// The delayed relative displacement mu x(t - Tg) is carried as the wheel "surface": its removal
// per revolution is mu x - S(t - Tg), so S(t) = mu x(t) and S(t - Tg) = mu x(t - Tg).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/floquet.hpp"
#include "models/amplitude_modulated/floquet_growth.hpp"

namespace chatterlab {
namespace {

struct G7Equations {
  AmplitudeModulatedParameters p;

  std::size_t state_size() const { return 2; }
  bool regenerates(Rotor r) const { return r == Rotor::wheel; }
  double nominal_speed_rpm(Rotor r) const { return r == Rotor::wheel ? p.wheel_speed_rpm : 60.0; }
  double displacement_m(std::span<const double> x) const { return x[0]; }
  // F_p = -kg b g (x - mu x(t - Tg)), x = x1 + F_p/(kc b), g = 1 + Q sin(wheel angle).
  template <class S>
  void contact(const ContactInputOf<S>& in, ContactOutputOf<S>& out) const {
    using std::sin;
    const auto wheel = static_cast<std::size_t>(Rotor::wheel);
    const double g = 1.0 + p.modulation_depth * sin(in.angle_rad[wheel]);
    const double kg = p.grinding_stiffness_n_per_m, kc = p.contact_stiffness_n_per_m;
    const S previous = in.previous_surface_m[wheel];
    const S force = -kg * g * (in.state[0] - previous) / (1.0 + kg / kc * g);
    const S x = in.state[0] + force / kc;
    out.normal_force_n = force;
    out.removed_m[wheel] = p.overlap_factor * x - previous;
  }
  template <class S>
  void derivatives(const ContactInputOf<S>& in, const ContactOutputOf<S>& c, std::span<S> dx) const {
    dx[0] = in.state[1];
    dx[1] = (c.normal_force_n - p.damping_n_s_per_m * in.state[1] - p.stiffness_n_per_m * in.state[0]) / p.mass_kg;
  }
};

class G7Linearisation final : public LinearisedModel {
 public:
  explicit G7Linearisation(AmplitudeModulatedParameters p) : eqs_{p} {}
  SurfaceLayout surface_layout() const override {
    return derived_detail::layout_of(2, true, false, eqs_.p.wheel_speed_rpm, 60.0);
  }
  JacobianMatrix jacobian(const ProcessPoint& point) const override {
    return derived_detail::jacobian(eqs_, surface_layout(), point);
  }

 private:
  G7Equations eqs_;
};

// floquet_growth_test.cpp's base case: 20 kg, 5e7 N/m, 10 % damping, kc 1e8, 1450 rpm.
AmplitudeModulatedParameters base() {
  AmplitudeModulatedParameters p;
  p.mass_kg = 20.0;
  p.stiffness_n_per_m = 5e7;
  p.damping_n_s_per_m = 0.1 * std::sqrt(5e7 * 20.0);
  p.grinding_stiffness_n_per_m = 2e7;
  p.contact_stiffness_n_per_m = 1e8;
  p.overlap_factor = 1.0;
  p.modulation_depth = 0.0;
  p.wheel_speed_rpm = 1450.0;
  return p;
}

TEST(G7WrittenOnceAccuracy, FloquetOfTheDerivedLinearisationEqualsTheHandWrittenMonodromy) {
  struct Case {
    double depth, overlap, grinding;
  };
  for (const Case c : {Case{0.0, 1.0, 2e7}, Case{0.05, 1.0, 2e7}, Case{0.1, 1.0, 2e7}, Case{0.2, 1.0, 2e7},
                       Case{0.1, 0.8, 3e7}}) {
    AmplitudeModulatedParameters p = base();
    p.modulation_depth = c.depth;
    p.overlap_factor = c.overlap;
    p.grinding_stiffness_n_per_m = c.grinding;
    const G7Linearisation model(p);
    PeriodicProcess process;  // constant speeds; the modulation follows the wheel angle
    process.period_s = 60.0 / p.wheel_speed_rpm;
    const FloquetResult derived = floquet_growth_rate(*periodic_surface_system(model, process));
    const auto hand = floquet_growth(p);
    std::printf("Q %.2f mu %.1f kg %.0e: derived %.6f (error %.1e) hand-written %.6f 1/s\n", c.depth, c.overlap,
                c.grinding, derived.growth_rate_per_s, derived.growth_rate_error_per_s, hand.growth_rate_per_s);
    ASSERT_TRUE(derived.converged);
    ASSERT_TRUE(hand.converged);
    // Both within their tolerances (1e-3 1/s plus relative parts): 3e-3 1/s + 1e-3 |sigma|.
    EXPECT_NEAR(derived.growth_rate_per_s, hand.growth_rate_per_s, 3e-3 + 1e-3 * std::abs(hand.growth_rate_per_s));
  }
}

}  // namespace
}  // namespace chatterlab
