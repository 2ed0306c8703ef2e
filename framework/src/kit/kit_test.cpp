// The study kit's building blocks: a ParamTable declared once gives specs (limits, defaults from
// the struct), validation messages, reading and writing; axis labels from key names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <span>
#include <sstream>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/kit/model.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/kit/settings.hpp"
#include "chatterlab/kit/simulation.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/param_table.hpp"
#include "unit/g1_test_machines.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::testing {
namespace {

enum class Shape { sine, square };

struct Mode {
  double frequency_hz = 100.0;
  double damping_ratio = 0.05;
};

struct Settings {
  double duration_s = 2.0;
  int steps = 10;
  bool one_sided = true;
  std::string label = "run";
  std::optional<double> fit_start_s;
  std::vector<double> levels{1.0, 2.0};
  Shape shape = Shape::square;
  std::vector<Mode> modes{Mode{}};
  double stiffness_n_per_m = 0.0;  // required
};

const ParamTable<Mode>& mode_table() {
  static const ParamTable<Mode> table = [] {
    ParamTable<Mode> t;
    t.add(&Mode::frequency_hz, "frequency_hz", "Hz", "natural frequency").positive();
    t.add(&Mode::damping_ratio, "damping_ratio", "1", "damping ratio").fraction(true);
    return t;
  }();
  return table;
}

const ParamTable<Settings>& settings_table() {
  static const ParamTable<Settings> table = [] {
    ParamTable<Settings> t;
    t.add(&Settings::duration_s, "duration_s", "s", "simulated time").positive().at_most(100.0);
    t.add(&Settings::steps, "steps", "1", "steps").at_least(1);
    t.add(&Settings::one_sided, "one_sided", "1", "one-sided contact");
    t.add(&Settings::label, "label", "", "a label");
    t.add(&Settings::fit_start_s, "fit_start_s", "s", "start of the fit").non_negative();
    t.add(&Settings::levels, "levels", "1", "levels").min_items(1);
    t.add_choice(&Settings::shape, "shape", "wave form", {{"sine", Shape::sine}, {"square", Shape::square}});
    t.add_tables(&Settings::modes, "modes", "structural modes", mode_table()).min_items(1);
    t.add(&Settings::stiffness_n_per_m, "stiffness_n_per_m", "N/m", "stiffness").positive().required();
    return t;
  }();
  return table;
}

class LineSeven final : public SourceMap {
 public:
  SourceLocation locate(std::string_view) const override { return {"s.toml", 7}; }
};

TEST(ParamTable, SpecsCarryKindsLimitsAndTheStructsDefaults) {
  const std::vector<ParamSpec> specs = settings_table().specs();
  ASSERT_EQ(specs.size(), 9u);
  EXPECT_EQ(specs[0].kind, ValueKind::real);
  EXPECT_EQ(specs[0].default_value, Json(2.0));
  EXPECT_EQ(specs[0].min, 0.0);
  EXPECT_TRUE(specs[0].min_exclusive);
  EXPECT_EQ(specs[0].max, 100.0);
  EXPECT_EQ(specs[1].kind, ValueKind::integer);
  EXPECT_EQ(specs[2].kind, ValueKind::boolean);
  EXPECT_EQ(specs[3].kind, ValueKind::string);
  EXPECT_TRUE(specs[4].optional);
  EXPECT_TRUE(specs[4].default_value.is_null());
  EXPECT_EQ(specs[5].kind, ValueKind::real_list);
  EXPECT_EQ(specs[6].choices, (std::vector<std::string>{"sine", "square"}));
  EXPECT_EQ(specs[6].default_value, Json("square"));
  EXPECT_EQ(specs[7].kind, ValueKind::table_list);
  ASSERT_EQ(specs[7].fields.size(), 2u);
  EXPECT_TRUE(specs[7].fields[1].max_exclusive);
  EXPECT_TRUE(specs[8].required());
}

TEST(ParamTable, ReadsAValidatedTableIntoTheStruct) {
  Json table = {{"stiffness_n_per_m", 5e7}, {"shape", "sine"}, {"fit_start_s", 0.5},
                {"modes", {{{"frequency_hz", 67.56}}}}};
  const Json validated = validate_params(table, settings_table().specs(), "simulation", LineSeven());
  const Settings s = settings_table().read(validated);
  EXPECT_EQ(s.duration_s, 2.0);
  EXPECT_EQ(s.stiffness_n_per_m, 5e7);
  EXPECT_EQ(s.shape, Shape::sine);
  ASSERT_TRUE(s.fit_start_s.has_value());
  EXPECT_EQ(*s.fit_start_s, 0.5);
  ASSERT_EQ(s.modes.size(), 1u);
  EXPECT_EQ(s.modes[0].frequency_hz, 67.56);
  EXPECT_EQ(s.modes[0].damping_ratio, 0.05);  // the field's default from the struct
  // Writing back gives the validated table: one declaration serves both directions.
  EXPECT_EQ(settings_table().write(s), validated);
}

TEST(ParamTable, ReadFillsKeysATableLacksFromTheStructsDefaults) {
  // A partial (unvalidated) table: what validation would fill in, read() fills in too, at every
  // level (a nested list item keeps its own defaults), so no plugin needs its own merge step.
  const Settings s = settings_table().read(Json{{"stiffness_n_per_m", 5e7},
                                                {"steps", 4},
                                                {"modes", {{{"damping_ratio", 0.2}}}}});
  EXPECT_EQ(s.steps, 4);
  EXPECT_EQ(s.duration_s, 2.0);
  EXPECT_TRUE(s.one_sided);
  EXPECT_EQ(s.label, "run");
  EXPECT_FALSE(s.fit_start_s.has_value());
  EXPECT_EQ(s.levels, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(s.shape, Shape::square);
  ASSERT_EQ(s.modes.size(), 1u);
  EXPECT_EQ(s.modes[0].frequency_hz, 100.0);
  EXPECT_EQ(s.modes[0].damping_ratio, 0.2);
  // The filled struct writes back as the validated table of the same input.
  const Json validated = validate_params({{"stiffness_n_per_m", 5e7}, {"steps", 4},
                                          {"modes", {{{"damping_ratio", 0.2}}}}},
                                         settings_table().specs(), "simulation", LineSeven());
  EXPECT_EQ(settings_table().write(s), validated);
  // A required key has no default to fall back on; a non-table is no table.
  EXPECT_THROW(settings_table().read(Json::object()), std::logic_error);
  EXPECT_THROW(settings_table().read(Json(3.0)), std::logic_error);
  EXPECT_EQ(mode_table().read(Json()).frequency_hz, 100.0);  // absent table: every default
}

TEST(ParamTable, ValidationNamesFileLineKeyValueAndLimit) {
  const std::string message = input_error_of([] {
    validate_params({{"stiffness_n_per_m", 5e7}, {"duration_s", 250.0}}, settings_table().specs(),
                    "simulation", LineSeven());
  });
  EXPECT_NE(message.find("s.toml:7"), std::string::npos) << message;
  EXPECT_NE(message.find("simulation.duration_s = 250"), std::string::npos) << message;
  EXPECT_NE(message.find("<= 100"), std::string::npos) << message;
  const std::string missing = input_error_of(
      [] { validate_params(Json::object(), settings_table().specs(), "simulation", LineSeven()); });
  EXPECT_NE(missing.find("stiffness_n_per_m"), std::string::npos) << missing;
}

TEST(ParamTable, ADuplicateKeyIsAProgrammingError) {
  ParamTable<Settings> t;
  t.add(&Settings::duration_s, "duration_s", "s", "time");
  EXPECT_THROW(t.add(&Settings::steps, "duration_s", "1", "again"), std::logic_error);
}

TEST(KitSettings, AbsentTableTakesEveryDefaultAndIsWrittenBack) {
  struct Small {
    double rate_hz = 3.0;
  };
  ParamTable<Small> t;
  t.add(&Small::rate_hz, "rate_hz", "Hz", "rate").positive();
  Json document = Json::object();
  const Small s = kit::validate_settings(document, "sampling", t, LineSeven());
  EXPECT_EQ(s.rate_hz, 3.0);
  EXPECT_EQ(document.at("sampling"), Json({{"rate_hz", 3.0}}));
  document["sampling"] = 4;
  const std::string message = input_error_of([&] { kit::validate_settings(document, "sampling", t, LineSeven()); });
  EXPECT_NE(message.find("expected a table [sampling]"), std::string::npos) << message;
}

TEST(KitModel, ExactSpeedRatiosOfSmallWholeNumbers) {
  EXPECT_EQ(kit::exact_ratio(1450.0, 290.0), "5/1");
  EXPECT_EQ(kit::exact_ratio(1000.0, 30.0), "100/3");
  EXPECT_EQ(kit::exact_ratio(1450.0, 290.01), "");
  EXPECT_EQ(kit::exact_ratio(1450.0, 55.0), "290/11");
  EXPECT_EQ(kit::exact_ratio(1450.0, 55.0, 10), "");  // needs q = 11
  EXPECT_EQ(kit::exact_ratio(0.0, 55.0), "");
}

// The fit window waits for the longest REGENERATIVE delay: a rotor whose surface the model does
// not regenerate feeds nothing back, however slowly it turns.
double longest_delay_of(const std::string& model_toml) {
  TempDir dir;
  const Study study = load_text(dir, "[study]\nkind = \"simulate\"\n" + model_toml + "[simulation]\nduration_s = 1.0\n");
  return kit::longest_delay_s(*kit::build_model(study.document["model"])->time_domain());
}

TEST(KitSimulation, LongestDelayIsTheSlowestRegeneratedRotorsRevolution) {
  // G7 regenerates the wheel alone: its 55 rpm work (1.09 s a revolution) is no delay.
  EXPECT_DOUBLE_EQ(longest_delay_of("[model]\ntype = \"amplitude_modulated\"\nfrequency_hz = 800.0\n"
                                    "damping_ratio = 0.05\nstiffness_n_per_m = 5.0e7\n"
                                    "grinding_stiffness_n_per_m = 1.0e7\ncontact_stiffness_n_per_m = 1.0e8\n"
                                    "modulation_depth = 0.3\nwheel_speed_rpm = 1450\nwork_speed_rpm = 55\n"),
                   60.0 / 1450.0);
  // G1 regenerates both by default: the 300 rpm work is the longest; without work regeneration the
  // 1450 rpm wheel is.
  const std::string g1 = model_table_toml("plunge_regenerative", g1_feed_risk_machine);
  EXPECT_DOUBLE_EQ(longest_delay_of(g1), 60.0 / 300.0);
  EXPECT_DOUBLE_EQ(longest_delay_of(g1 + "work_regeneration = false\n"), 60.0 / 1450.0);
  EXPECT_DOUBLE_EQ(longest_delay_of(g1 + "work_regeneration = false\nwheel_regeneration = false\n"), 0.0);
}

TEST(KitPlots, AxisLabelsAreWordsWithTheUnitOfTheKeySuffix) {
  EXPECT_EQ(kit::axis_label("wheel_speed_rpm"), "wheel speed [rpm]");
  EXPECT_EQ(kit::axis_label("model.contact_stiffness_n_per_m"), "contact stiffness [N/m]");
  EXPECT_EQ(kit::axis_label("model.modes.0.damping_ratio"), "mode 1 damping ratio");
  EXPECT_EQ(kit::axis_label("growth_rate_per_s"), "growth rate [1/s]");
  EXPECT_EQ(kit::axis_label("suppression.amplitude_ratio"), "suppression amplitude ratio");
  EXPECT_EQ(kit::axis_label("suppression.frequency_hz"), "suppression frequency [Hz]");
  EXPECT_EQ(kit::axis_label("penetration_damping_n_s_per_m"), "penetration damping [N s/m]");
  EXPECT_EQ(kit::axis_label("waviness_um"), "waviness [µm]");
  EXPECT_EQ(kit::axis_label("seed"), "seed");
}

TEST(KitPlots, DecimationKeepsEachBucketsExtremesInOrder) {
  // 100,000 samples of a small ripple with a three-sample spike that an every-n-th-sample
  // thinning at stride 20 would miss (it starts at an odd index): min/max per bucket keeps it.
  const std::size_t n = 100000;
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = 0.5 * static_cast<double>(i);
    y[i] = (i % 7 == 0 ? 0.1 : -0.1) + (i >= 61237 && i < 61240 ? 3.0 : 0.0);
  }
  const plot::Series s = kit::decimated("profile", x, y, 5000);
  ASSERT_LE(s.x.size(), 2 * 5000u);
  EXPECT_GE(s.x.size(), 5000u);
  const auto peak = std::max_element(s.y.begin(), s.y.end());
  EXPECT_DOUBLE_EQ(*peak, 2.9);  // -0.1 + 3: no spike sample is a multiple of 7
  EXPECT_DOUBLE_EQ(*std::min_element(s.y.begin(), s.y.end()), -0.1);
  for (std::size_t k = 1; k < s.x.size(); ++k) ASSERT_LT(s.x[k - 1], s.x[k]) << "not in time order at " << k;
  // The accessor form evaluates the same points as the vector form.
  const plot::Series lazy = kit::decimated("profile", n, [&](std::size_t i) { return x[i]; },
                                           [&](std::size_t i) { return y[i]; }, 5000);
  EXPECT_EQ(lazy.x, s.x);
  EXPECT_EQ(lazy.y, s.y);
  // A short series is drawn whole.
  EXPECT_EQ(kit::decimated("short", std::vector<double>{0, 1, 2}, std::vector<double>{5, 4, 6}, 5000).y,
            (std::vector<double>{5, 4, 6}));
}

// A table streamed in blocks (70,000 rows, about 2 MB: five blocks of rows) is exactly its
// csv_text; nothing is left beside the file. An empty table is its header line.
TEST(KitOutput, StreamedCsvEqualsCsvText) {
  TempDir dir;
  const std::size_t rows = 70000;
  std::vector<double> x(rows), y(rows);
  for (std::size_t r = 0; r < rows; ++r) {
    x[r] = static_cast<double>(r) * 0.1;
    y[r] = std::sin(static_cast<double>(r)) / 3.0;
  }
  const std::vector<std::string> header = {"x_mm", "y \"um\""};
  kit::write_csv_streamed(dir.path() / "t.csv", header, rows, [&](std::size_t r, std::span<double> cells) {
    cells[0] = x[r];
    cells[1] = y[r];
  });
  auto read = [&](const char* name) {
    std::ifstream in(dir.path() / name);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  };
  EXPECT_EQ(read("t.csv"), csv_text(header, {x, y}));
  kit::write_csv_streamed(dir.path() / "empty.csv", header, 0, [](std::size_t, std::span<double>) {});
  EXPECT_EQ(read("empty.csv"), csv_text(header, {{}, {}}));
  EXPECT_EQ(read("empty.csv").find('\n'), read("empty.csv").size() - 1);  // the header line only
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 2);
}

