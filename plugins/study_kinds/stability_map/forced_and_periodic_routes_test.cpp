// stability_map on the models written once for issue 17 item 5: G6 (unbalance_two_dof: the
// unbalance is an additive forcing, so the derived route gives the autonomous structure's certified
// rightmost root) and G7 (amplitude_modulated: coefficients periodic in the wheel angle, so the
// Floquet route over one wheel revolution). Known answers: G6's root against the eigenvalues of its
// 4 x 4 state matrix typed in here; G7 without modulation against the certified root of the same
// linearisation; refusals with their messages. StabilityMapRoutesAccuracy: each route's growth rate
// against the growth rate the `simulate` kind fits to a bilateral simulation of the same [model]
// (2 %, three points per model).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "chatterlab/kit.hpp"
#include "chatterlab/linearised_model.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;

// One grid point of `kind` on the study text: column name -> value.
std::map<std::string, Json> run(const TempDir& dir, const std::string& kind, const std::string& body) {
  const Study study = load_study(dir.write("study.toml", "[study]\nkind = \"" + kind + "\"\n" + body));
  const auto instance = study_kind_registry().at(kind).create(ParamValues(Json::object()));
  const std::vector<std::string> columns = instance->output_columns(study.document);
  const std::vector<Json> values = instance->run_point(study.point_document(0), {});
  std::map<std::string, Json> out;
  for (std::size_t c = 0; c < columns.size(); ++c) out[columns[c]] = values.at(c);
  return out;
}

// G6 with the example's structure (plugin info), wheel damping c1 and unbalance U; work at 1200 rpm
// so that a work revolution (the engine's longest delay, which a valid fit window must exceed) is 0.05 s.
std::string g6_model(double wheel_damping_n_s_per_m, double unbalance_kg_m) {
  return "[model]\ntype = \"unbalance_two_dof\"\nmass_1_kg = 60.0\ndamping_1_n_s_per_m = " +
         std::to_string(wheel_damping_n_s_per_m) +
         "\nstiffness_1_n_per_m = 5.0e7\nmass_2_kg = 20.0\ndamping_2_n_s_per_m = 3000.0\n"
         "stiffness_2_n_per_m = 3.0e7\ncontact_stiffness_n_per_m = 1.0e8\nwheel_wear_stiffness_n_per_m = 1.0e9\n"
         "unbalance_kg_m = " +
         std::to_string(unbalance_kg_m) + "\nwheel_speed_rpm = 1450.0\nwork_speed_rpm = 1200.0\n";
}

// G7 as studies/simulate_g7_sidebands.toml with grinding stiffness kg b and modulation depth Q. Its
// 55 rpm work is reported only (G7 regenerates the wheel alone), so the simulate kind's fit window
// waits for a wheel revolution, not for the work's 1.09 s.
std::string g7_model(double grinding_stiffness_n_per_m, double depth) {
  return "[model]\ntype = \"amplitude_modulated\"\nfrequency_hz = 800.0\ndamping_ratio = 0.05\n"
         "stiffness_n_per_m = 5.0e7\ngrinding_stiffness_n_per_m = " +
         std::to_string(grinding_stiffness_n_per_m) +
         "\ncontact_stiffness_n_per_m = 1.0e8\nmodulation_depth = " + std::to_string(depth) +
         "\nwheel_speed_rpm = 1450\nwork_speed_rpm = 55\n";
}

// The rightmost eigenvalue's real part of G6's structure, typed in from MODELS.md G6.
double g6_rightmost_eigenvalue(double c1) {
  const double m1 = 60, k1 = 5e7, m2 = 20, c2 = 3000, k2 = 3e7, k = 1e8 * 1e9 / (1e8 + 1e9);
  Eigen::MatrixXd a(4, 4);
  a << 0, 1, 0, 0, -(k + k1) / m1, -c1 / m1, -k / m1, 0, 0, 0, 0, 1, -k / m2, 0, -(k + k2) / m2, -c2 / m2;
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(a, false);
  const Eigen::VectorXcd lambdas = solver.eigenvalues();
  double best = -INFINITY;
  for (Eigen::Index i = 0; i < lambdas.size(); ++i) best = std::max(best, lambdas[i].real());
  return best;
}

