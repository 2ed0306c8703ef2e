// MODELS.md G7 written once (issue 17 item 5): the plugin's templated equations
// (AmplitudeModulatedEquations), their periodic linearisation taken by automatic differentiation
// (derived_model.hpp) and its Floquet growth by the framework's semi-discretisation of the
// delay-differential-algebraic system (floquet.hpp), over the plugin's coefficient period: an
// independent route against the hand-written G7 monodromy (floquet_growth.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/floquet.hpp"
#include "models/amplitude_modulated/amplitude_modulated.hpp"
#include "models/amplitude_modulated/floquet_growth.hpp"
#include "models/amplitude_modulated/g7_test_case.hpp"

namespace chatterlab {
namespace {

TEST(G7WrittenOnceAccuracy, FloquetOfTheDerivedLinearisationEqualsTheHandWrittenMonodromy) {
  struct Case {
    double depth, overlap, grinding;
  };
  for (const Case c : {Case{0.0, 1.0, 2e7}, Case{0.05, 1.0, 2e7}, Case{0.1, 1.0, 2e7}, Case{0.2, 1.0, 2e7},
                       Case{0.1, 0.8, 3e7}}) {
    AmplitudeModulatedParameters p = testing::g7_base_case();
    p.modulation_depth = c.depth;
    p.overlap_factor = c.overlap;
    p.grinding_stiffness_n_per_m = c.grinding;
    // The same oscillator in the plugin's modal parameters (m = k/w^2, c = 2 zeta sqrt(k m)).
    AmplitudeModulatedModalParameters modal;
    modal.frequency_hz = std::sqrt(p.stiffness_n_per_m / p.mass_kg) / (2.0 * std::numbers::pi);
    modal.damping_ratio = p.damping_n_s_per_m / (2.0 * std::sqrt(p.stiffness_n_per_m * p.mass_kg));
    modal.stiffness_n_per_m = p.stiffness_n_per_m;
    modal.grinding_stiffness_n_per_m = p.grinding_stiffness_n_per_m;
    modal.contact_stiffness_n_per_m = p.contact_stiffness_n_per_m;
    modal.overlap_factor = p.overlap_factor;
    modal.modulation_depth = p.modulation_depth;
    modal.wheel_speed_rpm = p.wheel_speed_rpm;
    const AmplitudeModulated model(modal);
    PeriodicProcess process;  // constant speeds; the modulation follows the wheel angle
    process.period_s = *model.coefficient_period_s();
    EXPECT_NEAR(process.period_s, 60.0 / p.wheel_speed_rpm, 1e-15);
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
