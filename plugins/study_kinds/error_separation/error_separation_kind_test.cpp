// The `error_separation` study kind end to end (load_study -> run_point -> files): exact
// separation of synthetic probe data written as CSV, the suppressed-harmonic report and its
// "error" mode, the shipped studies against the true profile stated in their headers, and bad
// input with the message text.
#include "study_kinds/error_separation/error_separation_kind.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "study_kinds/error_separation/error_separation.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/signal_io.hpp"
#include "chatterlab/study.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
constexpr double pi = std::numbers::pi;

// The form of the shipped studies (studies/data/make_error_separation_data.py).
double true_r(double th) {
  return 2.0 * std::cos(3 * th + 0.5) + 1.0 * std::cos(5 * th) + 0.5 * std::sin(18 * th) +
         0.3 * std::cos(40 * th + 1);
}

// Probe data for probes at `angles_deg` (any angles: the form is a trigonometric polynomial),
// n samples x revolutions; the part has a mean offset and eccentricity, the spindle moves.
std::string probe_csv(const std::vector<double>& angles_deg, std::size_t n,
                      std::size_t revolutions = 1, const std::string& header = "A,B,C") {
  std::ostringstream out;
  out.precision(17);
  out << header << "\n";
  for (std::size_t rev = 0; rev < revolutions; ++rev)
    for (std::size_t i = 0; i < n; ++i) {
      const double th = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
      const double dx = 1.5 * std::cos(2 * th) + 0.8 * std::sin(7 * th);
      const double dy = 1.2 * std::sin(2 * th + 0.4) - 0.5 * std::cos(4 * th);
      for (std::size_t q = 0; q < angles_deg.size(); ++q) {
        const double phi = angles_deg[q] * pi / 180;
        const double y = 5.0 + true_r(th + phi) + 10 * std::cos(th + phi - 0.3) +
                         dx * std::cos(phi) + dy * std::sin(phi);
        out << (q ? "," : "") << y;
      }
      out << "\n";
    }
  return out.str();
}

std::string study_text(const std::string& probes_table, const std::string& input_extra = "") {
  return "[study]\nkind = \"error_separation\"\n\n[input]\nfile = \"probes.csv\"\n"
         "columns = [\"A\", \"B\", \"C\"]\n" +
         input_extra + "\n[probes]\n" + probes_table;
}

Json read_json(const fs::path& file) {
  std::ifstream in(file);
  return Json::parse(in);
}

std::vector<Json> run_single(const Study& study, const fs::path& out) {
  const ErrorSeparationKind kind;
  PointContext context;
  context.artifact_dir = out;
  context.plots = false;
  return kind.run_point(study.point_document(0), context);
}

TEST(ErrorSeparationKind, ExactOnNoiseFreeProbeData) {
  TempDir dir;
  const std::size_t n = 256;
  // Offsets 71 and 144 samples: angles 99.84375 and 202.5 degrees.
  dir.write("probes.csv", probe_csv({0, 99.84375, 202.5}, n, 3));
  const Study study =
      load_text(dir, study_text("angles_deg = [0, 99.84375, 202.5]\n", "samples_per_rev = 256\n"));
  const fs::path out = dir.path() / "out";
  const auto row = run_single(study, out);

  const DataTable profile = read_data_table(out / "profile.csv");
  ASSERT_EQ(profile.rows(), n);
  double err = 0, norm = 0, lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < n; ++i) {
    const double want = true_r(2 * pi * static_cast<double>(i) / static_cast<double>(n));
    err = std::max(err, std::abs(profile.column("deviation_um")[i] - want));
    norm = std::max(norm, std::abs(want));
    lo = std::min(lo, want);
    hi = std::max(hi, want);
  }
  EXPECT_LE(err, 1e-9 * norm);
  const DataTable spindle = read_data_table(out / "spindle.csv");
  for (std::size_t i = 0; i < n; i += 13) {
    const double th = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
    EXPECT_NEAR(spindle.column("dx_um")[i],
                1.5 * std::cos(2 * th) + 0.8 * std::sin(7 * th) + 10 * std::cos(th - 0.3), 1e-9);
    EXPECT_NEAR(spindle.column("dy_um")[i],
                1.2 * std::sin(2 * th + 0.4) - 0.5 * std::cos(4 * th) - 10 * std::sin(th - 0.3),
                1e-9);
  }
  const Json summary = read_json(out / "summary.json");
  EXPECT_TRUE(summary.at("suppressed_harmonics").empty());
  EXPECT_EQ(summary.at("revolutions"), 3);
  EXPECT_TRUE(summary.at("first_harmonic_check").at("valid").get<bool>());
  EXPECT_NEAR(summary.at("roundness_um").get<double>(), hi - lo, 1e-9);
  EXPECT_NEAR(summary.at("mean_radius_offset_um").get<double>(), 5.0, 1e-9);
  EXPECT_TRUE(summary.at("angle_optimisation").at("found").get<bool>());
  EXPECT_NEAR(row[0].get<double>(), hi - lo, 1e-9);
  EXPECT_EQ(row[2], 0);
  EXPECT_TRUE(fs::exists(out / "transfer.csv"));
}

