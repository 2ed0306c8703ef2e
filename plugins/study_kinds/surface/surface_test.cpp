#include "shared/metrology/surface.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "study_kinds/surface/surface.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/signal_io.hpp"
#include "shared/metrology/surface_report.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::surface {
namespace {

using chatterlab::testing::load_error;
using chatterlab::testing::load_text;
using chatterlab::testing::TempDir;
constexpr double pi = std::numbers::pi;

// A CSV column of `n` values f(i), with an optional x column.
std::string table(std::size_t n, double (*f)(std::size_t), bool with_x = false, double dx = 0.001) {
  std::ostringstream out;
  out.precision(17);
  out << (with_x ? "x_mm,height_um\n" : "height_um\n");
  for (std::size_t i = 0; i < n; ++i) {
    if (with_x) out << static_cast<double>(i) * dx << ",";
    out << f(i) << "\n";
  }
  return out.str();
}

double waves(std::size_t i) {  // 0.4 mm waves (at 1 um spacing) of amplitude 2 um
  return 2.0 * std::sin(2 * pi * static_cast<double>(i) / 400.0);
}

double lobes(std::size_t i) {  // 7 lobes of amplitude 1.5 um on 3600 samples
  return 1.5 * std::cos(7 * 2 * pi * static_cast<double>(i) / 3600.0);
}

// One point of a surface study, its artifacts written to artifact_dir (plots drawn or not).
std::vector<Json> run_surface_point(const Study& study, const std::filesystem::path& artifact_dir, bool plots) {
  PointContext context;
  context.artifact_dir = artifact_dir;
  context.plots = plots;
  return SurfaceStudy().run_point(study.point_document(0), context);
}

// lobes() over one revolution of 3600 samples, times scale (1: um; 1e-6: m).
std::vector<double> lobe_samples(double scale) {
  std::vector<double> v;
  for (std::size_t i = 0; i < 3600; ++i) v.push_back(lobes(i) * scale);
  return v;
}

// A closed profile: one revolution of samples, interval_deg apart.
SampledSeries closed_profile(double interval_deg, std::vector<double> samples) {
  SampledSeries s;
  s.closed = true;
  s.sample_unit = "deg";
  s.sample_interval = interval_deg;
  s.set_samples(std::move(samples));
  return s;
}

std::string open_study(const std::string& extra_input = "", const std::string& filter =
                                                                "cutoff_mm = 2.5\n") {
  return "[study]\nkind = \"surface\"\n\n[input]\nfile = \"p.csv\"\ncolumn = \"height_um\"\n"
         "spacing_mm = 0.001\n" +
         extra_input + "\n[filter]\n" + filter;
}

TEST(SurfaceEvaluation, OpenSineParametersAndIdentity) {
  SampledSeries s;
  s.sample_interval = 0.001;
  s.sample_unit = "mm";
  // 50 whole waves in the evaluation length (the profile without lc/2 = 40 samples each end),
  // even about its centre, so the least-squares line removed as form is zero.
  std::vector<double> mm;
  for (std::size_t i = 0; i < 20080; ++i)
    mm.push_back(2e-3 * std::cos(2 * pi * (static_cast<double>(i) - 10040.0) / 400.0));
  s.set_samples(std::move(mm));
  SurfaceSettings settings;
  settings.value_to_um = 1e3;
  settings.cutoff_mm = 0.08;  // lambda / lc = 5: transmission 0.9726
  const SurfaceEvaluation e = evaluate_surface_profile(s, settings);
  const double h = waviness_transmission(FilterType::gaussian, 5.0);
  const double a = 2.0 * h;
  const Json& j = e.summary;
  EXPECT_NEAR(j["Wa_um"].get<double>(), 2 * a / pi, 2e-3);
  EXPECT_NEAR(j["Wq_um"].get<double>(), a / std::sqrt(2.0), 2e-3);
  EXPECT_NEAR(j["Wz_um"].get<double>(), 2 * a, 5e-3);
  EXPECT_NEAR(j["Wsk"].get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(j["Wku"].get<double>(), 1.5, 2e-3);
  EXPECT_NEAR(j["WSm_mm"].get<double>(), 0.4, 1e-3);
  EXPECT_TRUE(j.contains("motif"));
  for (std::size_t i = 0; i < e.profile_um.size(); ++i)
    ASSERT_DOUBLE_EQ(e.roughness_um(i), e.profile_um[i] - e.waviness_um[i]);
}

TEST(SurfaceEvaluation, ClosedProfileRoundnessAndUprTable) {
  const SampledSeries s = closed_profile(0.1, lobe_samples(1.0));
  SurfaceSettings settings;
  settings.cutoff_upr = 150;
  const Json j = evaluate_surface(s, settings);
  const double h = waviness_transmission(FilterType::gaussian, 150.0 / 7);
  for (const char* ref : {"least_squares", "minimum_zone", "minimum_circumscribed",
                          "maximum_inscribed"}) {
    EXPECT_NEAR(j["roundness"][ref]["RONt_um"].get<double>(), 3.0 * h, 1e-5) << ref;
    EXPECT_TRUE(j["roundness"][ref]["certified"].get<bool>());
  }
  EXPECT_DOUBLE_EQ(j["RONt_um"].get<double>(), j["roundness"]["least_squares"]["RONt_um"].get<double>());
  // 15 UPR removes most of 7 lobes: transmission exp(-pi (alpha 7/15)^2) = 0.85.
  EXPECT_NEAR(j["roundness_by_upr"]["15"]["least_squares_RONt_um"].get<double>(),
              3.0 * waviness_transmission(FilterType::gaussian, 15.0 / 7), 1e-6);
  EXPECT_TRUE(j["roundness_by_upr"]["150"].contains("least_squares_RONt_um"));
  EXPECT_TRUE(j["roundness_by_upr"]["500"].contains("least_squares_RONt_um"));  // 7.2 >= 7
  EXPECT_FALSE(j.contains("motif"));  // MOTIF is defined for open profiles
}

TEST(SurfaceEvaluation, RejectsTooFewSamplesPerCutoff) {
  const SampledSeries s = closed_profile(1.0, std::vector<double>(360, 0.0));
  SurfaceSettings settings;
  settings.cutoff_upr = 60;  // 6 samples per cut-off
  EXPECT_THROW(evaluate_surface(s, settings), InputError);
}

TEST(SurfaceEvaluation, AnalysisPluginEvaluatesASimulatedWorkSurface) {
  // A work surface in metres over one revolution, as a simulate study writes it.
  const SampledSeries s = closed_profile(0.1, lobe_samples(1e-6));
  const auto& entry = analysis_registry().at("surface_profile");
  const auto analysis = entry.create(ParamValues(
      validate_params(Json{{"unit", "m"}, {"cutoff_upr", 150}}, entry.info.params, "analysis",
                      chatterlab::kit::FileSourceMap("test"))));
  const Json j = analysis->analyse(s, Json::object());
  EXPECT_NEAR(j["RONt_um"].get<double>(), 3.0 * waviness_transmission(FilterType::gaussian, 150.0 / 7),
              1e-5);
}

class SurfaceStudyInput : public ::testing::Test {
 protected:
  TempDir dir_;
};

TEST_F(SurfaceStudyInput, RunPointWritesFilteredCsvAndSummary) {
  dir_.write("p.csv", table(6000, waves));
  Study study = load_text(dir_, open_study("", "cutoff_mm = 0.8\ntype = \"robust_gaussian\"\n"));
  const auto out = run_surface_point(study, dir_.path() / "out", false);
  ASSERT_EQ(out.size(), SurfaceStudy().output_columns(study.document).size());
  const DataTable csv = read_data_table(dir_.path() / "out" / "filtered.csv");
  EXPECT_EQ(csv.names, (std::vector<std::string>{"x_mm", "profile_um", "waviness_um", "roughness_um"}));
  EXPECT_EQ(csv.rows(), 6000u);
  std::ifstream summary(dir_.path() / "out" / "summary.json");
  const Json j = Json::parse(summary);
  for (const char* key : {"Wa_um", "Wq_um", "Wz_um", "Wt_um", "Wp_um", "Wv_um", "WSm_mm", "Wsk",
                          "Wku", "Wz_five_um"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["filter"]["type"], "robust_gaussian");
  EXPECT_TRUE(j["filter"]["converged"].get<bool>());
  // 0.4 mm waves under a 0.8 mm cut-off: robust regression transmission at lambda/lc = 0.5.
  const double a = 2.0 * waviness_transmission(FilterType::robust_gaussian, 0.5);
  EXPECT_NEAR(j["Wq_um"].get<double>(), a / std::sqrt(2.0), 0.02);
}

TEST_F(SurfaceStudyInput, FilteredCsvIsStreamedAsCsvTextAndOptional) {
  dir_.write("p.csv", table(6000, waves));
  SurfaceStudy kind;
  PointContext context;
  context.plots = false;
  // Written (small profile, "auto"): the streamed file is exactly csv_text of the evaluation.
  {
    Study study = load_text(dir_, open_study("", "cutoff_mm = 0.8\n"));
    context.artifact_dir = dir_.path() / "auto";
    kind.run_point(study.point_document(0), context);
    const auto table_ptr = read_shared_data_table(dir_.path() / "p.csv");
    const SurfaceEvaluation e = evaluate_surface_profile(
        series_from(study.point_document(0).at("input"), *table_ptr, "height_um"),
        settings_from(study.point_document(0), 6000));
    std::vector<double> x, roughness;
    for (std::size_t i = 0; i < e.samples(); ++i) {
      x.push_back(e.position(i));
      roughness.push_back(e.roughness_um(i));
    }
    const std::vector<double> profile(e.profile_um.begin(), e.profile_um.end());
    std::ifstream file(dir_.path() / "auto" / "filtered.csv");
    std::stringstream text;
    text << file.rdbuf();
    EXPECT_EQ(text.str(), csv_text({"x_mm", "profile_um", "waviness_um", "roughness_um"},
                                   {x, profile, e.waviness_um, roughness}));
    std::ifstream summary(dir_.path() / "auto" / "summary.json");
    EXPECT_FALSE(Json::parse(summary).contains("filtered_csv"));
  }
  // Not written on request; the summary says why and how to get it.
  {
    Study study = load_text(dir_, open_study("", "cutoff_mm = 0.8\n\n[parameters]\nfiltered_csv = \"never\"\n"));
    context.artifact_dir = dir_.path() / "never";
    kind.run_point(study.point_document(0), context);
    EXPECT_FALSE(std::filesystem::exists(dir_.path() / "never" / "filtered.csv"));
    std::ifstream summary(dir_.path() / "never" / "summary.json");
    EXPECT_EQ(Json::parse(summary).at("filtered_csv"),
              "not written: 6000 samples, parameters.filtered_csv = \"never\" "
              "(parameters.filtered_csv = \"always\" writes it)");
  }
  EXPECT_NE(load_error(dir_, open_study("", "cutoff_mm = 0.8\n\n[parameters]\nfiltered_csv = \"sometimes\"\n"))
                .find("parameters.filtered_csv"),
            std::string::npos);
}

TEST_F(SurfaceStudyInput, TooFewSamplesPerCutoff) {
  dir_.write("p.csv", table(6000, waves));
  const std::string message = load_error(dir_, open_study("", "cutoff_mm = 0.005\n"));
  EXPECT_NE(message.find("study.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("too few samples per cut-off: 5 (cutoff_mm = 0.005 at 0.001 mm spacing"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("at least 7"), std::string::npos) << message;
}

TEST_F(SurfaceStudyInput, CutoffLongerThanTheProfile) {
  dir_.write("p.csv", table(1000, waves));
  const std::string message = load_error(dir_, open_study("", "cutoff_mm = 2.5\n"));
  EXPECT_NE(message.find("cutoff_mm = 2.5 is longer than the profile (0.999 mm"),
            std::string::npos)
      << message;
}

TEST_F(SurfaceStudyInput, NonUniformSpacingNamesTheLine) {
  std::string text = table(3000, waves, true);
  // Row 101 (file line 102) moves by 0.5 um.
  std::istringstream lines(text);
  std::string line, edited;
  for (int k = 1; std::getline(lines, line); ++k)
    edited += (k == 102 ? std::string("0.1005,0.0") : line) + "\n";
  dir_.write("p.csv", edited);
  const std::string message =
      load_error(dir_, "[study]\nkind = \"surface\"\n[input]\nfile = \"p.csv\"\ncolumn = "
                       "\"height_um\"\nx_column = \"x_mm\"\n[filter]\ncutoff_mm = 0.8\n");
  EXPECT_NE(message.find("non-uniform spacing"), std::string::npos) << message;
  EXPECT_NE(message.find("at line 102"), std::string::npos) << message;
  EXPECT_NE(message.find("study.toml:6"), std::string::npos) << message;
}

TEST_F(SurfaceStudyInput, MissingColumnListsTheColumns) {
  dir_.write("p.csv", table(3000, waves, true));
  std::string message = load_error(
      dir_, "[study]\nkind = \"surface\"\n[input]\nfile = \"p.csv\"\ncolumn = \"radius\"\n"
            "spacing_mm = 0.001\n[filter]\ncutoff_mm = 0.8\n");
  EXPECT_NE(message.find("input.column = \"radius\""), std::string::npos) << message;
  EXPECT_NE(message.find("no column 'radius'"), std::string::npos) << message;
  EXPECT_NE(message.find("x_mm"), std::string::npos) << message;
  // Two columns and no `column`: which one is the profile?
  message = load_error(dir_, "[study]\nkind = \"surface\"\n[input]\nfile = \"p.csv\"\n"
                             "spacing_mm = 0.001\n[filter]\ncutoff_mm = 0.8\n");
  EXPECT_NE(message.find("missing key 'input.column'"), std::string::npos) << message;
}

TEST_F(SurfaceStudyInput, ClosedProfileKeys) {
  dir_.write("p.csv", table(3600, lobes));
  const std::string head =
      "[study]\nkind = \"surface\"\n[input]\nfile = \"p.csv\"\ncolumn = \"height_um\"\n"
      "closed = true\n";
  std::string message = load_error(dir_, head + "samples_per_rev = 3000\n");
  EXPECT_NE(message.find("input.samples_per_rev = 3000"), std::string::npos) << message;
  EXPECT_NE(message.find("3600 rows"), std::string::npos) << message;
  message = load_error(dir_, head + "[filter]\ncutoff_mm = 0.8\n");
  EXPECT_NE(message.find("use cutoff_upr"), std::string::npos) << message;
  // With the circumferential spacing a cut-off in mm converts: 3600 x 0.1 mm / 7.2 mm = 50 UPR.
  {
    Study study = load_text(dir_, head + "spacing_mm = 0.1\n[filter]\ncutoff_mm = 7.2\n");
    run_surface_point(study, dir_.path() / "converted", false);
    std::ifstream in(dir_.path() / "converted" / "summary.json");
    const Json j = Json::parse(in);
    EXPECT_NEAR(j["filter"]["cutoff_upr"].get<double>(), 50.0, 1e-9);
    EXPECT_NEAR(j["filter"]["circumference_mm"].get<double>(), 360.0, 1e-9);
  }
  // A column given by its 1-based index as a number.
  EXPECT_EQ(load_text(dir_, "[study]\nkind = \"surface\"\n[input]\nfile = \"p.csv\"\ncolumn = 1\n"
                            "closed = true\n").document["input"]["column"], "1");
  message = load_error(dir_, head + "[filter]\ncutoff_upr = 600\n");
  EXPECT_NE(message.find("too few samples per cut-off: 6 (cutoff_upr = 600 on 3600 samples per "
                         "revolution; at least 7 needed"),
            std::string::npos)
      << message;
  message = load_error(dir_, head + "[process]\nwheel_speed_rpm = 1450\n");
  EXPECT_NE(message.find("needs both"), std::string::npos) << message;
  // Defaults: 50 UPR Gaussian, values in um.
  Study study = load_text(dir_, head + "samples_per_rev = 3600\n");
  EXPECT_EQ(study.document["filter"]["type"], "gaussian");
  EXPECT_EQ(study.document["input"]["unit"], "um");
}

TEST_F(SurfaceStudyInput, OpenProfileKeys) {
  dir_.write("p.csv", table(3000, waves));
  std::string message = load_error(dir_, open_study("", ""));
  EXPECT_NE(message.find("missing key 'filter.cutoff_mm'"), std::string::npos) << message;
  message = load_error(dir_, open_study("", "cutoff_mm = 0.8\n[process]\nwheel_speed_rpm = 1\n"
                                            "work_speed_rpm = 1\n"));
  EXPECT_NE(message.find("need a closed"), std::string::npos) << message;
  message = load_error(dir_, open_study("unit = \"inch\"\n", "cutoff_mm = 0.8\n"));
  EXPECT_NE(message.find("input.unit"), std::string::npos) << message;
  message = load_error(dir_, "[study]\nkind = \"surface\"\n[input]\nfile = \"absent.csv\"\n");
  EXPECT_NE(message.find("absent.csv: no such file"), std::string::npos) << message;
}

}  // namespace
}  // namespace chatterlab::surface

namespace chatterlab::surface {
namespace {

// The polar roundness plot draws the minimum zone as its two circles (RONt apart, the zone's
// centre), and the waviness lies between them, touching both (issue 20).
TEST(SurfaceBandsPlot, ALongProfilesSpectrumIsDrawnBoundedWithItsPeaks) {
  // 100,000 radii in one revolution: 50,000 spectral lines. The Wz|f plot draws each of ~4000
  // log-spaced bins as its largest line, so the 26 UPR lobes, the 895 UPR chatter and a lone
  // 30,000 UPR line all stay in the plot while the number of impulses stays bounded.
  TempDir dir;
  const std::size_t n = 100000;
  {
    std::ofstream csv(dir.path() / "radii.csv");
    csv << "radius_um\n";
    for (std::size_t i = 0; i < n; ++i) {
      const double t = 2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n);
      csv << 0.8 * std::sin(26 * t) + 0.05 * std::sin(895 * t) + 0.01 * std::sin(30000 * t) << "\n";
    }
    std::ofstream toml(dir.path() / "bands.toml");
    toml << "[study]\nkind = \"surface\"\n[input]\nfile = \"radii.csv\"\ncolumn = \"radius_um\"\n"
            "closed = true\nsamples_per_rev = " << n << "\nunit = \"um\"\n"
            "[filter]\ntype = \"gaussian\"\ncutoff_upr = 50\n"
            "[process]\nwheel_speed_rpm = 1450\nwork_speed_rpm = 55\n";
  }
  const Study study = load_study(dir.path() / "bands.toml");
  run_surface_point(study, dir.path() / "out", true);
  std::ifstream dat(dir.path() / "out" / "wz_f_bands.dat");
  ASSERT_TRUE(dat) << "no wz_f_bands.dat (gnuplot missing?)";
  std::size_t impulses = 0;
  std::map<long, double> line;  // UPR -> amplitude
  for (std::string text; std::getline(dat, text);) {
    if (text.empty() || text[0] == '#') continue;
    std::istringstream in(text);
    double upr = 0, amplitude = 0;
    in >> upr >> amplitude;
    ++impulses;
    line[std::lround(upr)] = amplitude;
  }
  EXPECT_LT(impulses, 4100u);
  EXPECT_GT(impulses, 1000u);
  EXPECT_NEAR(line[26], 0.8, 1e-6);
  EXPECT_NEAR(line[895], 0.05, 1e-6);
  EXPECT_NEAR(line[30000], 0.01, 1e-6);
}

TEST(SurfacePolarPlot, MinimumZoneDrawsBothCirclesAroundTheProfile) {
  TempDir dir;
  const Study study = load_study(std::filesystem::path(CHATTERLAB_SOURCE_DIR) / "studies" / "surface_roundness.toml");
  run_surface_point(study, dir.path() / "out", true);
  std::ifstream summary_file(dir.path() / "out" / "summary.json");
  const Json rd = Json::parse(summary_file).at("roundness");
  std::ifstream dat(dir.path() / "out" / "polar.dat");
  ASSERT_TRUE(dat) << "no polar.dat (gnuplot missing?)";
  // Series blocks: "# series i: label", then x y lines ("NaN NaN" breaks a line).
  std::vector<std::vector<std::pair<double, double>>> series;
  std::vector<std::string> labels;
  for (std::string line; std::getline(dat, line);) {
    if (line.rfind("# series ", 0) == 0) {
      series.emplace_back();
      labels.push_back(line.substr(line.find(':') + 2));
    } else if (!line.empty() && line[0] != '#' && !series.empty()) {
      std::istringstream in(line);
      std::string x, y;
      in >> x >> y;
      series.back().emplace_back(x == "NaN" ? std::nan("") : std::stod(x), y == "NaN" ? std::nan("") : std::stod(y));
    }
  }
  ASSERT_EQ(labels.back().rfind("minimum zone: two circles", 0), 0u) << labels.back();
  EXPECT_EQ(series.back().size(), 2u * 361 + 1);  // outer, break, inner
  EXPECT_TRUE(std::isnan(series.back()[361].first));
  // Radii in the plot about the least-squares centre: base + limacon(c) -+ RONt/2 - limacon(LS).
  const Json& ls = rd.at("least_squares");
  const Json& mz = rd.at("minimum_zone");
  const double half = 0.5 * mz.at("RONt_um").get<double>();
  const double base = 2.0 * ls.at("RONt_um").get<double>();
  auto limacon = [](const Json& c, double th) {
    return c.at("radius_offset_um").get<double>() + c.at("centre_x_um").get<double>() * std::cos(th) +
           c.at("centre_y_um").get<double>() * std::sin(th);
  };
  double outer_gap = 1e300, inner_gap = 1e300;
  for (const auto& [x, y] : series.front()) {  // the waviness
    const double th = std::atan2(y, x), rho = std::hypot(x, y);
    const double mid = base + limacon(mz, th) - limacon(ls, th);
    EXPECT_LE(rho, mid + half + 1e-6);
    EXPECT_GE(rho, mid - half - 1e-6);
    outer_gap = std::min(outer_gap, mid + half - rho);
    inner_gap = std::min(inner_gap, rho - (mid - half));
  }
  EXPECT_LT(outer_gap, 0.05 * half);  // the profile touches both circles (sampled every few points)
  EXPECT_LT(inner_gap, 0.05 * half);
}

}  // namespace
}  // namespace chatterlab::surface
