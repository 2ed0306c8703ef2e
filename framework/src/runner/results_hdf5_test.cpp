// results.h5 ([output] format = "hdf5"): the writer's chunk rows, widening and nulls read back;
// a linear_dde stability map written as CSV and as HDF5 holds the same numbers (the HDF5 read
// with the C API here); a resumed HDF5 run equals an uninterrupted one; a complete run drops its
// journal and resumes from results.h5, which a resume reads one chunk row at a time.
#include "runner/results_hdf5.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <hdf5_hl.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "chatterlab/errors.hpp"
#include "chatterlab/runner.hpp"
#include "runner/output_dir.hpp"
#include "runner/results_io.hpp"
#include "runner/resume.hpp"

namespace chatterlab::runner {
namespace {

namespace fs = std::filesystem;

fs::path fresh(const std::string& name) {
  fs::path dir = fs::path(CHATTERLAB_TEST_BINARY_DIR) / "results_hdf5_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir.parent_path());
  return dir;
}

std::string text_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A study over `shape` (axes a0, a1, ...) with no kind behind it: only the writer reads it.
Study shaped_study(const std::vector<std::size_t>& shape) {
  Study study;
  study.file = "shaped.toml";
  study.kind = "none";
  study.document = {{"study", {{"kind", "none"}}}};
  for (std::size_t a = 0; a < shape.size(); ++a) {
    // (appended, not "a" + std::to_string(a): GCC 12 warns -Wrestrict about that at -O3)
    std::string key = "a";
    key += std::to_string(a);
    GridAxis axis{key, "model." + key, {}, {}};
    for (std::size_t i = 0; i < shape[a]; ++i) axis.values.push_back(0.25 * static_cast<double>(i));
    study.grid.push_back(std::move(axis));
  }
  return study;
}

// Point p's result: a number (null every 7th point), a boolean, a text that grows with p (the
// column is widened several times), a status (every 11th point failed).
PointResult synthetic(std::size_t p) {
  PointResult r;
  r.done = true;
  r.outputs.push_back(p % 7 == 3 ? Json() : Json(0.1 * static_cast<double>(p) - 7.0));
  r.outputs.push_back(p % 3 == 0);
  r.outputs.push_back(std::string(p / 2000, 'x') + "ü" + std::to_string(p));
  r.status = p % 11 == 5 ? "failed: no root, point " + std::to_string(p) : "ok";
  return r;
}

TEST(Hdf5Results, ChunkRowsWideningAndNullsReadBackUnchanged) {
  for (const std::vector<std::size_t>& shape :
       {std::vector<std::size_t>{3, 7, 5000}, std::vector<std::size_t>{40000},
        std::vector<std::size_t>{5, 4}}) {
    const Study study = shaped_study(shape);
    const fs::path file = fresh("shaped") / "results.h5";
    fs::create_directories(file.parent_path());
    {
      Hdf5ResultsWriter writer(study, {"value", "flag", "label"}, file,
                               {{"study_fingerprint", "f00"}});
      for (std::size_t p = 0; p < study.point_count(); ++p) writer.append(synthetic(p));
      writer.commit();
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(file.parent_path()), fs::directory_iterator()), 1)
        << "a temporary file was left behind";
    const Hdf5Results back = read_hdf5_results(file);
    EXPECT_EQ(back.shape, shape);
    EXPECT_EQ(back.header.study_fingerprint, "f00");
    EXPECT_EQ(back.header.columns, (std::vector<std::string>{"value", "flag", "label"}));
    ASSERT_EQ(back.records.size(), study.point_count());
    for (std::size_t p = 0; p < study.point_count(); ++p) {
      const PointResult expected = synthetic(p);
      const auto& [point, got] = back.records[p];
      ASSERT_EQ(point, p);
      ASSERT_EQ(got.outputs, expected.outputs) << "point " << p;
      ASSERT_EQ(got.status, expected.status) << "point " << p;
    }
  }
}

// --resume streams results.h5: finding the finished points reads no record, and taking them in
// grid order holds at most one chunk row, whatever the grid; --retry-failed leaves the failed
// points (every 11th) to compute.
TEST(Hdf5Results, AResumeReadsResultsH5OneChunkRowAtATime) {
  const Study study = shaped_study({3, 7, 5000});  // 105,000 points: 7 chunk rows
  const std::size_t n = study.point_count();
  const fs::path dir = fresh("streamed");
  fs::create_directories(dir);
  {
    Hdf5ResultsWriter writer(study, {"value", "flag", "label"}, results_path(dir, ResultsFormat::hdf5),
                             {{"study_fingerprint", "f00"}});
    for (std::size_t p = 0; p < n; ++p) writer.append(synthetic(p));
    writer.commit();
  }
  const JournalHeader header = Hdf5ResultsReader(dir / "results.h5").header();
  ResumedPoints all = read_resumable_points(dir, header, study, /*retry_failed=*/false);
  ASSERT_EQ(all.count(), n);
  EXPECT_EQ(all.buffered_records(), 0u);
  std::size_t most = 0;
  for (std::size_t p = 0; p < n; ++p) {
    const PointResult got = all.take(p);
    most = std::max(most, all.buffered_records());
    const PointResult expected = synthetic(p);
    ASSERT_EQ(got.outputs, expected.outputs) << "point " << p;
    ASSERT_EQ(got.status, expected.status) << "point " << p;
  }
  EXPECT_GT(most, 0u);
  EXPECT_LT(most, hdf5_chunk_points);
  EXPECT_THROW(all.take(n - 1), std::logic_error);

  ResumedPoints ok_only = read_resumable_points(dir, header, study, /*retry_failed=*/true);
  EXPECT_EQ(ok_only.count(), n - (n + 5) / 11);
  EXPECT_FALSE(ok_only.has(5));
  EXPECT_TRUE(ok_only.has(6));
  EXPECT_EQ(ok_only.take(6).outputs, synthetic(6).outputs);
}

TEST(Hdf5Results, AutoFormatIsHdf5AboveTheDocumentedSize) {
  Study study = shaped_study({auto_hdf5_above_points});
  EXPECT_EQ(results_format(study), ResultsFormat::csv);  // no [output]: CSV
  study.document["output"] = {{"format", "auto"}};
  EXPECT_EQ(results_format(study), ResultsFormat::csv);
  EXPECT_EQ(results_format(shaped_study({auto_hdf5_above_points + 1})), ResultsFormat::csv);
  Study large = shaped_study({auto_hdf5_above_points + 1});
  large.document["output"] = {{"format", "auto"}};
  EXPECT_EQ(results_format(large), ResultsFormat::hdf5);
  large.document["output"] = {{"format", "csv"}};
  EXPECT_EQ(results_format(large), ResultsFormat::csv);
  study.document["output"] = {{"format", "hdf5"}};
  EXPECT_EQ(results_format(study), ResultsFormat::hdf5);
  EXPECT_EQ(results_path("out", ResultsFormat::hdf5), fs::path("out/results.h5"));
}

TEST(Hdf5Results, TextInAColumnOfNumbersFailsTheCommitNamingColumnAndPoint) {
  const Study study = shaped_study({4});
  const fs::path file = fresh("conflict") / "results.h5";
  fs::create_directories(file.parent_path());
  try {
    Hdf5ResultsWriter writer(study, {"value"}, file, Json::object());
    for (std::size_t p = 0; p < 4; ++p) {
      PointResult r{true, {p == 2 ? Json("n/a") : Json(1.5)}, "ok", 0.0};
      writer.append(std::move(r));
    }
    writer.commit();
    ADD_FAILURE() << "a text cell in a column of numbers was accepted";
  } catch (const OutputError& e) {
    const std::string message = e.what();
    for (const char* part : {"column value holds \"n/a\" at point 2", "column of numbers",
                             "[output] format = \"csv\""})
      EXPECT_NE(message.find(part), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(file));
}

// ------------------------------------------------------------------ runs of a real study
// tests/cli/studies/dde_2d.toml (a 4 x 5 linear_dde stability map) with an [output] table.
fs::path dde_study(const fs::path& dir, const std::string& output_table) {
  fs::create_directories(dir);
  const fs::path file = dir / "dde_2d.toml";
  std::ofstream(file) << text_file(fs::path(CHATTERLAB_SOURCE_DIR) / "tests/cli/studies/dde_2d.toml")
                      << "\n[output]\n" << output_table << "\n";
  return file;
}

RunOptions quiet(const fs::path& out) {
  RunOptions options;
  options.out_dir = out;
  options.threads = 2;
  options.progress = false;
  options.plots = false;
  return options;
}

// results.csv split into rows of cells (RFC 4180 quotes).
std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows(1);
  std::string cell;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') cell += text[++i];
      else if (c == '"') quoted = false;
      else cell += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().push_back(std::move(cell));
      cell.clear();
    } else if (c == '\n') {
      rows.back().push_back(std::move(cell));
      cell.clear();
      rows.emplace_back();
    } else {
      cell += c;
    }
  }
  rows.pop_back();  // after the last "\n"
  return rows;
}