TEST(ErrorSeparationKind, SuppressedHarmonicsAreReportedOrRefused) {
  TempDir dir;
  // N = 360, offsets 0, 30, 100: gcd 10 -> harmonics 36k +/- 1 suppressed.
  dir.write("probes.csv", probe_csv({0, 30, 100}, 360));
  const Study study = load_text(dir, study_text("angles_deg = [0, 30, 100]\n"));
  const auto row = run_single(study, dir.path() / "out");
  const Json summary = read_json(dir.path() / "out" / "summary.json");
  const auto suppressed = summary.at("suppressed_harmonics").get<std::vector<int>>();
  ASSERT_GE(suppressed.size(), 4u);
  EXPECT_EQ(suppressed[0], 35);
  EXPECT_EQ(suppressed[1], 37);
  EXPECT_EQ(suppressed[2], 71);
  EXPECT_EQ(suppressed[3], 73);
  EXPECT_EQ(row[2], suppressed.size());
  EXPECT_EQ(row[3], "inf");  // worst Q over the band: infinite at a lost harmonic
  EXPECT_EQ(row[5], "degraded");
  EXPECT_EQ(summary.at("status"), "degraded");
  EXPECT_EQ(summary.at("transfer").at("worst_error_transfer_q"), "inf");
  EXPECT_TRUE(summary.at("transfer").at("worst_error_transfer_q_seen").is_number());
  ASSERT_FALSE(summary.at("warnings").empty());
  EXPECT_NE(summary.at("warnings")[0].get<std::string>().find("harmonics 35, 37, 71"),
            std::string::npos);
  // The true form has harmonics 3, 5, 18, 40: none suppressed, so the profile is still exact.
  const DataTable profile = read_data_table(dir.path() / "out" / "profile.csv");
  for (std::size_t i = 0; i < 360; i += 7)
    EXPECT_NEAR(profile.column("deviation_um")[i], true_r(2 * pi * static_cast<double>(i) / 360),
                1e-9);

  const std::string message = testing::load_error(
      dir, study_text("angles_deg = [0, 30, 100]\non_suppressed = \"error\"\n"));
  EXPECT_NE(message.find("study.toml:"), std::string::npos) << message;
  EXPECT_NE(message.find("harmonics 35, 37, 71, 73"), std::string::npos) << message;
  EXPECT_NE(message.find("on_suppressed = \"error\""), std::string::npos) << message;
}

