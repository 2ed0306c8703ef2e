// Time-series files (chatterlab/time_series_file.hpp): the .npy layout byte for byte as NumPy's
// format 1.0 defines it (magic, version, header length, a header dict padded to 64 bytes, then
// little-endian float64 records), decimation, CSV, and refusals.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "chatterlab/time_series_file.hpp"

namespace chatterlab {
namespace {

TEST(TimeSeriesFile, NpyIsAStructuredArrayOfFloat64Records) {
  const std::vector<double> t{0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};
  std::vector<double> x(t.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = -1.5 * static_cast<double>(i) + 1e-9;
  const std::string bytes = npy_bytes({"t_s", "displacement_m"}, {t, x}, 3);
  ASSERT_GE(bytes.size(), 10u);
  EXPECT_EQ(bytes.substr(0, 6), "\x93NUMPY");
  EXPECT_EQ(bytes[6], '\x01');
  EXPECT_EQ(bytes[7], '\x00');
  const std::size_t header_length =
      static_cast<unsigned char>(bytes[8]) + 256u * static_cast<unsigned char>(bytes[9]);
  EXPECT_EQ((10 + header_length) % 64, 0u);
  const std::string header = bytes.substr(10, header_length);
  EXPECT_EQ(header.rfind("{'descr': [('t_s', '<f8'), ('displacement_m', '<f8'), ], 'fortran_order': False, "
                         "'shape': (4,), }",
                         0),
            0u)
      << header;
  EXPECT_EQ(header.back(), '\n');
  // Rows 0, 3, 6, 9: (t, x) pairs.
  const std::size_t data = 10 + header_length;
  ASSERT_EQ(bytes.size(), data + 4 * 2 * sizeof(double));
  for (std::size_t r = 0; r < 4; ++r) {
    double values[2];
    std::memcpy(values, bytes.data() + data + r * 2 * sizeof(double), sizeof values);
    EXPECT_EQ(values[0], t[3 * r]);
    EXPECT_EQ(values[1], x[3 * r]);
  }
}

TEST(TimeSeriesFile, CsvKeepsEveryKthRowAndNpyIsWrittenAtomically) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "chatterlab_time_series_file_test";
  fs::remove_all(dir);
  const std::vector<double> t{0.0, 0.25, 0.5, 0.75, 1.0}, y{5.0, 6.0, 7.0, 8.0, 9.0};
  EXPECT_EQ(write_time_series(dir, "series", {"t_s", "y"}, {t, y}, TimeSeriesFormat::csv, 2), "series.csv");
  std::ifstream csv(dir / "series.csv");
  const std::string text((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "t_s,y\n0,5\n0.5,7\n1,9\n");
  EXPECT_EQ(write_time_series(dir, "series", {"t_s", "y"}, {t, y}, TimeSeriesFormat::npy), "series.npy");
  EXPECT_EQ(fs::file_size(dir / "series.npy"), npy_bytes({"t_s", "y"}, {t, y}).size());
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  fs::remove_all(dir);
}

TEST(TimeSeriesFile, RefusesColumnsOfUnequalLengthAndAZeroDecimation) {
  const std::vector<double> a{1.0, 2.0}, b{1.0};
  try {
    npy_bytes({"a", "b"}, {a, b});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "time series: column 'b' has 1 rows, 'a' 2");
  }
  EXPECT_THROW(npy_bytes({"a"}, {a}, 0), std::invalid_argument);
  EXPECT_THROW(npy_bytes({"a", "b"}, {a}), std::invalid_argument);
  EXPECT_THROW(parse_time_series_format("hdf5"), std::invalid_argument);
  EXPECT_EQ(parse_time_series_format("npy"), TimeSeriesFormat::npy);
}

}  // namespace
}  // namespace chatterlab
