// Study kind chatter_monitor: the shipped transition study end to end (alarm times against the
// known onset, files written), reuse of saved weights, a simulate-style CSV with t_s, and bad
// input (exit 2 messages naming file, key and limit).
#include "study_kinds/chatter_monitor/chatter_monitor.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>
#include <numbers>
#include <sstream>

#include <algorithm>

#include "shared/monitoring/features.hpp"
#include "shared/monitoring/monitor_common.hpp"
#include "chatterlab/catalog.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/study.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const fs::path shipped = fs::path(CHATTERLAB_SOURCE_DIR) / "studies/chatter_monitor_transition.toml";

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// 1 s at 8 kHz in the layout of a simulate study's timeseries.csv (t_s, displacement_m, force_n).
std::string transition_csv(double duration_s = 1.0, bool with_time = true) {
  monitor::TransitionSignal spec;
  spec.duration_s = duration_s;
  const std::vector<double> x = spec.samples();
  std::string text = with_time ? "t_s,displacement_m,force_n\n" : "displacement_m,force_n\n";
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (with_time) text += fmt::format("{},", static_cast<double>(i) / spec.sample_rate_hz);
    text += fmt::format("{},{}\n", 1e-7 * x[i], 100.0 + x[i]);
  }
  return text;
}

constexpr const char* monitor_tables = R"(
[monitor.bp_network]
stable_s = [0.1, 0.1186875]
onset_s = [0.7, 0.7186875]

[monitor.rbf_density]
)";

std::string study_text(const std::string& input, const std::string& monitor = monitor_tables) {
  return "[study]\nkind = \"chatter_monitor\"\n\n[input]\n" + input + "\n" + monitor;
}

TEST(ChatterMonitor, ShippedTransitionStudy) {
  const Study study = load_study(shipped);
  const Json& input = study.document.at("input");
  EXPECT_DOUBLE_EQ(input.at("sample_rate_hz").get<double>(), 8000.0);  // from t_s
  const ChatterMonitor kind;
  EXPECT_EQ(kind.output_columns(study.document),
            (std::vector<std::string>{"bp_network_first_alarm_s", "bp_network_alarm_intervals",
                                      "rbf_density_first_alarm_s", "rbf_density_alarm_intervals"}));
  TempDir dir;
  PointContext context;
  context.artifact_dir = dir.path();
  context.plots = false;
  const std::vector<Json> out = kind.run_point(study.point_document(0), context);
  // Onset at 0.5 s; the sine reaches the noise level at 0.625 s (see the study's header).
  for (std::size_t first : {0u, 2u}) {
    ASSERT_TRUE(out[first].is_number());
    EXPECT_GT(out[first].get<double>(), 0.625);
    EXPECT_LT(out[first].get<double>(), 0.8);
    EXPECT_EQ(out[first + 1], 1);
  }
  for (const char* file : {"alarms.csv", "features.csv", "summary.json", "network_weights.json"})
    EXPECT_TRUE(fs::exists(dir.path() / file)) << file;
  const std::string alarms = read_text(dir.path() / "alarms.csv");
  EXPECT_EQ(alarms.substr(0, alarms.find('\n')), "t_s,detector,score,alarm");
  const Json summary = Json::parse(read_text(dir.path() / "summary.json"));
  const Json& bp = summary.at("detectors").at("bp_network");
  EXPECT_TRUE(bp.at("training").at("converged").get<bool>());
  EXPECT_EQ(bp.at("test").at("confusion").at("true_positive").get<int>() +
                bp.at("test").at("confusion").at("true_negative").get<int>(),
            10);
  EXPECT_EQ(summary.at("detectors").at("rbf_density").at("alarm_intervals_s").size(), 1u);
}