// A file written on request above a size: "auto" writes it up to the limit (inclusive), "always"
// at any size, "never" not at all; the reason a skipped file is missing names the key and how to
// get the file.
TEST(KitOutput, OnRequestFileIsWrittenUpToItsLimitUnlessAskedOtherwise) {
  const kit::OnRequestFile file{"monitor", "series_csv", "alarms.csv", 1000};
  EXPECT_EQ(file.skipped("auto", 1000), std::nullopt);
  EXPECT_EQ(file.skipped("always", 5000), std::nullopt);
  EXPECT_EQ(file.skipped("auto", 1001),
            "not written: 1001 samples > 1000 (monitor.series_csv = \"auto\") "
            "(monitor.series_csv = \"always\" writes it)");
  EXPECT_EQ(file.skipped("never", 10),
            "not written: 10 samples, monitor.series_csv = \"never\" "
            "(monitor.series_csv = \"always\" writes it)");
  const ParamSpec spec = file.spec();
  EXPECT_EQ(spec.key, "series_csv");
  EXPECT_EQ(spec.default_value, "auto");
  EXPECT_EQ(spec.choices, (std::vector<std::string>{"auto", "always", "never"}));
  EXPECT_EQ(spec.description, "write alarms.csv: auto (inputs of up to 1000 samples), always or never");
}

}  // namespace
}  // namespace chatterlab::testing
