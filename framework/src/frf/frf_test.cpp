// FRF input: CSV with units in the header and UFF dataset 58 (ASCII, binary both byte orders,
// single and double precision, even and uneven abscissa, dataset 164 units), conversions from
// mobility and accelerance, the interpolant, and the messages of bad files.
#include "chatterlab/frf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "unit/frf_test_support.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using testing::TempDir;
using testing::input_error_of;

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::vector<FittedMode> two_modes() {
  FittedMode a, b;
  a.frequency_hz = 100.0, a.damping_ratio = 0.03, a.stiffness_n_per_m = 5e7;
  b.frequency_hz = 180.0, b.damping_ratio = 0.05, b.stiffness_n_per_m = 1e8;
  return {a, b};
}

void expect_same_frf(const MeasuredFrf& a, const MeasuredFrf& b, double relative) {
  ASSERT_EQ(a.frequency_hz.size(), b.frequency_hz.size());
  for (std::size_t i = 0; i < a.frequency_hz.size(); ++i) {
    EXPECT_NEAR(a.frequency_hz[i], b.frequency_hz[i], 1e-9 * b.frequency_hz[i]);
    EXPECT_LE(std::abs(a.receptance_m_per_n[i] - b.receptance_m_per_n[i]),
              relative * std::abs(b.receptance_m_per_n[i]))
        << "at " << b.frequency_hz[i] << " Hz";
  }
}

TEST(FrfCsv, RealAndImaginaryReceptanceInMicrometresPerNewton) {
  const std::string text =
      "# tap test, x direction\n"
      "frequency [Hz], real [um/N], imag [um/N], coherence [1]\n"
      "0, 0.02, 0, 0.5\n"  // a 0 Hz line is skipped
      "10, 0.020, -0.001, 0.99\n20, 0.021, -0.002, 0.98\n30, 0.022, -0.004, 0.97\n40, 0.024, -0.008, 0.96\n";
  const MeasuredFrf frf = parse_frf_csv(text, "tap.csv");
  ASSERT_EQ(frf.frequency_hz.size(), 4u);
  EXPECT_EQ(frf.frequency_hz[0], 10.0);
  EXPECT_DOUBLE_EQ(frf.receptance_m_per_n[3].real(), 0.024e-6);
  EXPECT_DOUBLE_EQ(frf.receptance_m_per_n[3].imag(), -0.008e-6);
  EXPECT_EQ(frf.coherence, (std::vector<double>{0.99, 0.98, 0.97, 0.96}));
  EXPECT_EQ(frf.description, "tap test, x direction");
  EXPECT_EQ(frf.measured_as, FrfQuantity::receptance);
}

// The same modes written as mobility (magnitude, phase in degrees) and accelerance in g/N read back
// as the same receptance.
TEST(FrfCsv, MobilityAndAccelerancePolarFormsConvertToReceptance) {
  const MeasuredFrf truth = testing::synthetic_frf(two_modes(), 50.0, 250.0, 2.0);
  std::string mobility = "frequency [Hz]; magnitude [(mm/s)/N]; phase [deg]\n";
  std::string accelerance = "freq [kHz], re [g/N], im [g/N]\n";
  for (std::size_t i = 0; i < truth.frequency_hz.size(); ++i) {
    const double f = truth.frequency_hz[i], w = kTwoPi * f;
    const Complex y = Complex(0.0, w) * truth.receptance_m_per_n[i] * 1e3;  // mm/s per N
    const Complex a = -w * w * truth.receptance_m_per_n[i] / 9.80665;
    mobility += fmt::format("{}; {:.17g}; {:.17g}\n", f, std::abs(y), std::arg(y) * 180.0 / std::numbers::pi);
    accelerance += fmt::format("{:.17g}, {:.17g}, {:.17g}\n", f / 1e3, a.real(), a.imag());
  }
  const MeasuredFrf from_mobility = parse_frf_csv(mobility, "y.csv");
  EXPECT_EQ(from_mobility.measured_as, FrfQuantity::mobility);
  expect_same_frf(from_mobility, truth, 1e-12);
  const MeasuredFrf from_accelerance = parse_frf_csv(accelerance, "a.csv");
  EXPECT_EQ(from_accelerance.measured_as, FrfQuantity::accelerance);
  expect_same_frf(from_accelerance, truth, 1e-12);
}