// alarms.csv as it was assembled in memory: every detector's analyse() result (JSON arrays), one
// row per evaluation, stable-sorted by time.
std::string alarms_csv_in_memory(const Json& monitor, const SampledSeries& series) {
  struct Row { double t; std::string detector; double score; bool alarm; };
  std::vector<Row> rows;
  for (const char* name : ChatterMonitor::detector_names) {
    if (!monitor.contains(name)) continue;
    const Json r = analysis_registry().at(name).create(ParamValues(monitor.at(name)))->analyse(series, Json::object());
    const auto t = r.at("t_s").get<std::vector<double>>();
    const auto score = r.at("score").get<std::vector<double>>();
    const auto alarm = r.at("alarm").get<std::vector<bool>>();
    for (std::size_t k = 0; k < t.size(); ++k) rows.push_back({t[k], name, score[k], alarm[k]});
  }
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.t < b.t; });
  std::string csv = "t_s,detector,score,alarm\n";
  for (const auto& row : rows)
    csv += fmt::format("{},{},{},{}\n", row.t, row.detector, row.score, row.alarm ? 1 : 0);
  return csv;
}

// The streamed alarms.csv (a merge of the detectors' tracks) and features.csv (windows computed
// as written) hold exactly the tables that were assembled in memory from the JSON results; the
// two detectors evaluate at shared times (every 10 samples), so the merge's order at equal times
// is checked too.
TEST(ChatterMonitor, StreamedTablesEqualTheInMemoryOnes) {
  const Study study = load_study(shipped);
  const Json point = study.point_document(0);
  TempDir dir;
  PointContext context;
  context.artifact_dir = dir.path();
  context.plots = false;
  ChatterMonitor().run_point(point, context);
  const SampledSeries series = monitor_input_signal(point.at("input"));
  const std::string alarms = read_text(dir.path() / "alarms.csv");
  EXPECT_EQ(alarms, alarms_csv_in_memory(point.at("monitor"), series));
  // rbf_density's first evaluation (sample 49) is also bp_network's fifth: its row comes first.
  const std::size_t rbf = alarms.find(",rbf_density,");
  ASSERT_NE(rbf, std::string::npos);
  const std::size_t line = alarms.rfind('\n', rbf) + 1;
  const std::string t = alarms.substr(line, rbf - line);
  EXPECT_EQ(alarms.substr(alarms.rfind('\n', line - 2) + 1, t.size() + 12), t + ",bp_network,");

  const FeatureSeries windows = feature_series(series.values, 10, 10, series.sample_interval);
  std::vector<double> variance, rho1, residual;
  for (const auto& f : windows.features) {
    variance.push_back(f.variance);
    rho1.push_back(f.rho1);
    residual.push_back(f.residual_variance);
  }
  EXPECT_EQ(windows.t_s.size(), 800u);  // 8000 samples in windows of 10
  EXPECT_EQ(read_text(dir.path() / "features.csv"),
            csv_text({"t_s", "variance", "rho1", "residual_variance"},
                     {windows.t_s, variance, rho1, residual}));
  const Json summary = Json::parse(read_text(dir.path() / "summary.json"));
  EXPECT_FALSE(summary.contains("series_csv"));
  EXPECT_EQ(summary.at("detectors").at("rbf_density").at("evaluations"), 796);  // (8000 - 50) / 10 + 1
}

// [monitor] series_csv: "never" leaves both tables out (summary.json says why and how to get
// them) without changing any result; "always" writes them; anything else is refused at load.
TEST(ChatterMonitor, SeriesCsvOnRequest) {
  TempDir dir;
  dir.write("signal.csv", transition_csv());
  const std::string input = "file = \"signal.csv\"\ncolumn = \"displacement_m\"";
  PointContext context;
  context.plots = false;
  std::vector<std::vector<Json>> outputs;
  for (const std::string choice : {"always", "never"}) {
    const Study study = load_study(dir.write(
        choice + ".toml",
        study_text(input, "[monitor]\nseries_csv = \"" + choice + "\"\n" + monitor_tables)));
    context.artifact_dir = dir.path() / choice;
    outputs.push_back(ChatterMonitor().run_point(study.point_document(0), context));
    const bool written = choice == "always";
    EXPECT_EQ(fs::exists(dir.path() / choice / "alarms.csv"), written);
    EXPECT_EQ(fs::exists(dir.path() / choice / "features.csv"), written);
    const Json summary = Json::parse(read_text(dir.path() / choice / "summary.json"));
    if (written) {
      EXPECT_FALSE(summary.contains("series_csv"));
    } else {
      EXPECT_EQ(summary.at("series_csv"),
                "not written: 8000 samples, monitor.series_csv = \"never\" "
                "(monitor.series_csv = \"always\" writes it)");
      ASSERT_TRUE(summary.at("detectors").at("bp_network").at("first_alarm_s").is_number());
    }
  }
  EXPECT_EQ(outputs[0], outputs[1]);
  const std::string message =
      testing::load_error(dir, study_text(input, "[monitor]\nseries_csv = \"sometimes\"\n" +
                                                     std::string(monitor_tables)));
  EXPECT_NE(message.find("study.toml:8: monitor.series_csv = \"sometimes\": not one of: always, auto, never"),
            std::string::npos)
      << message;
}