TEST(ErrorSeparationKind, TimeRecursionAndNPointAgreeWithTheFrequencyMethod) {
  TempDir dir;
  dir.write("probes.csv", probe_csv({0, 97, 194}, 360));
  const auto frequency =
      run_single(load_text(dir, study_text("angles_deg = [0, 97, 194]\n")), dir.path() / "f");
  const auto recursion = run_single(
      load_text(dir, study_text("angles_deg = [0, 97, 194]\nmethod = \"time_recursion\"\n")),
      dir.path() / "t");
  EXPECT_NEAR(frequency[0].get<double>(), recursion[0].get<double>(), 1e-9);
  const DataTable f = read_data_table(dir.path() / "f" / "profile.csv");
  const DataTable t = read_data_table(dir.path() / "t" / "profile.csv");
  for (std::size_t i = 0; i < 360; ++i)
    EXPECT_NEAR(f.column("deviation_um")[i], t.column("deviation_um")[i], 1e-9);
  EXPECT_GE(read_json(dir.path() / "t" / "summary.json").at("recursion_passes").get<int>(), 1);

  // Four probes, balanced weights.
  dir.write("probes.csv", probe_csv({0, 97, 194, 260}, 360, 1, "A,B,C,D"));
  const std::string four =
      "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\n"
      "columns = [\"A\", \"B\", \"C\", \"D\"]\n[probes]\nangles_deg = [0, 97, 194, 260]\n"
      "method = \"n_point\"\n";
  run_single(load_text(dir, four), dir.path() / "n");
  const DataTable np = read_data_table(dir.path() / "n" / "profile.csv");
  for (std::size_t i = 0; i < 360; i += 5)
    EXPECT_NEAR(np.column("deviation_um")[i], true_r(2 * pi * static_cast<double>(i) / 360), 1e-9);
}

TEST(ErrorSeparationKind, TwoPointApproximation) {
  // Probes at 0 and 180 - 360/N degrees; the form has harmonics 3, 5, 18, 40. Even harmonics
  // come out within ~pi/N (E5), so the 18- and 40-UPR content of the profile is close while the
  // odd 3 and 5 are not: compare the 18/40 part through the profile's spectrum.
  TempDir dir;
  const std::size_t n = 360;
  dir.write("probes.csv", probe_csv({0, 179}, n, 1, "A,C"));
  const std::string text = "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\n"
                           "columns = [\"A\", \"C\"]\n[probes]\nangles_deg = [0, 179]\nmethod = \"two_point\"\n";
  run_single(load_text(dir, text), dir.path() / "out");
  const Json summary = read_json(dir.path() / "out" / "summary.json");
  EXPECT_EQ(summary.at("method"), "two_point");
  EXPECT_EQ(summary.at("layout_angles_deg").size(), 3u);  // the three-point layout behind it
  const DataTable profile = read_data_table(dir.path() / "out" / "profile.csv");
  for (int l : {18, 40}) {
    double a = 0, b = 0;  // Fourier coefficients of harmonic l
    for (std::size_t i = 0; i < n; ++i) {
      const double th = 2 * pi * static_cast<double>(i) / static_cast<double>(n);
      a += 2.0 / n * profile.column("deviation_um")[i] * std::cos(l * th);
      b += 2.0 / n * profile.column("deviation_um")[i] * std::sin(l * th);
    }
    const double amplitude = std::hypot(a, b), want = l == 18 ? 0.5 : 0.3;
    EXPECT_NEAR(amplitude, want, 0.015 * want) << "harmonic " << l;
  }
}

