// The `simulate` study kind on the kit: its [simulation] table (the user-visible keys), the
// validated document (defaults written back, idempotent), the engine settings it runs with, the
// profile-quality analysis chosen by capability, and a short G1 run against its certified root.
#include "study_kinds/simulate/simulate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "chatterlab/kit/capabilities.hpp"
#include "chatterlab/study.hpp"
#include "study_kinds/simulate/simulate_point.hpp"
#include "unit/g1_test_machines.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;

const std::string g1_study = "[study]\nkind = \"simulate\"\n" +
                             testing::model_table_toml("plunge_regenerative", testing::g1_reference_machine) + R"([simulation]
duration_s = 2.5
sample_rate_hz = 10000
one_sided_contact = false
initial_waviness_m = 1e-9
)";

TEST(Simulate, TheSimulationTableKeepsTheUserVisibleKeys) {
  std::vector<std::string> keys;
  for (const ParamSpec& spec : Simulate::info().params) keys.push_back(spec.key);
  for (const char* key : {"duration_s", "sample_rate_hz", "initial_displacement_m", "initial_velocity_m_per_s",
                          "initial_waviness_m", "seed", "infeed_rate_m_per_s", "one_sided_contact",
                          "wheel_contact_arc_deg", "work_contact_arc_deg", "snapshot_times_s", "fit_start_s",
                          "fit_end_s", "relative_tolerance", "integrator", "fixed_steps_per_wave", "min_frequency_hz",
                          "divergence_limit_m", "timeseries_format", "timeseries_decimation",
                          "measurement_noise_m", "write_point_files", "wheel_speed_modulation",
                          "wheel_speed_amplitude_ratio", "wheel_speed_frequency_hz", "wheel_speed_schedule",
                          "work_speed_modulation", "work_speed_amplitude_ratio", "work_speed_frequency_hz",
                          "work_speed_schedule"})
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
  EXPECT_EQ(keys.size(), 30u);
}

TEST(Simulate, ValidationWritesTheDefaultsAndIsIdempotent) {
  TempDir dir;
  const Study study = load_study(dir.write("g1.toml", g1_study));
  const Json& sim = study.document.at("simulation");
  EXPECT_EQ(sim.at("snapshot_times_s"), Json::array({2.5}));  // the end
  EXPECT_EQ(sim.at("relative_tolerance"), Json(1e-6));
  EXPECT_EQ(sim.at("divergence_limit_m"), Json(0.01));
  EXPECT_EQ(sim.at("integrator"), Json("fixed_step"));
  EXPECT_EQ(sim.at("fixed_steps_per_wave"), Json(0.0));
  EXPECT_EQ(sim.at("timeseries_format"), Json("csv"));
  EXPECT_EQ(sim.at("timeseries_decimation"), Json(1));
  Json again = study.document;
  auto kind = study_kind_registry().at("simulate").create(ParamValues{});
  struct Nowhere final : SourceMap {
    SourceLocation locate(std::string_view) const override { return {}; }
  };
  kind->validate(again, Nowhere());
  EXPECT_EQ(again, study.document);
}

TEST(Simulate, ThePartQualityComesFromTheAnalysisWithTheCapability) {
  const auto found = kit::plugins_with(analysis_registry(), &Analysis::profile_quality);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found.front()->info.name, "surface_profile");
  EXPECT_EQ(simulate_point::profile_quality_analysis(), found.front());
}

TEST(Simulate, ALinearG1RunGrowsAtTheCertifiedRoot) {
  // docs/models/plunge_regenerative.md: the certified rightmost root of this machine is
  // 4.790137 /s at 361.7148 Hz; bilateral contact keeps the run linear (the default fixed-step
  // engine propagates G1's linear form exactly, docs/dynamics.md). 2.5 s: the default fit window
  // [1.25, 2.5] s spans more than one work revolution (1.09 s), as a valid fit needs.
  TempDir dir;
  const Study study = load_study(dir.write("g1.toml", g1_study));
  auto kind = study_kind_registry().at("simulate").create(ParamValues{});
  const std::vector<Json> row = kind->run_point(study.point_document(0), PointContext{});
  ASSERT_EQ(row.size(), 11u);
  EXPECT_NEAR(row[0].get<double>(), 4.790137, 0.01 * 4.790137);  // fitted growth rate
  EXPECT_EQ(row[1], Json(true)) << row[3];                        // ... and the fit is valid
  EXPECT_NEAR(row[4].get<double>(), 361.7148, 2.0);               // dominant frequency (spectral resolution)
  EXPECT_EQ(row[6].get<double>(), 0.0);                           // never out of contact
  EXPECT_EQ(row[7], Json("completed"));
  EXPECT_TRUE(row[8].is_number());  // the work surface's Wt was measured  // the work surface's Wt was measured
}

}  // namespace
}  // namespace chatterlab

// The unrolled work surface of a plunge: a revolution's infeed as one ramp with its step where
// the wheel cuts now, plus chatter waves. The ramp removal returns the waves and the rise.
TEST(SimulateSurfacePlot, InfeedRampIsRemovedAndItsRiseReported) {
  const std::size_t n = 3600, step = 1234;
  const double rise_m = 16.4e-6, wave_m = 2e-6;
  std::vector<double> removal(n), waves(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double u = static_cast<double>((i + n - step) % n) / static_cast<double>(n);  // 0 just after the cut
    waves[i] = wave_m * std::sin(2.0 * std::numbers::pi * 37.0 * static_cast<double>(i) / static_cast<double>(n));
    removal[i] = 5e-6 + rise_m * u + waves[i];
  }
  const chatterlab::simulate_point::Deramped d = chatterlab::simulate_point::without_infeed_ramp(removal);
  EXPECT_NEAR(d.rise_per_revolution, rise_m, 0.01 * rise_m);
  double worst = 0.0;
  for (std::size_t i = 0; i < n; ++i) worst = std::max(worst, std::abs(d.values[i] - waves[i]));
  EXPECT_LT(worst, 0.05 * wave_m);

  // Waves alone (a wheel that hardly wears): no ramp is invented.
  const chatterlab::simulate_point::Deramped none = chatterlab::simulate_point::without_infeed_ramp(waves);
  EXPECT_EQ(none.rise_per_revolution, 0.0);
  for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(none.values[i], waves[i], 1e-3 * wave_m);
}