TEST(FrfCsv, BadFilesNameFileLineColumnAndValue) {
  auto error = [](const std::string& text) {
    return input_error_of([&] { parse_frf_csv(text, "m.csv"); });
  };
  const std::string header = "frequency [Hz], real [m/N], imag [m/N]\n";
  std::string e = error(header + "10, 1e-8, 0\n20, 1e-8, x\n");
  EXPECT_NE(e.find("m.csv:3: column 'imag' = 'x': expected a finite number"), std::string::npos) << e;
  e = error(header + "10, 1e-8, 0\n20, 1e-8, 0\n15, 1e-8, 0\n");
  EXPECT_NE(e.find("m.csv:4: frequency 15 Hz is not above the previous line's 20 Hz (line 3)"), std::string::npos) << e;
  e = error(header + "10, 1e-8\n");
  EXPECT_NE(e.find("m.csv:2: 2 fields, but the header names 3 columns"), std::string::npos) << e;
  e = error("frequency [Hz], real [m/N], imag [mm/N]\n10,0,0\n");
  EXPECT_NE(e.find("m.csv:1: columns 'real' and 'imag' have different units ('m/N' and 'mm/N')"), std::string::npos) << e;
  e = error("frequency [Hz], real [m/s], imag [m/s]\n");
  EXPECT_NE(e.find("m.csv:1: column 'real': unit 'm/s' is not a receptance, mobility or accelerance unit"),
            std::string::npos) << e;
  e = error("frequency, real [m/N], imag [m/N]\n");
  EXPECT_NE(e.find("m.csv:1: column 'frequency': unit '' is not a frequency unit (Hz, kHz, rad/s)"), std::string::npos) << e;
  e = error("frequency [Hz], real [m/N], phase [deg]\n");
  EXPECT_NE(e.find("m.csv:1: the values need either a real and an imag column or a magnitude and a phase column, not "
                   "frequency, real, phase"),
            std::string::npos) << e;
  e = error("frequency [Hz], real [m/N], imag [m/N], temperature [K]\n");
  EXPECT_NE(e.find("m.csv:1: column 'temperature' is not an FRF column"), std::string::npos) << e;
  e = error(header + "10, 1e-8, 0\n20, 1e-8, 0\n");
  EXPECT_NE(e.find("m.csv: 2 frequency lines above 0 Hz; an FRF needs at least 4"), std::string::npos) << e;
  e = error("# only a comment\n");
  EXPECT_NE(e.find("m.csv: no header row"), std::string::npos) << e;
}

TEST(FrfUff58, EveryEncodingRoundTrips) {
  const MeasuredFrf truth = testing::synthetic_frf(two_modes(), 50.0, 250.0, 0.5);
  for (UffEncoding encoding : {UffEncoding::ascii, UffEncoding::binary_little_endian, UffEncoding::binary_big_endian})
    for (FrfQuantity quantity : {FrfQuantity::receptance, FrfQuantity::mobility, FrfQuantity::accelerance}) {
      SCOPED_TRACE(fmt::format("encoding {} quantity {}", static_cast<int>(encoding), to_string(quantity)));
      const std::vector<MeasuredFrf> read = parse_uff58(uff58_bytes(truth, encoding, quantity), "t.uff");
      ASSERT_EQ(read.size(), 1u);
      EXPECT_EQ(read[0].measured_as, quantity);
      // ASCII keeps 12 significant digits (E20.12), binary every bit.
      expect_same_frf(read[0], truth, encoding == UffEncoding::ascii ? 1e-10 : 1e-15);
    }
  // Uneven lines (abscissa stored with each value).
  MeasuredFrf uneven = truth;
  uneven.frequency_hz[3] += 0.125;
  expect_same_frf(parse_uff58(uff58_bytes(uneven, UffEncoding::ascii), "u.uff").at(0), uneven, 1e-10);
  expect_same_frf(parse_uff58(uff58_bytes(uneven, UffEncoding::binary_little_endian), "u.uff").at(0), uneven, 1e-15);
}