// Probes at 0, 90, 180 degrees on the shipped form (harmonics 3, 5, 18, 40): the odd 3 and 5 are
// lost. The run is degraded, says so everywhere (summary, results row, warning, transfer.csv),
// and proposes a layout that sees the band.
TEST(ErrorSeparationKind, OppositeProbeLayoutIsDegraded) {
  TempDir dir;
  dir.write("probes.csv", probe_csv({0, 90, 180}, 360));
  const Study study = load_text(dir, study_text("angles_deg = [0, 90, 180]\n"));
  const fs::path out = dir.path() / "out";
  const auto row = run_single(study, out);
  const Json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary.at("status"), "degraded");
  EXPECT_EQ(row[5], "degraded");
  EXPECT_EQ(row[3], "inf");
  EXPECT_EQ(summary.at("lost_harmonics").at("count"), 89);
  EXPECT_EQ(summary.at("suppressed_harmonics").size(), 89u);
  // The probes hold amplitude 2 at l = 3 and 1 at l = 5 (lost) and 0.5 at 18, 0.3 at 40 (seen),
  // plus the spindle's 2, 4 and 7 (dx, dy seen through cos/sin of the probe angle): the lost
  // share is what those amplitudes say, computed here independently.
  double lost = 0, band = 0;
  for (int l : {3, 5, 7, 2, 4, 18, 40}) {
    double a = 0;  // mean over the probes of the amplitude at l
    for (double phi_deg : {0.0, 90.0, 180.0}) {
      const double phi = phi_deg * pi / 180;
      double c = 0, s = 0;  // cos / sin coefficients of the probe signal at l
      for (std::size_t i = 0; i < 360; ++i) {
        const double th = 2 * pi * static_cast<double>(i) / 360;
        const double dx = 1.5 * std::cos(2 * th) + 0.8 * std::sin(7 * th);
        const double dy = 1.2 * std::sin(2 * th + 0.4) - 0.5 * std::cos(4 * th);
        const double y = true_r(th + phi) + dx * std::cos(phi) + dy * std::sin(phi);
        c += y * std::cos(l * th) * 2 / 360;
        s += y * std::sin(l * th) * 2 / 360;
      }
      a += std::hypot(c, s) / 3;
    }
    band += a * a;
    if (l % 2 == 1) lost += a * a;
  }
  EXPECT_NEAR(summary.at("lost_harmonics").at("lost_share_of_probe_power").get<double>(), lost / band, 1e-9);
  EXPECT_NEAR(row[6].get<double>(), 100 * lost / band, 1e-7);
  EXPECT_GT(lost / band, 0.5);
  // The separated roundness misses harmonics 3 and 5: it is far below the form's.
  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < 3600; ++i) {
    const double v = true_r(2 * pi * static_cast<double>(i) / 3600);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_LT(row[0].get<double>(), 0.7 * (hi - lo));
  // transfer.csv: a row per harmonic 2..180, the lost ones with infinite W and Q ("inf", which
  // the project's own table reader refuses as a number: read as text).
  std::ifstream csv(out / "transfer.csv");
  std::string header, l2, l3;
  std::getline(csv, header);
  std::getline(csv, l2);
  std::getline(csv, l3);
  EXPECT_EQ(header, "harmonic,abs_g,amplitude_transfer_w,error_transfer_q,lost");
  EXPECT_EQ(l3.substr(0, 2), "3,");
  EXPECT_EQ(l3.substr(l3.size() - 9), "inf,inf,1") << l3;
  EXPECT_EQ(l2.substr(l2.size() - 2), ",0") << l2;
  std::size_t rows = 2;
  for (std::string line; std::getline(csv, line);) rows += line.empty() ? 0 : 1;
  EXPECT_EQ(rows, 179u);
  // The warning says degraded, the lost share and a layout that sees the band.
  ASSERT_FALSE(summary.at("warnings").empty());
  const std::string warning = summary.at("warnings")[0].get<std::string>();
  EXPECT_NE(warning.find("degraded: harmonics 3, 5, 7"), std::string::npos) << warning;
  EXPECT_NE(warning.find(fmt::format("{:.1f} % of the probe signals' power", 100 * lost / band)),
            std::string::npos) << warning;
  EXPECT_NE(warning.find("see every harmonic 2..50"), std::string::npos) << warning;
  const Json& opt = summary.at("angle_optimisation");
  EXPECT_TRUE(opt.at("found").get<bool>());
  EXPECT_EQ(opt.at("this_layout_worst_q"), "inf");
  EXPECT_EQ(opt.at("this_layout_lost_harmonics"), 24);  // odd 3..49
}