TEST(StabilityMapRoutes, G6TakesTheDerivedRouteWithACertifiedRoot) {
  TempDir dir;
  for (double c1 : {6000.0, 600.0}) {
    const auto row = run(dir, "stability_map", g6_model(c1, 4.2e-4));
    EXPECT_EQ(row.at("route"), "derived");
    EXPECT_EQ(row.at("certified"), true);
    EXPECT_EQ(row.at("stable"), true);
    // The unbalance is additive: the root is the structure's, whatever U.
    EXPECT_NEAR(row.at("growth_rate_per_s").get<double>(), g6_rightmost_eigenvalue(c1), 1e-9 * 55.0);
    // The G6 closed forms beside the root: the lightly damped root sits near an undamped natural frequency.
    const double f = row.at("chatter_frequency_hz").get<double>();
    const double f1 = row.at("natural_frequency_1_hz").get<double>(), f2 = row.at("natural_frequency_2_hz").get<double>();
    EXPECT_LT(std::min(std::abs(f - f1) / f1, std::abs(f - f2) / f2), 0.01) << f << " " << f1 << " " << f2;
    EXPECT_GT(row.at("forced_amplitude_m").get<double>(), 0.0);
  }
}

// A Floquet point (a monodromy of dimension ~1100-2200): in the accuracy suite.
TEST(StabilityMapRoutesAccuracy, G7WithoutModulationEqualsTheCertifiedRoot) {
  TempDir dir;
  // Q = 0: the coefficients are constant, the Floquet growth rate is the certified root of the
  // same linearisation (derived_characteristic of the model written once).
  const auto plain = run(dir, "stability_map", g7_model(6.5e6, 0.0));
  const Json table = Json::parse(R"({"type": "amplitude_modulated", "frequency_hz": 800.0, "damping_ratio": 0.05,
      "stiffness_n_per_m": 5.0e7, "grinding_stiffness_n_per_m": 6.5e6, "contact_stiffness_n_per_m": 1.0e8,
      "modulation_depth": 0.0, "wheel_speed_rpm": 1450})");
  const auto model = kit::build_model(table);
  ASSERT_NE(model->linearised(), nullptr);
  EXPECT_EQ(model->characteristic(), nullptr);  // periodic coefficients: no autonomous root
  RootSearchOptions options;
  options.max_frequency_hz = 3200.0;
  const RightmostRoot root = find_rightmost_root(*derived_characteristic(*model->linearised()), options);
  ASSERT_TRUE(root.certified);
  EXPECT_NEAR(plain.at("growth_rate_per_s").get<double>(), root.root.real(), 1e-3 + 1e-3 * std::abs(root.root.real()));
  EXPECT_EQ(plain.at("route"), "floquet");
  std::printf("G7 kg b 6.5e6 Q 0: Floquet %.5f, certified root %.5f 1/s\n", plain.at("growth_rate_per_s").get<double>(),
              root.root.real());
}

TEST(StabilityMapRoutes, G7WithASpeedModulationIsRefused) {
  TempDir dir;
  const std::string message = testing::input_error_of([&] {
    load_study(dir.write("study.toml", "[study]\nkind = \"stability_map\"\n" + g7_model(6.5e6, 0.3) +
                                           "[suppression]\ntype = \"variable_speed\"\ntarget = \"wheel_speed\"\n"
                                           "shape = \"sinusoidal\"\namplitude_ratio = 0.05\nfrequency_hz = 2.0\n"));
  });
  EXPECT_NE(message.find("study.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("[suppression]: model.type = \"amplitude_modulated\" has coefficients that repeat once per "
                         "0.04138 s"),
            std::string::npos)
      << message;
}

