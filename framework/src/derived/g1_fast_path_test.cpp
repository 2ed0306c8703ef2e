// The hand-written fast path of MODELS.md G1 (plunge_regenerative's PlungeCharacteristic, eq 2-16
// factored by hand) against the derived route (the same physics written once as time-domain
// equations, derived_model.hpp: Jacobian by automatic differentiation, characteristic matrix of
// the delay-differential-algebraic system, delay_system.hpp). On random valid parameter sets
// (wheel and/or work regeneration, one to three modes) the two certified rightmost roots agree to
// 1e-9 relative and E(s) agrees up to a constant factor.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "chatterlab/derived_model.hpp"
#include "chatterlab/roots.hpp"
#include "derived/g1_written_once.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"
#include "unit/random_g1_machines.hpp"

namespace chatterlab {
namespace {

using test_support::G1Equations;

class G1Model final : public DerivedModel<G1Equations> {
 public:
  using DerivedModel::DerivedModel;
};

G1Equations written_once(const PlungeRegenerativeParameters& p) {
  G1Equations eqs;
  eqs.kc = p.contact_stiffness_n_per_m;
  eqs.kg = p.wheel_wear_stiffness_n_per_m;
  eqs.kw = p.work_removal_stiffness_n_per_m;
  eqs.wheel_rpm = p.wheel_speed_rpm;
  eqs.work_rpm = p.work_speed_rpm;
  eqs.wheel = p.wheel_regeneration;
  eqs.work = p.work_regeneration;
  eqs.modes.clear();
  for (const StructuralMode& m : p.modes) eqs.modes.push_back({m.frequency_hz, m.damping_ratio, m.stiffness_n_per_m});
  return eqs;
}

TEST(DerivedFastPath, PlungeRegenerativeOnFiftyRandomParameterSets) {
  testing::RandomG1Machines random(17);
  double worst_root = 0.0, worst_ratio = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    PlungeRegenerativeParameters p = random.machine(1000.0, 3000.0, 30.0, 200.0, 1e10);
    p.wheel_regeneration = trial % 3 != 1;
    p.work_regeneration = trial % 3 != 0;
    const int modes = 1 + trial % 3;
    for (int m = 0; m < modes; ++m) p.modes.push_back(random.mode(60.0, 500.0));
    SCOPED_TRACE(::testing::Message() << "trial " << trial);

    const PlungeRegenerative fast(p);
    const G1Model derived(written_once(p));
    const auto e_fast = fast.characteristic();
    const auto e_derived = derived.derived_characteristic();

    // E(s) up to a constant factor, away from the zeros.
    std::optional<Complex> ratio;
    for (int i = 0; i < 8; ++i) {
      const Complex s(random.uniform(-30.0, 20.0), random.uniform(10.0, 2.0 * std::numbers::pi * 700.0));
      const Complex reference = e_fast->evaluate(s).value;
      const Complex value = e_derived->evaluate(s).value / reference;
      if (!ratio) ratio = value;
      const double deviation = std::abs(value / *ratio - 1.0);
      worst_ratio = std::max(worst_ratio, deviation);
      EXPECT_LE(deviation, 1e-9) << "s = " << s;
    }

    RootSearchOptions options;
    options.max_frequency_hz = 700.0;
    const RightmostRoot r_fast = find_rightmost_root(*e_fast, options);
    const RightmostRoot r_derived = find_rightmost_root(*e_derived, options);
    ASSERT_TRUE(r_fast.certified) << r_fast.certificate;
    ASSERT_TRUE(r_derived.certified) << r_derived.certificate;
    const double relative = std::abs(r_derived.root - r_fast.root) / std::abs(r_fast.root);
    worst_root = std::max(worst_root, relative);
    EXPECT_LE(relative, 1e-9) << "fast " << r_fast.root << ", derived " << r_derived.root;
  }
  RecordProperty("worst_root_relative_difference", std::to_string(worst_root));
  RecordProperty("worst_characteristic_ratio_deviation", std::to_string(worst_ratio));
  std::printf("worst root relative difference %.3g, worst E ratio deviation %.3g\n", worst_root, worst_ratio);
}

}  // namespace
}  // namespace chatterlab