TEST(ChatterMonitor, SavedWeightsReproduceTheAlarm) {
  TempDir dir;
  dir.write("signal.csv", transition_csv());
  const ChatterMonitor kind;
  PointContext context;
  context.artifact_dir = dir.path() / "first";
  context.plots = false;
  const Study trained = load_study(dir.write("a.toml", study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"")));
  const auto a = kind.run_point(trained.point_document(0), context);
  const Study loaded = load_study(dir.write(
      "b.toml", study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                           "[monitor.bp_network]\nweights_file = \"first/network_weights.json\"\n")));
  const auto b = kind.run_point(loaded.point_document(0), PointContext{});
  ASSERT_TRUE(a[0].is_number());
  EXPECT_EQ(a[0], b[0]);
}

// A mono 16-bit PCM WAV recording of the transition: the sample rate comes from its header.
TEST(ChatterMonitor, WavInputTakesTheRateFromTheHeader) {
  monitor::TransitionSignal spec;
  const std::vector<double> x = spec.samples();
  std::string data;
  for (double v : x) {
    const auto sample = static_cast<std::int16_t>(std::lround(v / 12.0 * 32767.0));  // |x| < 12
    for (int b = 0; b < 2; ++b) data += static_cast<char>((static_cast<std::uint16_t>(sample) >> (8 * b)) & 0xff);
  }
  std::string wav;
  auto put = [&wav](std::uint32_t v, int bytes) {
    for (int b = 0; b < bytes; ++b) wav += static_cast<char>((v >> (8 * b)) & 0xff);
  };
  wav += "RIFF";
  put(static_cast<std::uint32_t>(36 + data.size()), 4);
  wav += "WAVEfmt ";
  for (auto [value, bytes] : {std::pair{16u, 4}, {1u, 2}, {1u, 2}, {8000u, 4}, {16000u, 4}, {2u, 2}, {16u, 2}})
    put(value, bytes);  // fmt size, PCM, mono, rate, byte rate, block align, bits
  wav += "data";
  put(static_cast<std::uint32_t>(data.size()), 4);
  wav += data;
  TempDir dir;
  dir.write("accel.wav", wav);
  const Study study = load_study(dir.write(
      "s.toml", study_text("file = \"accel.wav\"", "[monitor.rbf_density]\n")));
  EXPECT_DOUBLE_EQ(study.document.at("input").at("sample_rate_hz").get<double>(), 8000.0);
  EXPECT_EQ(study.document.at("input").at("column"), "1");  // the only channel
  // `column = 1` (a TOML integer) is the same 1-based channel index.
  const Study by_index = load_study(dir.write(
      "i.toml", study_text("file = \"accel.wav\"\ncolumn = 1", "[monitor.rbf_density]\n")));
  EXPECT_EQ(by_index.document.at("input").at("column"), "1");
  const auto out = ChatterMonitor().run_point(study.point_document(0), PointContext{});
  ASSERT_TRUE(out[0].is_number());
  EXPECT_GT(out[0].get<double>(), spec.time_of_amplitude(1.0));
  EXPECT_LT(out[0].get<double>(), spec.onset_s + 0.3);
}

std::string error(const TempDir& dir, const std::string& text) { return testing::load_error(dir, text); }