// A wheel so slow that one revolution, resolved at the 800 Hz mode, exceeds the monodromy limit.
TEST(StabilityMapRoutes, G7BeyondTheDiscretisationLimitIsRefused) {
  TempDir dir;
  std::string model = g7_model(6.5e6, 0.3);
  model.replace(model.find("wheel_speed_rpm = 1450"), 22, "wheel_speed_rpm = 100");
  const std::string message = testing::input_error_of(
      [&] { load_study(dir.write("study.toml", "[study]\nkind = \"stability_map\"\n" + model)); });
  EXPECT_NE(message.find("study.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("model.type = \"amplitude_modulated\": its Floquet route over one coefficient period: the "
                         "longest revolution (0.6 s)"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("> 3000"), std::string::npos) << message;
}

// ------------------------------------------------------------------ against simulation

// The `simulate` kind's fitted growth rate of a bilateral run of the same [model].
double simulated_growth(const TempDir& dir, const std::string& model, const std::string& simulation) {
  const auto row = run(dir, "simulate", model + "[simulation]\none_sided_contact = false\n" + simulation);
  EXPECT_EQ(row.at("fit_valid"), true) << row.at("fit_reason");
  EXPECT_EQ(row.at("contact_loss_fraction"), 0.0);
  return row.at("fitted_growth_rate_per_s").get<double>();
}

// G6 free decay (U = 0, started from 1 um): the slower mode's decay rate against the certified
// root, at three wheel dampings, fitted from 0.5 s (the faster mode has died away) over 5.5 / |root|
// (2.4 decades: the fit removes a least-squares line from the window, which a window spanning
// many decades would turn into the floor of its smallest samples).
TEST(StabilityMapRoutesAccuracy, G6RootAgreesWithSimulatedDecay) {
  TempDir dir;
  for (double c1 : {6000.0, 2000.0, 600.0}) {
    const double root = run(dir, "stability_map", g6_model(c1, 0.0)).at("growth_rate_per_s").get<double>();
    const double end_s = 0.5 + 5.5 / std::abs(root);
    const double simulated = simulated_growth(
        dir, g6_model(c1, 0.0),
        "duration_s = " + std::to_string(end_s) +
            "\nsample_rate_hz = 20000\ninitial_displacement_m = 1.0e-6\nfit_start_s = 0.5\nfit_end_s = " +
            std::to_string(end_s) + "\n");
    std::printf("G6 c1 %.0f N s/m: root %.5f simulated %.5f 1/s (%.3f %%)\n", c1, root, simulated,
                100.0 * (simulated / root - 1.0));
    EXPECT_NEAR(simulated, root, 0.02 * std::abs(root));
  }
}

// G7: the Floquet growth rate against the simulated one (fit over 1..3 s = 48 wheel periods, so the
// beat with the wheel period averages out), chattering and decaying. Deeper modulation or a
// stronger chain (Q 0.4, or kg b 8e6 at Q 0.15) makes the envelope pulse once per wheel revolution
// or two multipliers beat, and the simulate kind marks its fit invalid: such points are left out.
TEST(StabilityMapRoutesAccuracy, G7FloquetAgreesWithSimulatedGrowth) {
  TempDir dir;
  struct Point {
    double grinding, depth;
  };
  for (const Point p : {Point{6.5e6, 0.3}, Point{7.0e6, 0.2}, Point{5.0e6, 0.2}}) {
    const auto row = run(dir, "stability_map", g7_model(p.grinding, p.depth));
    ASSERT_EQ(row.at("floquet_converged"), true);
    EXPECT_EQ(row.at("route"), "floquet");
    EXPECT_NEAR(row.at("floquet_period_s").get<double>(), 60.0 / 1450.0, 1e-12);
    EXPECT_EQ(row.count("constant_speed_growth_rate_per_s"), 0u);  // no [suppression] comparison
    const double floquet = row.at("growth_rate_per_s").get<double>();
    const double simulated = simulated_growth(
        dir, g7_model(p.grinding, p.depth),
        "duration_s = 3.0\nsample_rate_hz = 8000\ninitial_displacement_m = 1.0e-8\nmin_frequency_hz = 100\n"
        "fit_start_s = 1.0\nfit_end_s = 3.0\n");
    std::printf("G7 kg b %.2g Q %.2f: Floquet %.5f simulated %.5f 1/s (%.3f %%)\n", p.grinding, p.depth, floquet,
                simulated, 100.0 * (simulated / floquet - 1.0));
    EXPECT_NEAR(simulated, floquet, 0.02 * std::abs(floquet));
  }
}

}  // namespace
}  // namespace chatterlab