TEST(ErrorSeparationKind, ShippedStudiesReproduceTheirStatedTruth) {
  const fs::path studies = fs::path(CHATTERLAB_SOURCE_DIR) / "studies";
  TempDir dir;
  run_single(load_study(studies / "error_separation_three_probe.toml"), dir.path() / "three");
  const DataTable profile = read_data_table(dir.path() / "three" / "profile.csv");
  for (std::size_t i = 0; i < 360; ++i)
    EXPECT_NEAR(profile.column("deviation_um")[i], true_r(2 * pi * static_cast<double>(i) / 360),
                1e-9);

  // Noisy (sigma = 0.2 um per probe), 8 revolutions averaged, time recursion, FIR 50/100 UPR: the
  // residual noise of the profile is what the error transfer predicts (E2, E3):
  // RMS^2 = (sigma^2 / M) (1/N) sum_l Q(l)^2 H(l)^2 over l = 2..N-2 (both signs of l).
  run_single(load_study(studies / "error_separation_averaged.toml"), dir.path() / "avg");
  const DataTable averaged = read_data_table(dir.path() / "avg" / "profile.csv");
  double rms = 0;
  for (std::size_t i = 0; i < 360; ++i) {
    const double d =
        averaged.column("deviation_um")[i] - true_r(2 * pi * static_cast<double>(i) / 360);
    rms += d * d / 360;
  }
  const DataTable transfer = read_data_table(dir.path() / "avg" / "transfer.csv");
  const auto h = error_separation::fir_response(
      error_separation::design_zero_phase_lowpass(50, 100, 360), 360);
  ASSERT_EQ(transfer.rows(), 179u);  // harmonics 2..180, none lost
  EXPECT_EQ(read_json(dir.path() / "avg" / "summary.json").at("status"), "ok");
  double predicted = 0;
  for (std::size_t row = 0; row < transfer.rows(); ++row) {
    const auto l = static_cast<std::size_t>(transfer.column("harmonic")[row]);
    const double q = transfer.column("error_transfer_q")[row] * h[l];
    predicted += (l == 180 ? 1.0 : 2.0) * q * q;
  }
  predicted = 0.2 / std::sqrt(8.0) * std::sqrt(predicted / 360);
  EXPECT_NEAR(std::sqrt(rms), predicted, 0.25 * predicted);

  const auto row =
      run_single(load_study(studies / "error_separation_cylinder.toml"), dir.path() / "cyl");
  const DataTable sections = read_data_table(dir.path() / "cyl" / "sections.csv");
  ASSERT_EQ(sections.rows(), 5u);
  for (std::size_t j = 0; j < 5; ++j) {
    const double z = sections.column("z_mm")[j];
    EXPECT_NEAR(sections.column("mean_radius_difference_um")[j], 3 + 0.01 * z, 1e-8);
    EXPECT_NEAR(sections.column("centre_x_um")[j], 2 + 0.05 * z, 1e-8);
    EXPECT_NEAR(sections.column("centre_y_um")[j], -1 + 0.0005 * z * z, 1e-8);
    EXPECT_NEAR(sections.column("straightness_u_um")[j], 0.3 * std::sin(z / 25), 1e-8);
    EXPECT_NEAR(sections.column("straightness_v_um")[j], 0.2 * z / 80, 1e-8);
  }
  EXPECT_GT(row.back().get<double>(), 0.0);  // cylindricity_um
  EXPECT_TRUE(fs::exists(dir.path() / "cyl" / "cylinder.csv"));
}