void expect_mentions(const std::string& message, const std::vector<std::string>& parts) {
  for (const auto& part : parts) EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

// `chatterlab describe bp_network` / `rbf_density` also names the monitor's table, where the
// chatter_monitor kind reads their parameters; lyapunov is not a detector.
TEST(ChatterMonitor, DescribeOfADetectorNamesTheMonitorTable) {
  for (const std::string name : {"bp_network", "rbf_density"}) {
    const std::string text = describe_plugin(name);
    EXPECT_NE(text.find(fmt::format("Also used as:   parameters in [monitor.{}] (study kind "
                                    "chatter_monitor)\n",
                                    name)),
              std::string::npos)
        << text;
  }
  EXPECT_EQ(describe_plugin("lyapunov").find("[monitor."), std::string::npos);
}

TEST(ChatterMonitor, BadInputNamesFileKeyAndLimit) {
  TempDir dir;
  dir.write("signal.csv", transition_csv());
  dir.write("short.csv", transition_csv(0.004));
  dir.write("no_time.csv", transition_csv(0.1, false));
  const std::string csv = (dir.path() / "signal.csv").string();

  expect_mentions(error(dir, study_text("file = \"signal.csv\"\ncolumn = \"velocity_m_per_s\"")),
                  {"study.toml:6: input.column = \"velocity_m_per_s\":", csv,
                   "no column 'velocity_m_per_s'", "t_s", "displacement_m", "force_n"});
  expect_mentions(error(dir, study_text("file = \"signal.csv\"")),
                  {"study.toml:4: missing key 'input.column':", "has the columns t_s, displacement_m, force_n"});
  expect_mentions(error(dir, study_text("file = \"no_time.csv\"\ncolumn = \"displacement_m\"")),
                  {"study.toml:4: missing key 'input.sample_rate_hz':", "no_time.csv",
                   "has no t_s column and no WAV header"});
  expect_mentions(error(dir, study_text("file = \"absent.csv\"\ncolumn = \"x\"")),
                  {"study.toml:5: input.file:", "absent.csv: no such file"});
  // 0.004 s = 32 samples: shorter than the 50-sample density window.
  expect_mentions(error(dir, study_text("file = \"short.csv\"\ncolumn = \"displacement_m\"",
                                        "[monitor.rbf_density]\n")),
                  {"study.toml:7: rbf_density.window_samples = 50: the signal 'displacement_m' has "
                   "32 samples, fewer than the 50 this needs",
                   "short.csv, 32 samples at 8000 Hz"});
  expect_mentions(
      error(dir, study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                            "[monitor.bp_network]\nstable_s = [0.1, 0.2]\nonset_s = [0.9, 1.5]\n")),
      {"study.toml:7: bp_network.onset_s = [0.9, 1.5]: outside the signal, which ends at t = 0.999875 s"});
  expect_mentions(error(dir, study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                                        "[monitor]\nsnapshot_times_s = [0.5]\n")),
                  {"study.toml:7: [monitor] enables no detector"});
  expect_mentions(error(dir, study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                                        "[monitor.rbf]\nrho = 0.3\n")),
                  {"unknown key 'monitor.rbf' (valid: bp_network, rbf_density, snapshot_times_s, series_csv)"});
  expect_mentions(error(dir, study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                                        "[monitor.rbf_density]\nrho = 1.5\n")),
                  {"monitor.rbf_density.rho = 1.5"});
  expect_mentions(error(dir, study_text("file = \"signal.csv\"\ncolumn = \"displacement_m\"",
                                        "[monitor]\nsnapshot_times_s = [2.0]\n[monitor.rbf_density]\n")),
                  {"study.toml:8: monitor.snapshot_times_s: 2 s is after the end of the signal (0.999875 s)"});
  dir.write("jitter.csv", "t_s,x\n0,1\n0.001,2\n0.0021,3\n0.003,4\n");
  expect_mentions(error(dir, study_text("file = \"jitter.csv\"\ncolumn = \"x\"", "[monitor.rbf_density]\n")),
                  {"study.toml:5:", "jitter.csv: line 4: t_s is not uniformly spaced",
                   "give input.sample_rate_hz or resample the signal"});
}

}  // namespace
}  // namespace chatterlab