// One dataset read whole through the C API: doubles, or (for text) fixed-length strings.
std::vector<double> read_numbers(hid_t file, const std::string& name) {
  hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  hid_t space = H5Dget_space(dataset);
  std::vector<double> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  EXPECT_GE(H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  H5Sclose(space);
  H5Dclose(dataset);
  return values;
}

std::vector<std::string> read_texts(hid_t file, const std::string& name) {
  hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  hid_t type = H5Dget_type(dataset);
  EXPECT_EQ(H5Tget_class(type), H5T_STRING);
  const std::size_t width = H5Tget_size(type);
  hid_t space = H5Dget_space(dataset);
  const auto n = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space));
  std::vector<char> buffer(n * width);
  EXPECT_GE(H5Dread(dataset, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data()), 0);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < n; ++i)
    out.emplace_back(buffer.data() + i * width, strnlen(buffer.data() + i * width, width));
  H5Sclose(space);
  H5Tclose(type);
  H5Dclose(dataset);
  return out;
}

TEST(Hdf5Results, CsvAndHdf5OfAStabilityMapHoldTheSameNumbers) {
  const fs::path dir = fresh("same_numbers");
  const Study csv_study = load_study(dde_study(dir / "csv", "format = \"csv\""));
  const Study h5_study = load_study(dde_study(dir / "h5", "format = \"hdf5\""));
  ASSERT_EQ(run_study(csv_study, quiet(dir / "csv" / "out")).exit_code(), 0);
  const RunSummary h5_run = run_study(h5_study, quiet(dir / "h5" / "out"));
  ASSERT_EQ(h5_run.exit_code(), 0);
  EXPECT_EQ(h5_run.results_file, dir / "h5" / "out" / "results.h5");
  EXPECT_FALSE(fs::exists(dir / "h5" / "out" / "results.csv"));

  const auto rows = csv_rows(text_file(dir / "csv" / "out" / "results.csv"));
  ASSERT_EQ(rows.size(), 21u);  // header + 4 x 5 points
  const std::vector<std::string>& header = rows[0];
  ASSERT_EQ(header.size(), 2 + csv_study.output_columns.size() + 1);

  hid_t file = H5Fopen((dir / "h5" / "out" / "results.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  std::size_t numbers = 0, texts = 0;
  for (std::size_t c = 2; c < header.size(); ++c) {
    hid_t dataset = H5Dopen2(file, header[c].c_str(), H5P_DEFAULT);
    ASSERT_GE(dataset, 0) << header[c];
    hid_t type = H5Dget_type(dataset);
    const H5T_class_t type_class = H5Tget_class(type);
    // The grid axes are the dataset's dimension scales, in [grid] order.
    hid_t space = H5Dget_space(dataset);
    hsize_t dims[2] = {0, 0};
    EXPECT_EQ(H5Sget_simple_extent_dims(space, dims, nullptr), 2);
    EXPECT_EQ(dims[0], 4u);
    EXPECT_EQ(dims[1], 5u);
    for (unsigned a = 0; a < 2; ++a) {
      hid_t scale = H5Dopen2(file, ("grid/" + header[a]).c_str(), H5P_DEFAULT);
      ASSERT_GE(scale, 0) << header[a];
      EXPECT_GT(H5DSis_attached(dataset, scale, a), 0) << header[c] << " axis " << a;
      H5Dclose(scale);
    }
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(dataset);
    if (type_class == H5T_FLOAT || type_class == H5T_ENUM) {
      // Booleans as 0/1 through the enum's conversion to double.
      const std::vector<double> values = read_numbers(file, header[c]);
      ASSERT_EQ(values.size(), 20u);
      for (std::size_t p = 0; p < 20; ++p) {
        const std::string& cell = rows[p + 1][c];
        if (cell == "true" || cell == "false")
          EXPECT_EQ(values[p], cell == "true" ? 1.0 : 0.0) << header[c] << " point " << p;
        else if (cell.empty())
          EXPECT_TRUE(std::isnan(values[p])) << header[c] << " point " << p;
        else  // the shortest round-trip text of a double gives that very double back
          EXPECT_EQ(values[p], std::strtod(cell.c_str(), nullptr)) << header[c] << " point " << p;
      }
      ++numbers;
    } else {
      const std::vector<std::string> values = read_texts(file, header[c]);
      ASSERT_EQ(values.size(), 20u);
      for (std::size_t p = 0; p < 20; ++p) EXPECT_EQ(values[p], rows[p + 1][c]) << header[c];
      ++texts;
    }
  }
  EXPECT_EQ(numbers, 5u);  // growth rate, frequency, stable, certified, certified real part
  EXPECT_EQ(texts, 3u);    // certificate, route, status
  // The axes' values, the study file and the provenance.
  for (std::size_t a = 0; a < 2; ++a) {
    const std::vector<double> axis = read_numbers(file, "grid/" + header[a]);
    for (std::size_t p = 0; p < 20; ++p)
      EXPECT_EQ(axis[a == 0 ? p / 5 : p % 5], std::strtod(rows[p + 1][a].c_str(), nullptr));
  }
  H5Fclose(file);
  const Hdf5Results back = read_hdf5_results(dir / "h5" / "out" / "results.h5");
  EXPECT_EQ(back.header.columns, csv_study.output_columns);
  const Json meta = Json::parse(text_file(dir / "h5" / "out" / "meta.json"));
  EXPECT_EQ(back.header.study_fingerprint, meta["study_fingerprint"]);
  EXPECT_EQ(meta["results_file"], "results.h5");
  // read_results_h5 (chatterlab/runner.hpp, what the Python API's run_study reads): the table
  // results.csv is written from, to the byte.
  EXPECT_EQ(format_csv(read_results_h5(h5_study, dir / "h5" / "out" / "results.h5")),
            text_file(dir / "csv" / "out" / "results.csv"));
}

TEST(Hdf5Results, AResumedRunEqualsAnUninterruptedOne) {
  const fs::path dir = fresh("resume");
  const Study study = load_study(dde_study(dir, "format = \"hdf5\"\nkeep_journal = true"));
  const fs::path whole = dir / "whole", resumed = dir / "resumed";
  ASSERT_EQ(run_study(study, quiet(whole)).exit_code(), 0);
  ASSERT_TRUE(fs::exists(journal_file(whole, 1, 0)));  // keep_journal = true

  // The interrupted run: the journal's header and its first 8 points, a 9th line cut short,
  // no results.h5 (it is only renamed into place at the end).
  fs::copy(whole, resumed, fs::copy_options::recursive);
  fs::remove(resumed / "results.h5");
  std::istringstream lines(text_file(journal_file(whole, 1, 0)));
  std::string line, cut;
  for (int i = 0; i <= 9 && std::getline(lines, line); ++i)
    cut += i < 9 ? line + "\n" : line.substr(0, line.size() / 2);
  std::ofstream(journal_file(resumed, 1, 0)) << cut;
  RunOptions options = quiet(resumed);
  options.resume = true;
  const RunSummary summary = run_study(study, options);
  EXPECT_EQ(summary.resumed, 8u);
  EXPECT_EQ(summary.exit_code(), 0);

  const Hdf5Results a = read_hdf5_results(whole / "results.h5");
  const Hdf5Results b = read_hdf5_results(resumed / "results.h5");
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.header.study_fingerprint, b.header.study_fingerprint);
  ASSERT_EQ(a.records.size(), b.records.size());
  for (std::size_t p = 0; p < a.records.size(); ++p) {
    EXPECT_EQ(a.records[p].second.outputs, b.records[p].second.outputs) << "point " << p;
    EXPECT_EQ(a.records[p].second.status, b.records[p].second.status) << "point " << p;
  }
}

TEST(Hdf5Results, ACompleteRunDropsItsJournalAndResumesFromResultsH5) {
  const fs::path dir = fresh("journal_removed");
  const Study study = load_study(dde_study(dir, "format = \"hdf5\""));
  const fs::path out = dir / "out";
  ASSERT_EQ(run_study(study, quiet(out)).exit_code(), 0);
  EXPECT_FALSE(fs::exists(journal_dir(out)));
  Json meta = Json::parse(text_file(out / "meta.json"));
  EXPECT_EQ(meta["state"], "complete");
  EXPECT_NE(meta["run"]["journal"].get<std::string>().find("removed"), std::string::npos);
  const Hdf5Results before = read_hdf5_results(out / "results.h5");

  RunOptions options = quiet(out);
  options.resume = true;
  const RunSummary again = run_study(study, options);
  EXPECT_EQ(again.resumed, 20u);
  meta = Json::parse(text_file(out / "meta.json"));
  EXPECT_EQ(meta["run"]["points_computed"], 0);
  const Hdf5Results after = read_hdf5_results(out / "results.h5");
  ASSERT_EQ(after.records.size(), before.records.size());
  for (std::size_t p = 0; p < after.records.size(); ++p)
    EXPECT_EQ(after.records[p].second.outputs, before.records[p].second.outputs) << p;

  // A later session's journal (an interrupted --resume --retry-failed) overlays results.h5: its
  // ok record of point 3 (marked -7) wins.
  fs::create_directories(journal_dir(out));
  PointResult marked = before.records[3].second;
  marked.outputs[0] = -7.0;
  std::ofstream(journal_file(out, 1, 0))
      << journal_header_line({before.header.study_fingerprint, 20, before.header.columns,
                              before.header.inputs})
      << journal_line(3, marked);
  EXPECT_EQ(run_study(study, options).resumed, 20u);
  const Hdf5Results overlaid = read_hdf5_results(out / "results.h5");
  EXPECT_EQ(overlaid.records[3].second.outputs[0], -7.0);
  EXPECT_EQ(overlaid.records[4].second.outputs, before.records[4].second.outputs);

  // Another computation is refused, naming results.h5 and what changed.
  std::string text = text_file(dir / "dde_2d.toml");
  text.replace(text.find("max_frequency_hz = 1.0"), 22, "max_frequency_hz = 2.0");
  std::ofstream(dir / "dde_2d.toml") << text;
  const Study changed = load_study(dir / "dde_2d.toml");
  try {
    run_study(changed, options);
    ADD_FAILURE() << "resumed another study from results.h5";
  } catch (const InputError& e) {
    const std::string message = e.what();
    for (const char* part : {"cannot resume from", "results.h5", "stability.max_frequency_hz: 1 then, 2 now"})
      EXPECT_NE(message.find(part), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace chatterlab::runner
