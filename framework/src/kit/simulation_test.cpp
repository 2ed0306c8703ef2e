// The study kit's simulation settings: the [simulation] table declared once (its keys, defaults
// and limits), turned into the engine's SimulationSettings, the checks beyond single keys with
// file, line, key, value and limit, and the parts reused with other defaults by another table.
#include "chatterlab/kit/simulation.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "chatterlab/kit/settings.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::testing {
namespace {

class LineNine final : public SourceMap {
 public:
  SourceLocation locate(std::string_view) const override { return {"s.toml", 9}; }
};

// A model whose wheel speed is a state (its law is the model's own) and whose work is not.
class Rotors final : public TimeDomainModel {
 public:
  std::size_t state_size() const override { return 3; }
  void initial_state(const Disturbance&, std::span<double> x) const override { x[0] = x[1] = x[2] = 0.0; }
  void state_scales(double d, std::span<double> s) const override { s[0] = s[1] = s[2] = d; }
  double highest_frequency_hz() const override { return 100.0; }
  bool regenerates(Rotor) const override { return false; }
  double nominal_speed_rpm(Rotor r) const override { return r == Rotor::wheel ? 1500.0 : 60.0; }
  std::optional<std::size_t> angle_state(Rotor r) const override {
    return r == Rotor::wheel ? std::optional<std::size_t>(2) : std::nullopt;
  }
  void contact(const ContactInput&, ContactOutput&) const override {}
  void derivatives(const ContactInput&, const ContactOutput&, std::span<double>) const override {}
  double displacement_m(std::span<const double> x) const override { return x[0]; }
};

kit::SimulationTable validated(Json table) {
  Json document{{"simulation", std::move(table)}};
  return kit::validate_settings(document, "simulation", kit::simulation_table(), LineNine());
}

TEST(KitSimulation, TheSimulationTableKeepsItsKeysAndDefaults) {
  std::vector<std::string> keys;
  for (const ParamSpec& spec : kit::simulation_table().specs()) keys.push_back(spec.key);
  const std::vector<std::string> expected{
      "duration_s", "sample_rate_hz", "initial_displacement_m", "initial_velocity_m_per_s", "initial_waviness_m",
      "seed", "infeed_rate_m_per_s", "one_sided_contact", "wheel_contact_arc_deg", "work_contact_arc_deg",
      "snapshot_times_s", "fit_start_s", "fit_end_s", "min_frequency_hz", "relative_tolerance", "integrator",
      "fixed_steps_per_wave", "divergence_limit_m", "wheel_speed_modulation", "wheel_speed_amplitude_ratio",
      "wheel_speed_frequency_hz", "wheel_speed_schedule", "work_speed_modulation", "work_speed_amplitude_ratio",
      "work_speed_frequency_hz", "work_speed_schedule"};
  EXPECT_EQ(keys, expected);
  const kit::SimulationTable t = validated({{"duration_s", 0.5}});
  EXPECT_EQ(t.sample_rate_hz, 20000.0);
  EXPECT_EQ(t.disturbance.initial_displacement_m, 1e-6);
  EXPECT_FALSE(t.contact.one_sided_contact.has_value());  // absent: one-sided exactly with an infeed
  EXPECT_FALSE(kit::one_sided(t.contact));
  EXPECT_TRUE(kit::one_sided(kit::ContactSettings{1e-6, std::nullopt, 0.0, 0.0}));
  EXPECT_EQ(t.integration.relative_tolerance, 1e-6);
  EXPECT_EQ(t.integration.integrator, TimeIntegrator::fixed_step);  // the default route
  EXPECT_EQ(t.integration.fixed_steps_per_wave, 0.0);                // the engine's default steps
  EXPECT_EQ(t.integration.divergence_limit_m, 0.01);
  EXPECT_EQ(t.fit.min_frequency_hz, 10.0);
  EXPECT_EQ(t.wheel_speed.shape, kit::SpeedLawShape::constant);
  const kit::FitWindow w = kit::fit_window(t.fit, t.duration_s);
  EXPECT_EQ(w.start_s, 0.25);  // the second half by default
  EXPECT_EQ(w.end_s, 0.5);
}

TEST(KitSimulation, EngineSettingsCarryEveryPartAndTheSpeedLawsOfRotorsWithoutAngleState) {
  kit::SimulationTable t = validated({{"duration_s", 0.4},
                                      {"sample_rate_hz", 5000.0},
                                      {"initial_velocity_m_per_s", -2e-4},
                                      {"seed", 7},
                                      {"infeed_rate_m_per_s", 1e-5},
                                      {"one_sided_contact", false},
                                      {"work_contact_arc_deg", 2.5},
                                      {"relative_tolerance", 1e-5},
                                      {"integrator", "adams"},
                                      {"fixed_steps_per_wave", 25.0},
                                      {"work_speed_modulation", "sinusoidal"},
                                      {"work_speed_amplitude_ratio", 0.2},
                                      {"work_speed_frequency_hz", 0.5},
                                      {"wheel_speed_modulation", "square"},
                                      {"wheel_speed_amplitude_ratio", 0.1},
                                      {"wheel_speed_frequency_hz", 1.0}});
  Rotors model;
  kit::check_simulation(t, model, "simulation", LineNine());
  ASSERT_TRUE(t.snapshot_times_s.has_value());
  EXPECT_EQ(*t.snapshot_times_s, std::vector<double>{0.4});  // the end by default
  const SimulationSettings s = kit::simulation_settings(t, model);
  EXPECT_EQ(s.duration_s, 0.4);
  EXPECT_EQ(s.sample_rate_hz, 5000.0);
  EXPECT_EQ(s.disturbance.displacement_m, 1e-6);
  EXPECT_EQ(s.disturbance.velocity_m_per_s, -2e-4);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.infeed_rate_m_per_s, 1e-5);
  EXPECT_FALSE(s.one_sided_contact);
  EXPECT_EQ(s.contact_arc_deg[static_cast<std::size_t>(Rotor::work)], 2.5);
  EXPECT_EQ(s.relative_tolerance, 1e-5);
  EXPECT_EQ(s.integrator, TimeIntegrator::adams);
  EXPECT_EQ(s.fixed_steps_per_wave, 25.0);
  EXPECT_EQ(s.snapshot_times_s, std::vector<double>{0.4});
  // The wheel's speed is the model's state: no law; the work's law is the sine around 60 rpm.
  EXPECT_EQ(s.speed[static_cast<std::size_t>(Rotor::wheel)], nullptr);
  const auto& work = s.speed[static_cast<std::size_t>(Rotor::work)];
  ASSERT_NE(work, nullptr);
  EXPECT_NEAR(work->rpm(0.5), 60.0 * (1.0 + 0.2 * std::sin(2.0 * std::numbers::pi * 0.5 * 0.5)), 1e-9);
}

