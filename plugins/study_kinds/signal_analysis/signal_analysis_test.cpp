#include "study_kinds/signal_analysis/signal_analysis.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <fstream>

#include "shared/nonlinear/test_signals.hpp"
#include "chatterlab/catalog.hpp"
#include "chatterlab/runner.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::load_error;
using testing::TempDir;

// A two-column CSV (t_s, x) like a `simulate` study's timeseries.csv.
void write_signal(const TempDir& dir, const std::string& name, const std::vector<double>& x) {
  std::string text = "t_s,displacement_m\n";
  for (std::size_t i = 0; i < x.size(); ++i) text += fmt::format("{},{}\n", 0.001 * double(i), x[i]);
  dir.write(name, text);
}

std::string study(const std::string& input, const std::string& analysis = "") {
  return "[study]\nkind = \"signal_analysis\"\n\n[input]\n" + input + "\n" + analysis;
}

class SignalAnalysisInput : public ::testing::Test {
 protected:
  TempDir dir_;
};

TEST_F(SignalAnalysisInput, MissingColumnListsTheColumns) {
  write_signal(dir_, "s.csv", test_signals::henon(500));
  const std::string m = load_error(dir_, study("file = \"s.csv\"\ncolumn = \"x\"\nsample_rate_hz = 1000"));
  EXPECT_NE(m.find("input.column = \"x\""), std::string::npos) << m;
  EXPECT_NE(m.find("t_s, displacement_m"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, IntegerColumnIsTheOneBasedIndex) {
  // `column = 2` (a TOML integer) reads the second column, as `column = "2"` does; 3 is named
  // as out of range with the columns listed.
  write_signal(dir_, "s.csv", test_signals::henon(500));
  const Study s = testing::load_text(dir_, study("file = \"s.csv\"\ncolumn = 2\nsample_rate_hz = 1000"));
  EXPECT_EQ(s.document.at("input").at("column"), "2");
  const SampledSeries series = SignalAnalysis::load_series(s.document.at("input"));
  ASSERT_EQ(series.values.size(), 500u);
  EXPECT_DOUBLE_EQ(series.values[7], test_signals::henon(500)[7]);
  const std::string m =
      load_error(dir_, study("file = \"s.csv\"\ncolumn = 3\nsample_rate_hz = 1000"));
  EXPECT_NE(m.find("input.column = \"3\""), std::string::npos) << m;
  EXPECT_NE(m.find("t_s, displacement_m"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, WithoutSampleRateEveryRateIsPerSample) {
  // No sample rate and no WAV header: time is counted in samples, and the exponent's column (and
  // every rate) says so: lyapunov_max_per_sample, not _per_s.
  write_signal(dir_, "s.csv", test_signals::henon(500));
  const Study s = testing::load_text(dir_, study("file = \"s.csv\"\ncolumn = \"displacement_m\""));
  const auto columns = SignalAnalysis().output_columns(s.document);
  EXPECT_NE(std::find(columns.begin(), columns.end(), "lyapunov_max_per_sample"), columns.end());
  EXPECT_EQ(std::find(columns.begin(), columns.end(), "lyapunov_max_per_s"), columns.end());
  const SampledSeries series = SignalAnalysis::load_series(s.document.at("input"));
  EXPECT_EQ(series.sample_unit, "sample");
  EXPECT_EQ(series.sample_interval, 1.0);
}

TEST_F(SignalAnalysisInput, ShorterThanTheMinimumIsBadInput) {
  // 150 samples: exit 2 before anything runs (the minimum is named), not a failed point.
  write_signal(dir_, "s.csv", test_signals::henon(150));
  const std::string m = load_error(
      dir_, study("file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000"));
  EXPECT_NE(m.find("150 samples are too short"), std::string::npos) << m;
  EXPECT_NE(m.find("at least 300 samples"), std::string::npos) << m;
  EXPECT_NE(m.find("study.toml:"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, ConstantSignal) {
  write_signal(dir_, "s.csv", std::vector<double>(500, 0.25));
  const std::string m = load_error(
      dir_, study("file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000"));
  EXPECT_NE(m.find("the signal is constant"), std::string::npos) << m;
  EXPECT_NE(m.find("study.toml:"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, NonFiniteSample) {
  dir_.write("s.csv", "t_s,displacement_m\n0,1\n0.001,nan\n0.002,3\n");
  const std::string m = load_error(
      dir_, study("file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000"));
  EXPECT_NE(m.find("line 3"), std::string::npos) << m;
  EXPECT_NE(m.find("not finite"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, TooShortForTheRequestedDimensionSaysTheMinimum) {
  write_signal(dir_, "s.csv", test_signals::henon(300));
  const std::string m = load_error(
      dir_, study("file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000",
                  "[analysis]\nmethods = [\"lyapunov\"]\n[analysis.lyapunov]\n"
                  "embedding_dimension = 6\ndelay_samples = 50\n"));
  EXPECT_NE(m.find("300 samples are too short for embedding dimension 6 with delay 50"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("at least 350 samples"), std::string::npos) << m;
}

TEST_F(SignalAnalysisInput, TheilerWindowLeavingTooFewNeighboursSaysTheLimit) {
  // 400 samples in dimension 2, delay 1: 399 vectors; a window W leaves 399 - (2 W + 1)
  // candidates, at least 100 wanted: W <= 149.
  write_signal(dir_, "s.csv", test_signals::henon(400));
  const std::string input = "file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000";
  auto analysis = [](int w) {
    return fmt::format("[analysis]\nmethods = [\"embedding\", \"lyapunov\"]\n[analysis.lyapunov]\n"
                       "theiler_window_samples = {}\n",
                       w);
  };
  const std::string m = load_error(dir_, study(input, analysis(150)));
  EXPECT_NE(m.find("analysis.lyapunov.theiler_window_samples = 150: too few neighbours"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("399 delay vectors"), std::string::npos) << m;
  EXPECT_NE(m.find("at most 149 samples"), std::string::npos) << m;
  EXPECT_NO_THROW(testing::load_text(dir_, study(input, analysis(149))));
}

TEST_F(SignalAnalysisInput, UnknownMethodAndStrayOverride) {
  write_signal(dir_, "s.csv", test_signals::henon(500));
  const std::string input = "file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000";
  std::string m = load_error(dir_, study(input, "[analysis]\nmethods = [\"lyapunof\"]\n"));
  EXPECT_NE(m.find("analysis.methods.0 = \"lyapunof\": no such analysis"), std::string::npos) << m;
  EXPECT_NE(m.find("correlation_dimension, embedding"), std::string::npos) << m;
  m = load_error(dir_, study(input, "[analysis]\nmethods = [\"embedding\"]\n[analysis.lyapunov]\n"
                                    "max_steps = 10\n"));
  EXPECT_NE(m.find("analysis.lyapunov: not a listed method"), std::string::npos) << m;
  m = load_error(dir_, study(input, "[analysis]\nmethods = [\"lyapunov\"]\n[analysis.lyapunov]\n"
                                    "max_step = 10\n"));
  EXPECT_NE(m.find("analysis.lyapunov.max_step"), std::string::npos) << m;
}

// End to end through the runner: summary.json with the headline estimates, results.csv, plots.
TEST_F(SignalAnalysisInput, HenonStudyWritesSummaryAndPlots) {
  write_signal(dir_, "s.csv", test_signals::henon(3000));
  const auto file = dir_.write(
      "study.toml", study("file = \"s.csv\"\ncolumn = \"displacement_m\"\nsample_rate_hz = 1000",
                          "[analysis]\nmethods = [\"embedding\", \"lyapunov\"]\n"
                          "[analysis.lyapunov]\nmax_reference_points = 1000\n"));
  const Study s = load_study(file, {});
  RunOptions options;
  options.out_dir = dir_.path() / "out";
  options.threads = 1;
  options.progress = false;
  const auto summary = run_study(s, options);
  ASSERT_EQ(summary.failed, 0u);
  std::ifstream in(options.out_dir / "summary.json");
  const Json j = Json::parse(in);
  EXPECT_EQ(j["delay_samples"]["value"], 1);
  EXPECT_EQ(j["embedding_dimension"]["value"], 2);
  // 0.419 per iteration at 1000 iterations per second.
  EXPECT_NEAR(j["lyapunov_max_per_s"]["value"].get<double>(), 419, 30);
  EXPECT_EQ(j["correlation_dimension"]["quality"], "failed");  // not run
  EXPECT_TRUE(j["methods"].contains("lyapunov"));
  for (const char* stem : {"embedding_ami", "embedding_fnn", "lyapunov_divergence", "phase_portrait"})
    EXPECT_TRUE(std::filesystem::exists(options.out_dir / (std::string(stem) + ".png"))) << stem;
}


// The verdict rules on synthetic method results: chaos needs all four pieces of evidence.
Json chaotic_context() {
  return Json{{"lyapunov",
               {{"divergence", "exponential"},
                {"lyapunov_max_per_sample", {{"value", 0.42}, {"ci_low", 0.40}, {"ci_high", 0.44}}}}},
              {"correlation_dimension", {{"correlation_dimension", {{"value", 1.21}}}}},
              {"surrogates",
               {{"rejected_for_prediction", true},
                {"rejected_for_exponent", true},
                {"rejected_for_dimension", true}}}};
}

TEST(SignalAnalysisVerdict, ChaosNeedsEveryPieceOfEvidence) {
  EXPECT_EQ(SignalAnalysis::chaos_verdict(chaotic_context())["verdict"], "deterministic chaos");
  // Each missing piece withdraws the claim, and the reason says which.
  Json c = chaotic_context();
  c["surrogates"]["rejected_for_dimension"] = false;
  Json v = SignalAnalysis::chaos_verdict(c);
  EXPECT_NE(v["verdict"], "deterministic chaos");
  EXPECT_NE(v["reason"].get<std::string>().find("do not reject a linear stochastic process for the "
                                                "dimension"),
            std::string::npos)
      << v.dump();
  c = chaotic_context();
  c["lyapunov"]["lyapunov_max_per_sample"]["ci_low"] = -0.01;
  EXPECT_NE(SignalAnalysis::chaos_verdict(c)["verdict"], "deterministic chaos");
  c = chaotic_context();
  c["correlation_dimension"]["correlation_dimension"]["value"] = nullptr;
  EXPECT_NE(SignalAnalysis::chaos_verdict(c)["verdict"], "deterministic chaos");
  c = chaotic_context();
  c.erase("surrogates");
  v = SignalAnalysis::chaos_verdict(c);
  EXPECT_EQ(v["verdict"], "not determined");
  EXPECT_NE(v["reason"].get<std::string>().find("'surrogates' not run"), std::string::npos);
}

TEST(SignalAnalysisVerdict, StochasticPeriodicAndNoisySignals) {
  Json c = chaotic_context();
  c["surrogates"] = {{"rejected_for_prediction", false},
                     {"rejected_for_exponent", false},
                     {"rejected_for_dimension", false}};
  EXPECT_EQ(SignalAnalysis::chaos_verdict(c)["verdict"], "linear stochastic");
  c = chaotic_context();
  c["lyapunov"]["divergence"] = "none";
  EXPECT_EQ(SignalAnalysis::chaos_verdict(c)["verdict"], "periodic or quasi-periodic");
  c = chaotic_context();
  c["correlation_dimension"] = {{"correlation_dimension", {{"value", nullptr}}}, {"noise_level", 0.1}};
  EXPECT_EQ(SignalAnalysis::chaos_verdict(c)["verdict"], "noise-dominated");
}

// `chatterlab describe <analysis>` shows how a signal_analysis study names the method and where its
// parameters go, not a `type =` key that no study reads.
TEST(SignalAnalysisCatalog, DescribeShowsMethodsListAndParameterTable) {
  const std::string text = describe_plugin("lyapunov");
  EXPECT_NE(text.find("Used as:        [analysis] methods = [\"lyapunov\", ...], parameters in "
                      "[analysis.lyapunov] (study kind signal_analysis)\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\nParameters ([analysis.lyapunov]):\n"), std::string::npos) << text;
  EXPECT_NE(text.find("Example:\n  [analysis]\n  methods = [\"lyapunov\"]\n\n"
                      "  [analysis.lyapunov]\n  max_reference_points = 200\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("type = "), std::string::npos) << text;
}

}  // namespace
}  // namespace chatterlab