// A hand-written ASCII file as other programs write it: complex single precision (type 5, 6E13.5),
// even abscissa, accelerance, in a unit system of millimetres (dataset 164 length factor 1000),
// after a dataset this reader skips, with a time-response dataset 58 too.
TEST(FrfUff58, SinglePrecisionMillimetreUnitsAndOtherDatasets) {
  std::string text =
      "    -1\n"
      "    15\n"
      "         1         0         0         0  0.0000000E+00  0.0000000E+00  0.0000000E+00\n"
      "    -1\n"
      "    -1\n"
      "   164\n"
      "         5mm (milli newton)            2\n"
      "  1.00000000000000000D+03  1.00000000000000000D+00  1.00000000000000000D+00\n"
      "  2.73150000000000000D+02\n"
      "    -1\n"
      "    -1\n"
      "    58\n"
      "time signal\nNONE\nNONE\nNONE\nNONE\n"
      "    1         0    0         0 NONE               1   3 NONE               1   3\n"
      "         2         4         1  0.00000E+00  1.00000E-03  0.00000E+00\n"
      "        17    0    0    0 Time                 s                   \n"
      "        12    1    0    0 Acceleration         mm/s^2              \n"
      "         0    0    0    0 NONE                 NONE                \n"
      "         0    0    0    0 NONE                 NONE                \n"
      "  1.00000E+00  2.00000E+00  3.00000E+00  4.00000E+00\n"
      "    -1\n"
      "    -1\n"
      "    58\n"
      "tap\nNONE\nNONE\nNONE\nNONE\n"
      "    4         1    1         0 NONE               1   3 NONE               1   3\n"
      "         5         4         1  1.00000E+02  1.00000E+01  0.00000E+00\n"
      "        18    0    0    0 Frequency            Hz                  \n"
      "        12    1    0    0 Acceleration         mm/s^2              \n"
      "        13    0    1    0 Force                N                   \n"
      "         0    0    0    0 NONE                 NONE                \n"
      " -1.00000E+03  2.00000E+02 -1.10000E+03  2.50000E+02 -1.20000E+03  3.00000E+02\n"
      " -1.30000E+03  3.50000E+02\n"
      "    -1\n";
  const std::vector<MeasuredFrf> frfs = parse_uff58(text, "mm.unv");
  ASSERT_EQ(frfs.size(), 1u);
  const MeasuredFrf& frf = frfs[0];
  EXPECT_EQ(frf.measured_as, FrfQuantity::accelerance);
  EXPECT_EQ(frf.description, "tap");
  EXPECT_NE(frf.source.find("mm.unv, FRF 1 (line 27: response 1:+Z, reference 1:+Z)"), std::string::npos) << frf.source;
  ASSERT_EQ(frf.frequency_hz, (std::vector<double>{100.0, 110.0, 120.0, 130.0}));
  // -1000 mm/s^2/N at 100 Hz = -1 m/s^2/N -> H = 1/w^2; imaginary part likewise.
  const double w = kTwoPi * 100.0;
  EXPECT_NEAR(frf.receptance_m_per_n[0].real(), 1.0 / (w * w), 1e-6 / (w * w));
  EXPECT_NEAR(frf.receptance_m_per_n[0].imag(), -0.2 / (w * w), 1e-6 / (w * w));
}

TEST(FrfUff58, BadFilesNameTheLineAndField) {
  const MeasuredFrf truth = testing::synthetic_frf(two_modes(), 50.0, 60.0, 1.0);
  const std::string good = uff58_bytes(truth, UffEncoding::ascii);
  auto error = [](const std::string& text) { return input_error_of([&] { parse_uff58(text, "b.uff"); }); };
  // Record 7 of the 58 (line 18 of the file: 7 lines of dataset 164, then -1, 58 and 5 ID lines, record 6).
  std::string bad = good;
  const std::size_t r7 = bad.find("         6        11");
  ASSERT_NE(r7, std::string::npos);
  bad.replace(r7, 10, "         3");
  std::string e = error(bad);
  EXPECT_NE(e.find("b.uff:15: dataset 58 record 7: ordinate data type 3 is not 2, 4, 5 or 6"), std::string::npos) << e;
  // Fewer values than declared.
  bad = good;
  bad.replace(r7 + 10, 10, "        12");
  e = error(bad);
  EXPECT_NE(e.find("declares 12 points (24 numbers) but holds 22 numbers"), std::string::npos) << e;
  // A binary file cut short.
  const std::string binary = uff58_bytes(truth, UffEncoding::binary_little_endian);
  e = error(binary.substr(0, binary.size() - 40));
  EXPECT_NE(e.find("binary dataset 58 (line 8) needs 176 bytes of data but the file ends after"), std::string::npos) << e;
  // Not IEEE floating point.
  bad = binary;
  bad.replace(bad.find("58b") + 3 + 6, 6, "     1");
  e = error(bad);
  EXPECT_NE(e.find("floating-point format '1' is not 2 (IEEE 754)"), std::string::npos) << e;
  // Something else than a dataset.
  e = error("hello\n");
  EXPECT_NE(e.find("b.uff:1: expected a '    -1' line opening a dataset, found 'hello'"), std::string::npos) << e;
  // No FRF at all.
  bad = good;
  bad.replace(bad.find("    4         1"), 5, "    1");
  e = error(bad);
  EXPECT_NE(e.find("b.uff: no FRF in the file (a dataset 58 with function type 4); its datasets 58 hold: line 8: "
                   "function type 1"),
            std::string::npos) << e;
}