TEST(KitSimulation, ChecksBeyondSingleKeysNameFileLineKeyAndLimit) {
  Rotors model;
  auto message = [&](Json table) {
    return input_error_of([&] {
      kit::SimulationTable t = validated(std::move(table));
      kit::check_simulation(t, model, "simulation", LineNine());
    });
  };
  const std::string few = message({{"duration_s", 0.001}, {"sample_rate_hz", 1000.0}});
  EXPECT_NE(few.find("s.toml:9: simulation.duration_s = 0.001: only 1 output samples; at least 64"), std::string::npos)
      << few;
  const std::string many = message({{"duration_s", 6000.0}});
  EXPECT_NE(many.find("1.2e+08 output samples exceeds the limit of 5e+07"), std::string::npos) << many;
  const std::string snapshot = message({{"duration_s", 1.0}, {"snapshot_times_s", {0.5, 1.5}}});
  EXPECT_NE(snapshot.find("simulation.snapshot_times_s = 1.5: a time is beyond duration_s = 1"), std::string::npos)
      << snapshot;
  const std::string fit = message({{"duration_s", 1.0}, {"fit_start_s", 0.8}, {"fit_end_s", 0.6}});
  EXPECT_NE(fit.find("fit_start_s < fit_end_s <= duration_s = 1"), std::string::npos) << fit;
  const std::string schedule = message({{"duration_s", 1.0}, {"work_speed_modulation", "schedule"}});
  EXPECT_NE(schedule.find("simulation.work_speed_modulation = \"schedule\" needs work_speed_schedule"),
            std::string::npos) << schedule;
  const std::string rows = message(
      {{"duration_s", 1.0}, {"work_speed_modulation", "schedule"}, {"work_speed_schedule", {{0.0, 60.0, 1.0}}}});
  EXPECT_NE(rows.find("simulation.work_speed_schedule = [0.0,60.0,1.0]: each row must be [t_s, rpm]"),
            std::string::npos) << rows;
  const std::string frequency =
      message({{"duration_s", 1.0}, {"wheel_speed_modulation", "sinusoidal"}, {"wheel_speed_amplitude_ratio", 0.1}});
  EXPECT_NE(frequency.find("simulation.wheel_speed_frequency_hz = 0: a sinusoidal modulation"), std::string::npos)
      << frequency;
}

TEST(KitSimulation, AnotherTableEmbedsThePartsWithItsOwnDefaults) {
  // A kind whose runs are linear and coarse: bilateral contact and rtol 1e-4 by default.
  struct Mine {
    double revolutions = 40.0;
    kit::ContactSettings contact{0.0, false, 0.0, 0.0};
    kit::IntegratorSettings integration{1e-4, TimeIntegrator::explicit_runge_kutta, 1.0};
  };
  ParamTable<Mine> t;
  t.add(&Mine::revolutions, "revolutions", "1", "wheel revolutions").positive();
  t.add_fields(&Mine::contact, kit::contact_table());
  t.add_fields(&Mine::integration, kit::integrator_table());
  Json document = Json::object();
  const Mine m = kit::validate_settings(document, "mine", t, LineNine());
  EXPECT_EQ(m.contact.one_sided_contact, std::optional<bool>(false));
  EXPECT_EQ(document["mine"]["one_sided_contact"], Json(false));
  EXPECT_EQ(document["mine"]["relative_tolerance"], Json(1e-4));
  EXPECT_EQ(document["mine"]["divergence_limit_m"], Json(1.0));
  SimulationSettings s;
  kit::apply(m.integration, s);
  EXPECT_EQ(s.relative_tolerance, 1e-4);
  // The shared limits hold: rtol <= 1e-3.
  document["mine"]["relative_tolerance"] = 0.01;
  const std::string message = input_error_of([&] { kit::validate_settings(document, "mine", t, LineNine()); });
  EXPECT_NE(message.find("mine.relative_tolerance = 0.01"), std::string::npos) << message;
}

}  // namespace
}  // namespace chatterlab::testing