TEST(ErrorSeparationKind, BadInputIsRefusedWithItsReason) {
  TempDir dir;
  dir.write("probes.csv", probe_csv({0, 99, 202}, 360));
  auto error = [&](const std::string& text) { return testing::load_error(dir, text); };
  auto expect_in = [](const std::string& message, const std::string& part) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  };

  std::string m = error(
      "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\n"
      "columns = [\"A\", \"B\", \"D\"]\n[probes]\nangles_deg = [0, 99, 202]\n");
  expect_in(m, "study.toml:5: input.columns: no column \"D\" in");
  expect_in(m, "(columns: A, B, C)");

  // Integer columns are 1-based indices, as "4" would be: probes.csv has three.
  m = error(
      "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\n"
      "columns = [1, 2, 4]\n[probes]\nangles_deg = [0, 99, 202]\n");
  expect_in(m, "study.toml:5: input.columns: no column \"4\" in");
  const Study by_index = testing::load_text(
      dir, "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\n"
           "columns = [1, 2, 3]\n[probes]\nangles_deg = [0, 99, 202]\n");
  EXPECT_EQ(by_index.document.at("input").at("columns"), Json({"1", "2", "3"}));

  m = error(study_text("angles_deg = [0, 99]\n"));
  expect_in(m, "probes.angles_deg = [0, 99]: 2 angles for 3 input.columns");

  m = error(study_text("angles_deg = [0, 99, 202]\n", "samples_per_rev = 100\n"));
  expect_in(
      m, "input.samples_per_rev = 100: the data have 360 rows, not a whole number of revolutions");

  dir.write("short.csv", "X\n1\n2\n3\n4\n5\n6\n7\n8\n9\n");
  dir.write("long.csv", "X\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n");
  m = error(
      "[study]\nkind = \"error_separation\"\n[input]\nfiles = [\"short.csv\", \"short.csv\", "
      "\"long.csv\"]\n"
      "columns = [\"X\", \"X\", \"X\"]\n[probes]\nangles_deg = [0, 99, 202]\n");
  expect_in(m, "input.files: probe signals differ in length");
  expect_in(m, "has 9 rows");
  expect_in(m, "has 10 rows");

  m = error(study_text("angles_deg = [0, 90, 180]\nmethod = \"time_recursion\"\n"));
  expect_in(m, "shares the factor 90 with samples_per_rev = 360");

  m = error(study_text("angles_deg = [0, 99, 198]\nmethod = \"time_recursion\"\n"));
  expect_in(m, "shares the factor 9");

  m = error(study_text("angles_deg = [0.5, 97.5, 194.5]\nmethod = \"time_recursion\"\n"));
  expect_in(m, "equally spaced probes 0, p, 2p whole samples apart (one sample = 1 deg)");

  m = error(
      "[study]\nkind = \"error_separation\"\n[input]\nfile = \"probes.csv\"\ncolumns = [\"A\", "
      "\"C\"]\n"
      "[probes]\nangles_deg = [0, 178]\nmethod = \"two_point\"\n");
  expect_in(m, "the two probes must be 180 - 360/N = 179 deg apart (N = 360), not 178");

  m = error(study_text("angles_deg = [0, 90, 270]\n"));
  expect_in(m, "opposite each other");

  m = error(study_text("angles_deg = [0, 99, 202]\nmethod = \"n_point\"\nweights = [1, 1, 1]\n"));
  expect_in(m, "they do not cancel spindle motion");

  m = error(study_text("angles_deg = [0, 99, 202]\n") +
            "[separation]\nfir_passband_upr = 50\nfir_stopband_upr = 51\n");
  expect_in(m, "separation.fir_passband_upr = 50: FIR:");

  m = error(study_text("angles_deg = [0, 99, 202]\n") + "[separation]\nmax_harmonic = 500\n");
  expect_in(m, "separation.max_harmonic = 500: out of range, must be <= N/2 = 180");

  m = error(study_text("angles_deg = [0, 99, 202]\n", "colums = 3\n"));
  expect_in(m, "unknown key 'input.colums'");

  m = error(
      "[study]\nkind = \"error_separation\"\n[input]\nfile = \"missing.csv\"\ncolumns = [\"A\", "
      "\"B\", \"C\"]\n"
      "[probes]\nangles_deg = [0, 99, 202]\n");
  expect_in(m, "input.file:");
  expect_in(m, "missing.csv: no such file");
}

}  // namespace
}  // namespace chatterlab