TEST(FrfFile, FormatByContentsAndChoiceAmongSeveralFrfs) {
  TempDir dir;
  const MeasuredFrf a = testing::synthetic_frf(two_modes(), 50.0, 60.0, 1.0);
  const MeasuredFrf b = testing::synthetic_frf(two_modes(), 70.0, 80.0, 1.0);
  const auto two = dir.write("two.unv", uff58_bytes(a, UffEncoding::ascii) + uff58_bytes(b, UffEncoding::binary_big_endian));
  EXPECT_EQ(read_frfs(two).size(), 2u);
  expect_same_frf(read_frf(two, 2), b, 1e-15);
  std::string e = input_error_of([&] { read_frf(two); });
  EXPECT_NE(e.find("two.unv: holds 2 FRFs; choose one by its number (frf_dataset):\n  1: "), std::string::npos) << e;
  EXPECT_NE(e.find("(11 lines, 70-80 Hz)"), std::string::npos) << e;
  e = input_error_of([&] { read_frf(two, 3); });
  EXPECT_NE(e.find("two.unv: FRF number 3 does not exist: the file holds 2 FRFs"), std::string::npos) << e;
  const auto csv = dir.write("one.csv", "frequency [Hz], real [m/N], imag [m/N]\n1,1,0\n2,1,0\n3,1,0\n4,1,0\n");
  EXPECT_EQ(read_frf(csv).frequency_hz.size(), 4u);
  e = input_error_of([&] { read_frf(dir.path() / "missing.csv"); });
  EXPECT_NE(e.find("missing.csv: no such file"), std::string::npos) << e;
}

// The interpolant between lines: H of one mode sampled at 0.25 Hz (12 lines per half-power
// bandwidth), checked halfway between lines, where the spline is least accurate.
TEST(FrfInterpolant, MatchesTheModeBetweenLines) {
  FittedMode m;
  m.frequency_hz = 67.56, m.damping_ratio = 0.03, m.stiffness_n_per_m = 5.53e7;
  const MeasuredFrf frf = testing::synthetic_frf({m}, 20.0, 200.0, 0.25);
  const FrfInterpolant h(frf);
  double worst = 0.0, worst_derivative = 0.0;
  for (double f = 30.125; f < 190.0; f += 0.25) {
    const auto v = h.at(f);
    ASSERT_TRUE(v);
    const Complex exact = modes_receptance({m}, f);
    const double step = 1e-4;
    const Complex slope = (modes_receptance({m}, f + step) - modes_receptance({m}, f - step)) / (2 * step);
    worst = std::max(worst, std::abs(v->receptance_m_per_n - exact) / std::abs(exact));
    worst_derivative = std::max(worst_derivative, std::abs(v->derivative_m_per_n_hz - slope) / std::abs(slope));
  }
  EXPECT_LT(worst, 2e-5);
  EXPECT_LT(worst_derivative, 2e-3);
  EXPECT_FALSE(h.at(19.9));
  EXPECT_FALSE(h.at(200.1));
  EXPECT_EQ(h.at(20.0)->receptance_m_per_n, frf.receptance_m_per_n.front());
}

}  // namespace
}  // namespace chatterlab
