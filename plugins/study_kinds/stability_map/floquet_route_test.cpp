// stability_map's Floquet route (floquet_route.hpp) on MODELS.md G1 with a modulated wheel or
// work speed (S2, S3): the constant-speed limit against the certified autonomous root, the
// refused shapes with their messages, and (FloquetRouteAccuracy) the Floquet growth rate against
// growth rates fitted from bilateral-contact simulations at three points per strategy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/suppression.hpp"
#include "study_kinds/stability_map/floquet_route.hpp"
#include "study_kinds/stability_map/stability_map.hpp"
#include "unit/g1_test_machines.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;

// studies/suppression_wheel_speed.toml's G3 case: wheel chain alone, 1450 rpm, 3.1 1/s at 290 Hz.
const std::string wheel_model = testing::g1_suppression_machine(1450.0, 60.0, 180.0, "work_regeneration = false\n");

// Work chain alone (S3). studies/suppression_work_speed.toml's work turns at 60 rpm: one work
// revolution (1 s) resolved at its 180 Hz mode needs a monodromy beyond the discretisation's
// limit (refused, tested below), so the Floquet checks take a work at 600 rpm with a 60 Hz mode
// (same stiffnesses): a revolution of 0.1 s.
const std::string work_model = testing::g1_suppression_machine(1500.0, 600.0, 60.0, "wheel_regeneration = false\n");

std::string suppression(const std::string& target, const std::string& shape, double amplitude, double frequency_hz) {
  return "[suppression]\ntype = \"variable_speed\"\ntarget = \"" + target + "\"\nshape = \"" + shape +
         "\"\namplitude_ratio = " + std::to_string(amplitude) + "\nfrequency_hz = " + std::to_string(frequency_hz) +
         "\n";
}

Study load(const TempDir& dir, const std::string& body) {
  return load_study(dir.write("study.toml", "[study]\nkind = \"stability_map\"\n" + body));
}

const StabilityMap kind;

std::map<std::string, Json> run(const Study& study) {
  const std::vector<std::string> columns = kind.output_columns(study.document);
  const std::vector<Json> values = kind.run_point(study.point_document(0), {});
  std::map<std::string, Json> out;
  for (std::size_t c = 0; c < columns.size(); ++c) out[columns[c]] = values.at(c);
  return out;
}

TEST(FloquetRoute, ColumnsSayWhichRoute) {
  TempDir dir;
  const Study floquet = load(dir, std::string(wheel_model) + suppression("wheel_speed", "sinusoidal", 0.05, 5.0));
  const auto row = run(floquet);
  EXPECT_EQ(row.at("route"), "floquet");
  EXPECT_EQ(row.at("floquet_converged"), true);
  EXPECT_NEAR(row.at("floquet_period_s").get<double>(), 0.2, 1e-12);
  EXPECT_EQ(row.at("stable"), row.at("growth_rate_per_s").get<double>() < 0.0);
  const Study plain = load(dir, wheel_model);
  EXPECT_EQ(run(plain).at("route"), "characteristic");
}

// The constant-speed limit: at amplitude 0 the periodic linearisation is autonomous, and ln|mu|/T
// over one revolution is the rightmost root's real part (certified by the characteristic route).
TEST(FloquetRoute, AmplitudeZeroEqualsTheAutonomousRoot) {
  TempDir dir;
  for (const auto& [model, target] : {std::pair{wheel_model, "wheel_speed"}, std::pair{work_model, "work_speed"}}) {
    SCOPED_TRACE(target);
    const auto row = run(load(dir, std::string(model) + suppression(target, "sinusoidal", 0.0, 1.0)));
    ASSERT_EQ(row.at("floquet_converged"), true);
    const double floquet = row.at("growth_rate_per_s").get<double>();
    const double root = row.at("constant_speed_growth_rate_per_s").get<double>();
    // The Floquet settings' tolerance: 1e-3 1/s + 1e-3 |growth|.
    EXPECT_NEAR(floquet, root, 1e-3 + 1e-3 * std::abs(root));
    EXPECT_LE(row.at("floquet_error_per_s").get<double>(), 1e-3 + 1e-3 * std::abs(root));
  }
}

TEST(FloquetRoute, ShapesWithoutAPeriodicLinearisationAreRefused) {
  TempDir dir;
  const std::string random = testing::input_error_of(
      [&] { load(dir, std::string(wheel_model) + suppression("wheel_speed", "random", 0.05, 5.0)); });
  EXPECT_NE(random.find("study.toml:"), std::string::npos) << random;
  EXPECT_NE(random.find("suppression.shape = \"random\": a random modulation is not periodic"), std::string::npos)
      << random;
  const std::string feed =
      testing::input_error_of([&] { load(dir, std::string(wheel_model) + suppression("feed", "sinusoidal", 0.05, 5.0)); });
  EXPECT_NE(feed.find("suppression.target = \"feed\": the Floquet route takes periodic rotor speeds"), std::string::npos)
      << feed;
  // The shipped S3 case: one work revolution of 1 s at 60 rpm.
  const std::string slow_work = testing::g1_suppression_machine(1500.0, 60.0, 180.0, "wheel_regeneration = false\n");
  const std::string large =
      testing::input_error_of([&] { load(dir, slow_work + suppression("work_speed", "sinusoidal", 0.05, 1.0)); });
  EXPECT_NE(large.find("suppression.target = \"work_speed\": the longest revolution"), std::string::npos) << large;
  EXPECT_NE(large.find("> 3000"), std::string::npos) << large;
  // A model without a linearisation (G4's penetration damping has a characteristic function only).
  std::string damped = wheel_model;
  damped.replace(damped.find("plunge_regenerative"), 19, "plunge_with_penetration_damping");
  damped += "penetration_damping_n_s_per_m = 1.0e4\n";
  const std::string unlinearised =
      testing::input_error_of([&] { load(dir, damped + suppression("wheel_speed", "sinusoidal", 0.05, 5.0)); });
  EXPECT_NE(unlinearised.find("model.type = \"plunge_with_penetration_damping\": a stability_map with [suppression]"),
            std::string::npos)
      << unlinearised;
}

