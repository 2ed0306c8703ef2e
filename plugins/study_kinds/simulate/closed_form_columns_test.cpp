// simulate's closed-form columns (closed_form_columns.hpp, issue 19): G6's forced amplitude (the
// damped 2 x 2 solve, unbalance_closed_form.hpp) beside the simulated steady amplitude where it
// applies (constant speeds, contact kept), null with the reason where it does not (a modulated
// wheel speed), and no columns for a model without such a closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "chatterlab/study.hpp"
#include "study_kinds/simulate/simulate.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;

// studies/simulate_g6_unbalance.toml's machine and unbalance (G8 wheel balanced to G6.3).
constexpr const char* g6 = R"([study]
kind = "simulate"
[model]
type = "unbalance_two_dof"
mass_1_kg = 60.0
damping_1_n_s_per_m = 6000.0
stiffness_1_n_per_m = 5.0e7
mass_2_kg = 20.0
damping_2_n_s_per_m = 3000.0
stiffness_2_n_per_m = 3.0e7
contact_stiffness_n_per_m = 1.0e8
wheel_wear_stiffness_n_per_m = 1.0e9
unbalance_kg_m = 4.2e-4
wheel_speed_rpm = WHEEL
work_speed_rpm = 58.0
[simulation]
duration_s = 1.0
sample_rate_hz = 20000
initial_displacement_m = 0.0
one_sided_contact = false
)";

std::string with_wheel(double rpm) {
  std::string text = g6;
  text.replace(text.find("WHEEL"), 5, std::to_string(rpm));
  return text;
}

const Simulate kind;

std::map<std::string, Json> run(const TempDir& dir, const std::string& text) {
  const Study study = load_study(dir.write("study.toml", text));
  const std::vector<std::string> columns = kind.output_columns(study.document);
  const std::vector<Json> values = kind.run_point(study.point_document(0), {});
  EXPECT_EQ(columns.size(), values.size());
  std::map<std::string, Json> out;
  for (std::size_t c = 0; c < columns.size(); ++c) out[columns[c]] = values.at(c);
  return out;
}

// Below, between and near the natural frequencies (158 and 433 Hz): 1450 rpm (24 Hz, quasi-static),
// 9000 rpm (150 Hz, near the first resonance) and 18000 rpm (300 Hz, between the two).
TEST(SimulateClosedForms, G6SteadyAmplitudeEqualsTheClosedForm) {
  TempDir dir;
  for (double rpm : {1450.0, 9000.0, 18000.0}) {
    SCOPED_TRACE(rpm);
    const auto row = run(dir, with_wheel(rpm));
    ASSERT_TRUE(row.at("forced_amplitude_m").is_number()) << row.at("closed_form_note");
    EXPECT_EQ(row.at("closed_form_note"), "applies; the simulated response is steady");
    const double closed = row.at("forced_amplitude_m").get<double>();
    const double simulated = row.at("steady_amplitude_m").get<double>();
    std::printf("G6 at %.0f rpm: closed form %.6e m, simulated %.6e m (%.3f %%)\n", rpm, closed, simulated,
                100.0 * (simulated / closed - 1.0));
    EXPECT_NEAR(simulated, closed, 0.005 * closed);
  }
}

TEST(SimulateClosedForms, ColumnIsNullWithTheReasonWhereTheClosedFormDoesNotApply) {
  TempDir dir;
  const auto row = run(dir, with_wheel(1450.0) +
                                "wheel_speed_modulation = \"sinusoidal\"\nwheel_speed_amplitude_ratio = 0.1\n"
                                "wheel_speed_frequency_hz = 2.0\n");
  EXPECT_TRUE(row.at("forced_amplitude_m").is_null());
  EXPECT_TRUE(row.at("steady_amplitude_m").is_number());
  const std::string note = row.at("closed_form_note").get<std::string>();
  EXPECT_EQ(note.rfind("does not apply: the wheel speed varies (", 0), 0u) << note;
  EXPECT_NE(note.find("the closed form is the steady state at constant nominal speeds"), std::string::npos) << note;
}

TEST(SimulateClosedForms, ModelsWithoutSuchAClosedFormGetNoColumns) {
  TempDir dir;
  const Study study = load_study(dir.write("study.toml", R"([study]
kind = "simulate"
[model]
type = "amplitude_modulated"
frequency_hz = 800.0
damping_ratio = 0.05
stiffness_n_per_m = 5.0e7
grinding_stiffness_n_per_m = 5.0e6
contact_stiffness_n_per_m = 1.0e8
modulation_depth = 0.3
wheel_speed_rpm = 1450
[simulation]
duration_s = 0.1
)"));
  const std::vector<std::string> columns = kind.output_columns(study.document);
  EXPECT_EQ(std::count(columns.begin(), columns.end(), "steady_amplitude_m"), 0);
  EXPECT_EQ(std::count(columns.begin(), columns.end(), "closed_form_note"), 0);
}

}  // namespace
}  // namespace chatterlab
