// read_data_table: text tables with and without header, separators, WAV, and the messages of
// bad files (file, line, column named).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "chatterlab/errors.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& content) {
  fs::path dir = fs::temp_directory_path() / "chatterlab_signal_io_test";
  fs::create_directories(dir);
  fs::path file = dir / name;
  std::ofstream(file, std::ios::binary) << content;
  return file;
}

std::string message_of(const fs::path& file, const std::string& column = "1") {
  try {
    read_signal_column(file, column);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReadDataTable, CsvWithHeaderCommentsAndCrLf) {
  auto file = write("a.csv", "\xEF\xBB\xBF# probe data\r\nt_s,\"x_m\"\r\n0,1.5\r\n0.1,-2e-3\r\n\r\n");
  DataTable t = read_data_table(file);
  ASSERT_EQ(t.names, (std::vector<std::string>{"t_s", "x_m"}));
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.column("x_m")[1], -2e-3);
  EXPECT_EQ(t.column("2")[0], 1.5);
  EXPECT_EQ(t.source_line(0), 3u);
  EXPECT_EQ(t.source_line(1), 4u);
  EXPECT_EQ(t.source_line(2), 0u);  // past the end
}

TEST(ReadDataTable, SourceLinesAcrossCommentsAndBlankLines) {
  DataTable t = read_data_table(write("lines.csv", "a\n1\n# note\n2\n3\n\n\n4\n5\n"));
  ASSERT_EQ(t.rows(), 5u);
  const std::vector<std::size_t> lines{2, 4, 5, 8, 9};
  for (std::size_t row = 0; row < lines.size(); ++row) EXPECT_EQ(t.source_line(row), lines[row]) << row;
  EXPECT_EQ(t.line_runs.size(), 3u);  // 2; 4-5; 8-9
}

TEST(ReadDataTable, WhitespaceColumnsWithoutHeader) {
  auto file = write("b.dat", "1 2\t3\n  4 5 6\n");
  DataTable t = read_data_table(file);
  EXPECT_EQ(t.names, (std::vector<std::string>{"1", "2", "3"}));
  EXPECT_EQ(read_signal_column(file, "3"), (std::vector<double>{3, 6}));
}

TEST(ReadDataTable, MessagesNameFileLineAndColumn) {
  EXPECT_EQ(message_of(write("c.csv", "a,b\n1,2\n3,x\n"), "b"),
            (fs::temp_directory_path() / "chatterlab_signal_io_test/c.csv").string() +
                ": line 3: column 'b': 'x' is not a number");
  EXPECT_NE(message_of(write("d.csv", "a,b\n1,2\n3\n")).find("line 3: 1 fields, but the table has 2 columns (a, b)"),
            std::string::npos);
  EXPECT_NE(message_of(write("e.csv", "a,b\n1,nan\n"), "b").find("line 2: column 'b': nan is not finite"),
            std::string::npos);
  EXPECT_NE(message_of(write("f.csv", "a,b\n1,2\n"), "force").find("no column 'force' (columns: a, b; or 1..2)"),
            std::string::npos);
  EXPECT_NE(message_of(write("g.csv", "# only\n")).find("no data rows"), std::string::npos);
  EXPECT_NE(message_of(fs::path("/nonexistent/x.csv")).find("/nonexistent/x.csv: no such file"),
            std::string::npos);
}

void put16(std::string& s, std::uint16_t v) { s.append(reinterpret_cast<const char*>(&v), 2); }
void put32(std::string& s, std::uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); }

TEST(ReadDataTable, Wav16BitStereo) {
  std::string body;
  const std::int16_t frames[3][2] = {{0, 16384}, {-32768, 100}, {32767, -16384}};
  for (auto& f : frames) {
    put16(body, static_cast<std::uint16_t>(f[0]));
    put16(body, static_cast<std::uint16_t>(f[1]));
  }
  std::string wav = "RIFF";
  put32(wav, static_cast<std::uint32_t>(36 + body.size()));
  wav += "WAVEfmt ";
  put32(wav, 16);
  put16(wav, 1);     // PCM
  put16(wav, 2);     // channels
  put32(wav, 8000);  // rate
  put32(wav, 8000 * 4);
  put16(wav, 4);
  put16(wav, 16);
  wav += "data";
  put32(wav, static_cast<std::uint32_t>(body.size()));
  wav += body;
  DataTable t = read_data_table(write("s.wav", wav));
  ASSERT_TRUE(t.sample_rate_hz);
  EXPECT_EQ(*t.sample_rate_hz, 8000.0);
  EXPECT_EQ(t.columns.size(), 2u);
  EXPECT_EQ(t.column("2"), (std::vector<double>{0.5, 100.0 / 32768.0, -0.5}));
  EXPECT_EQ(t.column("1")[1], -1.0);
  EXPECT_NE(message_of(write("bad.wav", "RIFFxxxxWAVE")).find("not a readable WAV file: no fmt chunk"),
            std::string::npos);
}

}  // namespace
}  // namespace chatterlab
