// G1's linearisation (PlungeLinearisation, plunge_time_domain.hpp): the Jacobian that automatic
// differentiation takes of the contact law the simulations run, against the engine's hand-written
// linear form, and its derived characteristic function's rightmost root against the hand-written
// eq 2-16 (PlungeCharacteristic) on the reference case and the G8 grinder.
#include <gtest/gtest.h>

#include <cmath>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/roots.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"

namespace chatterlab {
namespace {

TEST(PlungeLinearisation, JacobianMatchesTheEnginesLinearForm) {
  const PlungeRegenerativeParameters p = g8_grinder();
  const PlungeLinearisation lin(p);
  const PlungeTimeDomain td(p);
  const SurfaceLayout layout = lin.surface_layout();
  ASSERT_EQ(layout.states, 14u);
  ASSERT_EQ(layout.regenerated.size(), 2u);
  const JacobianMatrix j = lin.jacobian({});
  const LinearForm form = *td.linear_form(0.0);
  const std::size_t n = layout.states;
  for (std::size_t r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < n; ++c)
      EXPECT_NEAR(j(r, c), form.contact_matrix[r * n + c], 1e-12 * std::abs(form.contact_matrix[r * n + c]) + 1e-300)
          << r << "," << c;
    // A surface one revolution ago enters like the forcing with the opposite sign.
    for (std::size_t k = 0; k < 2; ++k) EXPECT_NEAR(j(r, n + k), -form.contact_input[r], 1e-12 * std::abs(form.contact_input[r]));
  }
  // Removal per surface: F/kg and F/kw with F = k_series (U0 - Wg - Ww - x).
  const double series = 1.0 / (1.0 / p.contact_stiffness_n_per_m + 1.0 / p.wheel_wear_stiffness_n_per_m +
                               1.0 / p.work_removal_stiffness_n_per_m);
  EXPECT_NEAR(j(n, n), -series / p.wheel_wear_stiffness_n_per_m, 1e-15);
  EXPECT_NEAR(j(n + 1, n + 1), -series / p.work_removal_stiffness_n_per_m, 1e-15);
  EXPECT_NEAR(j(n + 1, 0), -series / p.work_removal_stiffness_n_per_m, 1e-15);
}

TEST(PlungeLinearisation, DerivedRootEqualsTheHandWrittenRoot) {
  for (const PlungeRegenerativeParameters& p : {reference_g1_case(), g8_grinder()}) {
    const PlungeRegenerative model(p);
    ASSERT_NE(model.linearised(), nullptr);
    RootSearchOptions options;
    options.max_frequency_hz = 1500.0;
    const RightmostRoot fast = find_rightmost_root(*model.characteristic(), options);
    const RightmostRoot derived = find_rightmost_root(*derived_characteristic(*model.linearised()), options);
    ASSERT_TRUE(fast.certified);
    ASSERT_TRUE(derived.certified);
    EXPECT_NEAR(derived.root.real(), fast.root.real(), 1e-9 * std::abs(fast.root));
    EXPECT_NEAR(derived.root.imag(), fast.root.imag(), 1e-9 * std::abs(fast.root));
  }
}

}  // namespace
}  // namespace chatterlab