// ------------------------------------------------------------------ against simulation

// The growth rate of a bilateral-contact simulation of the same model and modulation: the peak
// |x| of each modulation period (each holds hundreds of chatter waves, so the peak does not
// depend on the Floquet solution's phase), ln(peak) fitted by least squares over the periods in
// [fit_start_s, fit_end_s] (whole periods: the growth within a period varies with the speed).
double simulated_growth_rate(const Study& study, double fit_start_s, double fit_end_s) {
  const Json document = study.point_document(0);
  auto model = kit::build_model(document.at("model"));
  auto td = model->time_domain();
  Json params = document.at("suppression");
  params.erase("type");
  auto plugin = suppression_registry().at("variable_speed").create(ParamValues(std::move(params)));
  SimulationSettings s;
  s.duration_s = fit_end_s;
  s.sample_rate_hz = 20000.0;
  s.one_sided_contact = false;  // the linearisation
  s.disturbance = {1e-6, 0.0};
  s.divergence_limit_m = 1e30;
  apply_modulation(plugin->target(), plugin->law(fit_end_s), *td, s);
  const SimulationResult r = simulate(*td, s);
  EXPECT_EQ(r.status, "completed");
  const double period = plugin->modulation_period_s();
  std::vector<double> t, log_peak;
  for (double start = fit_start_s; start + period <= fit_end_s + 1e-9; start += period) {
    double peak = 0.0;
    for (std::size_t i = 0; i < r.t_s.size(); ++i)
      if (r.t_s[i] >= start && r.t_s[i] < start + period) peak = std::max(peak, std::abs(r.displacement_m[i]));
    t.push_back(start + 0.5 * period);
    log_peak.push_back(std::log(peak));
  }
  const double count = static_cast<double>(t.size());
  double mt = 0.0, my = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) mt += t[i] / count, my += log_peak[i] / count;
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) num += (t[i] - mt) * (log_peak[i] - my), den += (t[i] - mt) * (t[i] - mt);
  return num / den;
}

struct SimulationCase {
  std::string model;
  const char* target;
  double amplitude, frequency_hz;
  const char* shape = "sinusoidal";
};

// Three points per strategy (and one square wave each), the simulations fitted over the modulation periods in [3 s, 8 s]
// (the start-up transient gone). Tolerance 1 % (measured: at most 0.062 %, the square work-speed
// wave: 6.2732 against 6.2693 1/s; docs/derived_stability.md). Not every point is a
// quick check: at 10 % wheel-speed amplitude and 5-10 Hz a second Floquet mode grows almost as
// fast (the fitted rate still climbs from 1.17 to 1.52 1/s towards the Floquet 1.61 1/s over
// 1-8 s), so those points are left out (docs/derived_stability.md, "Floquet").
TEST(FloquetRouteAccuracy, AgreesWithSimulatedGrowthRates) {
  TempDir dir;
  for (const SimulationCase& c : {SimulationCase{wheel_model, "wheel_speed", 0.02, 5.0},
                                  SimulationCase{wheel_model, "wheel_speed", 0.05, 2.0},
                                  SimulationCase{wheel_model, "wheel_speed", 0.14, 1.0},
                                  SimulationCase{work_model, "work_speed", 0.05, 2.0},
                                  SimulationCase{work_model, "work_speed", 0.1, 5.0},
                                  SimulationCase{work_model, "work_speed", 0.2, 1.0},
                                  // Square waves: speed jumps, a kink in the revolution delay.
                                  SimulationCase{wheel_model, "wheel_speed", 0.05, 1.0, "square"},
                                  SimulationCase{work_model, "work_speed", 0.1, 2.0, "square"}}) {
    SCOPED_TRACE(std::string(c.shape) + " " + c.target + " amplitude " + std::to_string(c.amplitude) + " at " +
                 std::to_string(c.frequency_hz) + " Hz");
    const Study study = load(dir, std::string(c.model) + suppression(c.target, c.shape, c.amplitude, c.frequency_hz));
    const auto row = run(study);
    ASSERT_EQ(row.at("floquet_converged"), true);
    const double floquet = row.at("growth_rate_per_s").get<double>();
    const double simulated = simulated_growth_rate(study, 3.0, 8.0);
    std::printf("%s %s a %g f %g: Floquet %.5f simulated %.5f 1/s\n", c.shape, c.target, c.amplitude, c.frequency_hz,
                floquet, simulated);
    EXPECT_NEAR(floquet, simulated, 0.01 * std::abs(simulated))
        << "constant speed: " << row.at("constant_speed_growth_rate_per_s");
    // The modulation changes the growth (the check is not of the constant-speed limit).
    EXPECT_GT(std::abs(floquet - row.at("constant_speed_growth_rate_per_s").get<double>()), 0.05);
  }
}

}  // namespace
}  // namespace chatterlab
