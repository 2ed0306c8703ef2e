// The G1 process-condition rules (process_scaling.hpp) by hand: width, the G4 speed factors,
// S1's thickness factor, "not given" conditions, kd's G4 law; and the stiffness chain's
// switched-off chains.
#include "shared/plunge_dynamics/process_scaling.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>
#include <limits>
#include <numbers>

namespace chatterlab::plunge_dynamics {
namespace {

PlungeRegenerativeParameters own() {
  PlungeRegenerativeParameters p;
  p.wheel_speed_rpm = 1500.0;
  p.work_speed_rpm = 60.0;
  p.contact_stiffness_n_per_m = 1e8;
  p.wheel_wear_stiffness_n_per_m = 4e9;
  p.work_removal_stiffness_n_per_m = 5e7;
  p.modes = {{200.0, 0.05, 5e7}};
  return p;
}

TEST(PlungeProcessScaling, NothingGivenIsTheModelItself) {
  const PlungeRegenerativeParameters p = parameters_at(own(), {}, {}, ProcessScaling{});
  EXPECT_EQ(p.wheel_speed_rpm, 1500.0);
  EXPECT_EQ(p.work_speed_rpm, 60.0);
  EXPECT_EQ(p.contact_stiffness_n_per_m, 1e8);
  EXPECT_EQ(p.wheel_wear_stiffness_n_per_m, 4e9);
  EXPECT_EQ(p.work_removal_stiffness_n_per_m, 5e7);
  EXPECT_EQ(p.modes.size(), 1u);
  EXPECT_EQ(penetration_damping_factor(own(), {}, {}, ProcessScaling{}), 1.0);
  const ProcessConditions n = nominal_conditions(own());
  EXPECT_EQ(n.wheel_speed_rpm, 1500.0);
  EXPECT_EQ(n.work_speed_rpm, 60.0);
  EXPECT_EQ(n.contact_width_mm, 0.0);
}

TEST(PlungeProcessScaling, WidthScalesAllThreeAndSpeedsFollowG4) {
  // Work radius 50 mm at 60 rpm and a 400 mm wheel at 1500 rpm: v_w = pi 0.1 60/60 = 0.1 pi,
  // v_s = pi 0.4 1500/60 = 10 pi, Kv = 0.01. Doubling the work speed and the width:
  // kw = 2 kw0 (0.02/1.02)/(0.01/1.01), kg = 2 kg0 (1.01/1.02), kc = 2 kc0.
  const ProcessConditions reference{0.0, 0.0, 10.0, 50.0, 400.0};
  ProcessConditions at = reference;
  at.work_speed_rpm = 120.0;
  at.contact_width_mm = 20.0;
  const PlungeRegenerativeParameters p = parameters_at(own(), reference, at, ProcessScaling{});
  EXPECT_EQ(p.work_speed_rpm, 120.0);
  EXPECT_EQ(p.wheel_speed_rpm, 1500.0);  // not given: the model's
  EXPECT_DOUBLE_EQ(p.contact_stiffness_n_per_m, 2e8);
  EXPECT_NEAR(p.work_removal_stiffness_n_per_m, 1e8 * (0.02 / 1.02) / (0.01 / 1.01), 1e-6);
  EXPECT_NEAR(p.wheel_wear_stiffness_n_per_m, 8e9 * 1.01 / 1.02, 1e-3);
  // Width only: the speed factors are 1.
  ProcessScaling width_only;
  width_only.speed_dependent_stiffness = false;
  const PlungeRegenerativeParameters w = parameters_at(own(), reference, at, width_only);
  EXPECT_DOUBLE_EQ(w.work_removal_stiffness_n_per_m, 1e8);
  EXPECT_DOUBLE_EQ(w.wheel_wear_stiffness_n_per_m, 8e9);
  // Without a radius the speed ratio is unknown: the speed factors are 1 as well.
  ProcessConditions no_radius = at, no_radius_ref = reference;
  no_radius.work_radius_mm = no_radius_ref.work_radius_mm = 0.0;
  EXPECT_DOUBLE_EQ(parameters_at(own(), no_radius_ref, no_radius, ProcessScaling{}).work_removal_stiffness_n_per_m, 1e8);
}

TEST(PlungeProcessScaling, ThicknessFactorOfS1OnContactAndWear) {
  // Eq 5-29: k = k0 (1 - eps/2 da/a); 20 % deeper cut, eps = 0.6: factor 0.94 on kc and kg only.
  ProcessScaling scaling;
  scaling.thickness_exponent = 0.6;
  ProcessConditions at;
  at.depth_of_cut_ratio = 1.2;
  const PlungeRegenerativeParameters p = parameters_at(own(), {}, at, scaling);
  EXPECT_NEAR(p.contact_stiffness_n_per_m, 0.94e8, 1e-6);
  EXPECT_NEAR(p.wheel_wear_stiffness_n_per_m, 0.94 * 4e9, 1e-4);
  EXPECT_EQ(p.work_removal_stiffness_n_per_m, 5e7);
}

TEST(PlungeProcessScaling, PenetrationDampingFollowsRemovalContactLengthAndWorkSpeed) {
  // kd = ks sqrt(de u0)/v_w. Same geometry, twice the work speed, 1.44 x the depth of cut, width
  // only (kw unchanged): kd x sqrt(1.44)/2 = 0.6.
  ProcessScaling width_only;
  width_only.speed_dependent_stiffness = false;
  const ProcessConditions reference{0.0, 0.0, 0.0, 50.0, 400.0};
  ProcessConditions at = reference;
  at.work_speed_rpm = 120.0;
  at.depth_of_cut_ratio = 1.44;
  EXPECT_NEAR(penetration_damping_factor(own(), reference, at, width_only), 0.6, 1e-15);
  // A smaller part (radius 25 mm): de from 100*400/500 = 80 to 50*400/450 mm and v_w halves with it.
  at = reference;
  at.work_radius_mm = 25.0;
  EXPECT_NEAR(penetration_damping_factor(own(), reference, at, width_only),
              std::sqrt((50.0 * 400.0 / 450.0) / 80.0) * 2.0, 1e-14);
  // No radius: v_w ~ n_w (the same part).
  EXPECT_NEAR(penetration_damping_factor(own(), {}, ProcessConditions{0.0, 30.0}, width_only), 2.0, 1e-15);
}

// The typed parameter values (feed_risk groups 10^5 conditions by them) are bitwise the leaves of
// the parameter table a model writes, which the interface's default reads: the two routes group
// alike.
TEST(PlungeProcessScaling, ParameterValuesAreTheTableLeavesBitwise) {
  struct TableRoute final : ProcessConditionsModel {
    PlungeRegenerativeParameters parameters = own();
    ProcessConditions nominal_conditions() const override { return plunge_dynamics::nominal_conditions(parameters); }
    Json parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                       const ProcessScaling& scaling) const override {
      return plunge_parameters_table().write(plunge_dynamics::parameters_at(parameters, reference, conditions, scaling));
    }
  } model;
  model.parameters.modes.push_back({310.7, 0.031, 1.132e9});
  model.parameters.wheel_regeneration = false;
  const ProcessConditions reference{0.0, 0.0, 35.0, 50.0, 400.0};
  ProcessConditions at = reference;
  at.work_speed_rpm = 287.3;
  at.contact_width_mm = 2.137;
  at.work_radius_mm = 131.9;
  std::vector<double> from_table, typed;
  model.parameter_values_at(reference, at, ProcessScaling{}, from_table);
  parameter_values(plunge_dynamics::parameters_at(model.parameters, reference, at, ProcessScaling{}), typed);
  // The table's size, 5 numbers, the modes' count, each mode's size and 3 numbers, 2 switches.
  ASSERT_EQ(from_table.size(), 1u + 5u + 1u + 4u * 2u + 2u);
  ASSERT_EQ(typed.size(), from_table.size());
  for (std::size_t i = 0; i < typed.size(); ++i)
    EXPECT_EQ(std::bit_cast<std::uint64_t>(typed[i]), std::bit_cast<std::uint64_t>(from_table[i])) << "value " << i;
  EXPECT_EQ(typed[2], 287.3);
  EXPECT_EQ(typed[15], 0.0);  // wheel regeneration off
  EXPECT_EQ(typed[16], 1.0);
}

TEST(PlungeStiffnessChain, ChainsSwitchedOffAreInfinitelyStiff) {
  PlungeRegenerativeParameters p = own();
  p.work_regeneration = false;
  const StiffnessChain chain = stiffness_chain(p);
  EXPECT_EQ(chain.contact_stiffness_n_per_m, 1e8);
  EXPECT_EQ(chain.wheel_wear_stiffness_n_per_m, 4e9);
  EXPECT_EQ(chain.work_removal_stiffness_n_per_m, std::numeric_limits<double>::infinity());
  EXPECT_EQ(chain.penetration_damping_n_s_per_m, 0.0);
  ASSERT_EQ(chain.modes.size(), 1u);
  EXPECT_EQ(chain.modes[0].frequency_hz, 200.0);
  EXPECT_EQ(chain.modes[0].damping_ratio, 0.05);
  EXPECT_EQ(chain.modes[0].stiffness_n_per_m, 5e7);
}

}  // namespace
}  // namespace chatterlab::plunge_dynamics
