// The study runner's pieces (CSV cells, journal lines, grid order, output directory policy) and
// run_study() itself on a small study kind defined here, so failures, resume and the files are
// tested without depending on a model's numerics (tests/cli/ runs the real stability_map).
#include "chatterlab/runner.hpp"

#include <gtest/gtest.h>

#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <thread>

#include "chatterlab/errors.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/version.hpp"
#include "runner/build_info.hpp"
#include "runner/journal_writer.hpp"
#include "runner/output_dir.hpp"
#include "runner/progress.hpp"
#include "runner/results_io.hpp"
#include "runner/result_writer.hpp"
#include "runner/resume.hpp"
#include "runner/worker_protocol.hpp"
#include "study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using runner::PointResult;

// ------------------------------------------------------------------ helpers
fs::path fresh_dir(const std::string& name) {
  fs::path dir = fs::path(CHATTERLAB_TEST_BINARY_DIR) / "runner_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir.parent_path());
  return dir;
}

void write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::size_t begin = 0;
  for (std::size_t end; (end = text.find('\n', begin)) != std::string::npos; begin = end + 1)
    out.push_back(text.substr(begin, end - begin));
  return out;
}

PointResult ok(std::vector<Json> outputs) { return {true, std::move(outputs), "ok"}; }

// ------------------------------------------------------------------ results.csv cells
TEST(RunnerCsv, QuotesOnlyWhenNeeded) {
  EXPECT_EQ(runner::csv_field("growth_rate_per_s"), "growth_rate_per_s");
  EXPECT_EQ(runner::csv_field(""), "");
  EXPECT_EQ(runner::csv_field("a,b"), "\"a,b\"");
  EXPECT_EQ(runner::csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(runner::csv_field("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(runner::csv_field(" padded"), "\" padded\"");
  EXPECT_EQ(runner::csv_field("model.modes.0.damping_ratio"), "model.modes.0.damping_ratio");
}

TEST(RunnerCsv, CellsPrintRoundTripNumbers) {
  for (double v : {0.1, 1.0 / 3.0, 0.1 + 0.2, -2.5e-17, 5e-324, 1.7976931348623157e308, 1450.0}) {
    std::string text = runner::format_cell(Json(v));
    // strtod, not stod: stod throws on the subnormal 5e-324 (ERANGE).
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), v) << text;  // exact: round-trip form
  }
  EXPECT_EQ(runner::format_cell(Json(0.1)), "0.1");
  EXPECT_EQ(runner::format_cell(Json(1450.0)), "1450");
  EXPECT_EQ(runner::format_cell(Json(std::int64_t{-42})), "-42");
  EXPECT_EQ(runner::format_cell(Json(std::uint64_t{42})), "42");
  EXPECT_EQ(runner::format_cell(Json(true)), "true");
  EXPECT_EQ(runner::format_cell(Json(false)), "false");
  EXPECT_EQ(runner::format_cell(Json()), "");
  EXPECT_EQ(runner::format_cell(Json("ok: 0 zeros, Re s > -1")), "\"ok: 0 zeros, Re s > -1\"");
  EXPECT_EQ(runner::format_cell(Json::array({1, 2})), "\"[1,2]\"");
}

TEST(RunnerCsv, TableHasHeaderRowsAndQuotedFailures) {
  ResultTable table;
  table.grid_columns = {"wheel_speed_rpm", "model.modes.0.damping_ratio"};
  table.output_columns = {"growth_rate_per_s", "stable"};
  table.rows = {{1450.0, 0.05, -0.25, true}, {1500.0, 0.05, Json(), Json()}};
  table.status = {"ok", runner::failure_status("no root, band too small\nline two")};
  EXPECT_EQ(runner::format_csv(table),
            "wheel_speed_rpm,model.modes.0.damping_ratio,growth_rate_per_s,stable,status\n"
            "1450,0.05,-0.25,true,ok\n"
            "1500,0.05,,,\"failed: no root, band too small line two\"\n");
}

TEST(RunnerCsv, ParallelFormattingGivesTheSameBytes) {
  ResultTable table;
  table.grid_columns = {"x"};
  table.output_columns = {"y", "note"};
  for (int i = 0; i < 5000; ++i) {  // above the size where rows are formatted in parallel
    table.rows.push_back({i * 0.1, std::sqrt(i * 1.0), i % 7 ? Json("a, b") : Json()});
    table.status.push_back(i % 7 ? "ok" : runner::failure_status("no root"));
  }
  const std::string serial = runner::format_csv(table, 1);
  EXPECT_EQ(runner::format_csv(table, 4), serial);
  EXPECT_EQ(lines_of(serial).size(), 5001u);
  EXPECT_EQ(lines_of(serial)[8], "0.7000000000000001,2.6457513110645907,,failed: no root");
  EXPECT_EQ(lines_of(serial)[9], "0.8,2.8284271247461903,\"a, b\",ok");
}

TEST(RunnerCsv, FailureStatusIsOneLine) {
  EXPECT_EQ(runner::failure_status("a\r\nb"), "failed: a  b");
  EXPECT_EQ(runner::failure_status(""), "failed: unknown error");
  // Invalid UTF-8 from an exception text: replaced once, so the journal round trip keeps it.
  std::string status = runner::failure_status("bad \xff byte, 5 \xc2\xb5m");
  EXPECT_EQ(status, "failed: bad \xef\xbf\xbd byte, 5 \xc2\xb5m");
  PointResult failed{true, {Json()}, status};
  std::string journal =
      runner::journal_header_line({"f", 1, {"a"}}) + runner::journal_line(0, failed);
  EXPECT_EQ(runner::parse_journal(journal).records.at(0).second.status, status);
}

// ------------------------------------------------------------------ journal
TEST(RunnerJournal, RecordsRoundTripBitForBit) {
  runner::JournalHeader header{"0123456789abcdef", 10, {"a", "b", "c"}};
  std::vector<std::pair<std::size_t, PointResult>> written = {
      {3, ok({0.1 + 0.2, true, "ok: 0 zeros"})},
      {7, ok({5e-324, false, Json()})},
      {0, {true, {Json(), Json(), Json()}, "failed: Newton diverged, \"twice\""}},
      {9, ok({-1.7976931348623157e308, std::int64_t{-3}, 1.0 / 3.0})},
  };
  std::string text = runner::journal_header_line(header);
  for (const auto& [p, r] : written) text += runner::journal_line(p, r);

  runner::JournalContents read = runner::parse_journal(text);
  ASSERT_TRUE(read.header_found);
  EXPECT_EQ(read.header.study_fingerprint, header.study_fingerprint);
  EXPECT_EQ(read.header.points, 10u);
  EXPECT_EQ(read.header.columns, header.columns);
  EXPECT_EQ(read.truncated_lines, 0u);
  EXPECT_EQ(read.invalid_lines, 0u);
  ASSERT_EQ(read.records.size(), written.size());
  for (std::size_t k = 0; k < written.size(); ++k) {
    EXPECT_EQ(read.records[k].first, written[k].first);
    EXPECT_EQ(read.records[k].second.status, written[k].second.status);
    for (std::size_t c = 0; c < 3; ++c) {
      const Json& got = read.records[k].second.outputs[c];
      const Json& want = written[k].second.outputs[c];
      // Through the CSV formatter: what matters is that results.csv prints the same bytes.
      EXPECT_EQ(runner::format_cell(got), runner::format_cell(want)) << k << "," << c;
      if (want.is_number_float()) {
        double a = got.get<double>(), b = want.get<double>();
        EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
      }
    }
  }
}

TEST(RunnerJournal, TruncatedLastLineIsDropped) {
  runner::JournalHeader header{"f", 5, {"a"}};
  std::string full = runner::journal_header_line(header) + runner::journal_line(1, ok({1.5})) +
                     runner::journal_line(2, ok({2.5}));
  std::string cut = runner::journal_line(3, ok({3.5}));
  cut.resize(cut.size() / 2);  // a kill in the middle of a write
  runner::JournalContents read = runner::parse_journal(full + cut);
  ASSERT_TRUE(read.header_found);
  ASSERT_EQ(read.records.size(), 2u);
  EXPECT_EQ(read.records[1].first, 2u);
  EXPECT_EQ(read.truncated_lines, 1u);
  EXPECT_EQ(read.invalid_lines, 0u);

  // Even a complete-looking JSON object without its newline may be a prefix of a longer line.
  std::string whole = runner::journal_line(4, ok({4.5}));
  whole.pop_back();
  EXPECT_EQ(runner::parse_journal(full + whole).records.size(), 2u);
}

TEST(RunnerJournal, InconsistentLinesAreLeftForRecomputation) {
  runner::JournalHeader header{"f", 5, {"a", "b"}};
  std::string text = runner::journal_header_line(header);
  text += "garbage\n";
  text += runner::journal_line(1, ok({1.0}));       // one output for two columns
  text += runner::journal_line(5, ok({1.0, 2.0}));  // point 5 of 5 does not exist
  text += R"({"i":2,"out":[1,2],"status":"maybe"})"
          "\n";  // neither ok nor failed
  text += R"({"i":-1,"out":[1,2],"status":"ok"})"
          "\n";  // negative index
  text += "\n";  // blank lines are harmless
  text += runner::journal_line(4, ok({4.0, 8.0}));
  runner::JournalContents read = runner::parse_journal(text);
  EXPECT_EQ(read.invalid_lines, 5u);
  ASSERT_EQ(read.records.size(), 1u);
  EXPECT_EQ(read.records[0].first, 4u);
}

TEST(RunnerJournal, MissingOrCutHeaderMeansNoRecords) {
  EXPECT_FALSE(runner::parse_journal("").header_found);
  EXPECT_EQ(runner::parse_journal("").truncated_lines, 0u);
  runner::JournalContents cut = runner::parse_journal(R"({"chatterlab_journal":1,"stu)");
  EXPECT_FALSE(cut.header_found);
  EXPECT_EQ(cut.truncated_lines, 1u);
  runner::JournalContents wrong = runner::parse_journal(std::string(R"({"chatterlab_journal":2})") +
                                                        "\n" + runner::journal_line(0, ok({1.0})));
  EXPECT_FALSE(wrong.header_found);
  EXPECT_TRUE(wrong.records.empty());
}

// ------------------------------------------------------------------ grid order
Study two_axis_study() {
  Study study;
  study.file = "two_axis.toml";
  study.kind = "stability_map";
  study.document = {{"study", {{"kind", "stability_map"}}}, {"model", {{"a", 1.0}, {"b", 2.0}}}};
  study.grid = {GridAxis{"a", "model.a", {10.0, 20.0}, {}},
                GridAxis{"model.b", "model.b", {1.0, 2.0, 3.0}, {}}};
  return study;
}

TEST(RunnerGridOrder, RowsFollowGridOrderWithLastAxisFastest) {
  Study study = two_axis_study();
  std::vector<PointResult> results(6);
  // Filled in a scrambled order, as threads and ranks finish them.
  for (std::size_t p : {4, 0, 5, 2, 1, 3}) results[p] = ok({static_cast<double>(p)});
  ResultTable table = runner::assemble_results(study, {"out"}, results);
  EXPECT_EQ(table.grid_columns, (std::vector<std::string>{"a", "model.b"}));
  ASSERT_EQ(table.rows.size(), 6u);
  const double expected[6][3] = {{10, 1, 0}, {10, 2, 1}, {10, 3, 2},
                                 {20, 1, 3}, {20, 2, 4}, {20, 3, 5}};
  for (std::size_t p = 0; p < 6; ++p)
    for (std::size_t c = 0; c < 3; ++c) EXPECT_EQ(table.rows[p][c].get<double>(), expected[p][c]);

  results[3].done = false;
  EXPECT_THROW(runner::assemble_results(study, {"out"}, results), std::logic_error);
}

// results.csv streamed in completion order has the bytes of the table assembled at the end.
TEST(RunnerStreaming, ScrambledArrivalsGiveTheAssembledCsv) {
  Study study = two_axis_study();
  const fs::path dir = fresh_dir("streaming");
  std::vector<PointResult> results(6);
  for (std::size_t p = 0; p < 6; ++p)
    results[p] = p == 2 ? PointResult{true, {Json()}, runner::failure_status("no root")}
                        : ok({p == 4 ? Json("a, \"quoted\" text") : Json(0.1 * static_cast<double>(p))});
  const std::string expected = runner::format_csv(runner::assemble_results(study, {"out"}, results));
  {
    runner::GridOrderWriter writer(study, {"out"}, dir / "results.csv");
    for (std::size_t p : {4, 0, 5, 2, 1, 3}) {
      PointResult copy = results[p];
      writer.add(p, std::move(copy));
      EXPECT_FALSE(fs::exists(dir / "results.csv"));  // only complete, at commit()
    }
    writer.commit();
    const Json failed = writer.failed_points();
    ASSERT_EQ(failed.size(), 1u);
    EXPECT_EQ(failed[0]["point"], 2);
    EXPECT_EQ(failed[0]["grid"], Json({{"a", 10.0}, {"model.b", 3.0}}));
    EXPECT_EQ(failed[0]["reason"], "no root");
    const ResultTable plot = writer.take_plot_table();
    EXPECT_FALSE(plot.decimated());
    EXPECT_EQ(plot.rows.size(), 6u);
  }
  EXPECT_EQ(runner::read_file(dir / "results.csv"), expected);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(RunnerStreaming, AbandonedOrIncompleteWritesNoCsv) {
  Study study = two_axis_study();
  const fs::path dir = fresh_dir("streaming_abandoned");
  runner::GridOrderWriter writer(study, {"out"}, dir / "results.csv");
  writer.add(0, ok({1.0}));
  EXPECT_THROW(writer.commit(), std::logic_error);  // 5 points missing
  writer.abandon();
  EXPECT_TRUE(fs::is_empty(dir));
}

// A large grid's plots get every k-th value of each axis: at most max_rows rows, the longest
// axis thinned first, and the study handed with them describes exactly those rows.
TEST(RunnerStreaming, PlotTableOfALargeGridIsDecimatedAndFlagged) {
  Study study;
  study.file = "big.toml";
  std::vector<Json> a, b;
  for (int i = 0; i < 1000; ++i) a.push_back(static_cast<double>(i));
  for (int i = 0; i < 30; ++i) b.push_back(static_cast<double>(100 + i));
  study.grid = {GridAxis{"a", "model.a", a, {}}, GridAxis{"b", "model.b", b, {}}};
  EXPECT_EQ(runner::plot_strides(study, 65536), (std::vector<std::size_t>{1, 1}));
  EXPECT_EQ(runner::plot_strides(study, 1000), (std::vector<std::size_t>{31, 1}));  // 33 x 30
  const fs::path dir = fresh_dir("streaming_decimated");
  runner::GridOrderWriter writer(study, {"out"}, dir / "results.csv", runner::ResultsFormat::csv,
                                 Json::object(), 1000);
  for (std::size_t p = study.point_count(); p-- > 0;) writer.add(p, ok({static_cast<double>(p)}));
  writer.commit();
  const ResultTable plot = writer.take_plot_table();
  ASSERT_TRUE(plot.decimated());
  EXPECT_EQ(plot.strides, (std::vector<std::size_t>{31, 1}));
  EXPECT_EQ(plot.full_point_count, 30000u);
  const Study& thin = writer.plot_study();
  ASSERT_EQ(thin.grid[0].values.size(), 33u);
  EXPECT_EQ(thin.grid[0].values[1], 31.0);
  ASSERT_EQ(plot.rows.size(), 990u);
  // Row 31 = a index 1 (value 31), b index 1: point 31 * 30 + 1 of the whole grid.
  EXPECT_EQ(plot.rows[31], (std::vector<Json>{31.0, 101.0, 31.0 * 30 + 1}));
  EXPECT_EQ(lines_of(runner::read_file(dir / "results.csv")).size(), 30001u);
}

TEST(RunnerJournal, FingerprintChangesWithTheComputation) {
  Study study = two_axis_study();
  const std::string base = runner::study_fingerprint(study, {"out"});
  EXPECT_EQ(base.size(), 64u);
  EXPECT_EQ(runner::study_fingerprint(two_axis_study(), {"out"}), base);
  EXPECT_NE(runner::study_fingerprint(study, {"out", "more"}), base);
  Study other_value = study;
  other_value.document["model"]["a"] = 1.5;
  EXPECT_NE(runner::study_fingerprint(other_value, {"out"}), base);
  Study other_grid = study;
  other_grid.grid[1].values.back() = 4.0;
  EXPECT_NE(runner::study_fingerprint(other_grid, {"out"}), base);
  Study swapped_axes = study;
  std::swap(swapped_axes.grid[0], swapped_axes.grid[1]);  // numbers the points differently
  EXPECT_NE(runner::study_fingerprint(swapped_axes, {"out"}), base);
}

TEST(RunnerJournal, FingerprintIgnoresWhatChangesNoNumber) {
  Study study = two_axis_study();
  const std::string base = runner::study_fingerprint(study, {"out"});
  Study renamed = study;
  renamed.document["study"]["name"] = "another name";
  renamed.document["study"]["description"] = "and a description";
  renamed.document["run"] = {{"point_timeout_s", 5.0}, {"isolate", true}};
  EXPECT_EQ(runner::study_fingerprint(renamed, {"out"}), base);
  Study reordered = study;  // tables and keys written in another order
  reordered.document = {{"model", {{"b", 2.0}, {"a", 1.0}}}, {"study", {{"kind", "stability_map"}}}};
  EXPECT_EQ(runner::study_fingerprint(reordered, {"out"}), base);
  // The content of an input file is part of it.
  const fs::path data = fresh_dir("fingerprint") / "data.csv";
  write(data, "1\n");
  Study with_data = study;
  with_data.inputs = std::make_shared<InputSnapshot>();
  with_data.inputs->read(data, InputRole::data);
  const std::string with_v1 = runner::study_fingerprint(with_data, {"out"});
  EXPECT_NE(with_v1, base);
  write(data, "2\n");
  with_data.inputs = std::make_shared<InputSnapshot>();
  with_data.inputs->read(data, InputRole::data);
  EXPECT_NE(runner::study_fingerprint(with_data, {"out"}), with_v1);
}

TEST(RunnerJournal, TimeoutsRoundTripWithTheirTime) {
  runner::JournalHeader header{"f", 3, {"a"}};
  PointResult timeout{true, {Json()}, runner::timeout_status("still running after 2 s"), 2.25};
  runner::JournalContents read = runner::parse_journal(runner::journal_header_line(header) +
                                                       runner::journal_line(1, timeout));
  ASSERT_EQ(read.records.size(), 1u);
  EXPECT_EQ(read.records[0].second.status, "timeout: still running after 2 s");
  EXPECT_EQ(read.records[0].second.elapsed_s, 2.25);
  EXPECT_EQ(runner::outcome_of(read.records[0].second.status), runner::PointOutcome::timeout);
  EXPECT_EQ(runner::reason_of(read.records[0].second.status), "still running after 2 s");
  EXPECT_EQ(runner::outcome_of("failed: x"), runner::PointOutcome::failed);
  EXPECT_EQ(runner::outcome_of("ok"), runner::PointOutcome::ok);
}

TEST(RunnerResume, OkRecordsWinAndRetryFailedLeavesFailuresToCompute) {
  Study study = two_axis_study();
  const std::vector<std::string> columns{"out"};
  const runner::JournalHeader header{runner::study_fingerprint(study, columns), 6, columns,
                                     runner::result_inputs(study)};
  fs::path out = fresh_dir("journals");
  PointResult failed{true, {Json()}, "failed: disk full", 0.0};
  // Session 1: point 0 ok, 1 failed, 2 timed out. Session 10 (sorted after 2 as text, before it
  // by number): point 1 ok. Session 2: point 0 failed (must not replace the ok record).
  write(runner::journal_file(out, 1, 0),
        runner::journal_header_line(header) + runner::journal_line(0, ok({1.0})) +
            runner::journal_line(1, failed) +
            runner::journal_line(2, {true, {Json()}, runner::timeout_status("slow"), 9.0}));
  write(runner::journal_file(out, 2, 0),
        runner::journal_header_line(header) + runner::journal_line(0, failed));
  write(runner::journal_file(out, 10, 0),
        runner::journal_header_line(header) + runner::journal_line(1, ok({2.0})));
  runner::ResumedPoints all = runner::read_journals(out, header, study, false);
  ASSERT_EQ(all.count(), 3u);
  EXPECT_FALSE(all.has(3));
  EXPECT_EQ(all.buffered_records(), 0u);  // found, not read: records are read when taken
  const PointResult p0 = all.take(0), p1 = all.take(1), p2 = all.take(2);
  EXPECT_EQ(p0.status, "ok");
  EXPECT_EQ(p0.outputs[0], 1.0);
  EXPECT_EQ(p1.status, "ok");
  EXPECT_EQ(p1.outputs[0], 2.0);
  EXPECT_EQ(runner::outcome_of(p2.status), runner::PointOutcome::timeout);
  EXPECT_EQ(p2.elapsed_s, 9.0);
  // Records stream from the files in grid order: one cannot go back, nor take a point twice.
  EXPECT_THROW(all.take(1), std::logic_error);
  EXPECT_THROW(all.take(2), std::logic_error);
  runner::ResumedPoints retry = runner::read_journals(out, header, study, true);
  ASSERT_EQ(retry.count(), 2u);  // the timed-out point 2 is computed again
  EXPECT_TRUE(retry.has(1));
  EXPECT_FALSE(retry.has(2));
  EXPECT_THROW(retry.take(2), std::logic_error);
}

// A resume reads the journals line by line and keeps only where each record is: a journal line
// that changes between the scan and the read is an error, not a silently different result.
TEST(RunnerResume, AJournalChangedAfterTheScanIsAnError) {
  Study study = two_axis_study();
  const std::vector<std::string> columns{"out"};
  const runner::JournalHeader header{runner::study_fingerprint(study, columns), 6, columns,
                                     runner::result_inputs(study)};
  fs::path out = fresh_dir("journal_changed");
  const fs::path file = runner::journal_file(out, 1, 0);
  write(file, runner::journal_header_line(header) + runner::journal_line(3, ok({1.0})) +
                  runner::journal_line(0, ok({7.0})) + "{\"i\":1,\"out\":[2");  // cut by a kill
  runner::ResumedPoints resumed = runner::read_journals(out, header, study, false);
  EXPECT_EQ(resumed.count(), 2u);
  EXPECT_EQ(resumed.truncated_lines, 1u);
  EXPECT_EQ(resumed.take(0).outputs[0], 7.0);  // the second line, found by its place
  EXPECT_EQ(resumed.take(3).outputs[0], 1.0);
  runner::ResumedPoints changed = runner::read_journals(out, header, study, false);
  write(file, runner::journal_header_line(header) + runner::journal_line(4, ok({1.0})));
  EXPECT_THROW(changed.take(3), std::runtime_error);
}

TEST(RunnerResume, FirstDifferenceNamesThePathAndBothValues) {
  Json then = {{"model", {{"a", 1.0}, {"modes", {{{"f", 10.0}}, {{"f", 20.0}}}}}}};
  Json now = then;
  EXPECT_EQ(runner::first_difference(then, now), "");
  now["model"]["modes"][1]["f"] = 25.5;
  EXPECT_EQ(runner::first_difference(then, now), "model.modes.1.f: 20 then, 25.5 now");
  now = then;
  now["model"]["b"] = true;
  EXPECT_EQ(runner::first_difference(then, now), "model.b: absent then, true now");
  EXPECT_EQ(runner::result_relevant({{"study", {{"kind", "k"}, {"name", "n"}}}, {"run", {}}}),
            Json({{"study", {{"kind", "k"}}}}));
}

// ------------------------------------------------------------------ files and directories
TEST(RunnerFiles, AtomicWriteReplacesAndLeavesNoTemporaries) {
  fs::path dir = fresh_dir("atomic");
  fs::create_directories(dir);
  runner::write_file_atomically(dir / "results.csv", "old\n");
  runner::write_file_atomically(dir / "results.csv", "new\n");
  EXPECT_EQ(runner::read_file(dir / "results.csv"), "new\n");
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1u);  // no temporaries left
  runner::write_file_atomically(dir / "sub" / "x.csv", "x");  // parent directories are created
  EXPECT_EQ(runner::read_file(dir / "sub" / "x.csv"), "x");
  EXPECT_THROW(runner::write_file_atomically(dir / "results.csv" / "x.csv", "x"), std::runtime_error);
}

TEST(RunnerOutputDir, CreatesMarksAndReplacesOnlyItsOwnRuns) {
  fs::path dir = fresh_dir("owned") / "nested" / "out";
  runner::prepare_output_dir(dir, false, "s.toml");
  EXPECT_TRUE(fs::exists(dir / runner::output_marker_name));

  write(dir / "results.csv", "previous run\n");
  write(dir / "journal" / "points-1-0.jsonl", "{}\n");
  runner::prepare_output_dir(dir, true, "s.toml");  // --resume keeps the previous run
  EXPECT_TRUE(fs::exists(dir / "results.csv"));
  EXPECT_TRUE(fs::exists(dir / "journal" / "points-1-0.jsonl"));
  runner::prepare_output_dir(dir, false, "s.toml");  // a new run replaces it cleanly
  EXPECT_FALSE(fs::exists(dir / "results.csv"));
  EXPECT_FALSE(fs::exists(dir / "journal"));
  EXPECT_TRUE(fs::exists(dir / runner::output_marker_name));
}

TEST(RunnerOutputDir, RefusesForeignAndUnusableDirectories) {
  fs::path foreign = fresh_dir("foreign");
  write(foreign / "thesis.tex", "precious");
  for (bool resume : {false, true}) {
    try {
      runner::prepare_output_dir(foreign, resume, "s.toml");
      ADD_FAILURE() << "a non-empty directory without the chatterlab mark was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not written by chatterlab"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(foreign.string()), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(runner::read_file(foreign / "thesis.tex"), "precious");
  EXPECT_FALSE(fs::exists(foreign / runner::output_marker_name));

  fs::path file = foreign / "thesis.tex";
  EXPECT_THROW(runner::prepare_output_dir(file, false, "s.toml"), InputError);  // a file
  EXPECT_THROW(runner::prepare_output_dir(file / "out", false, "s.toml"), InputError);  // under a file
  EXPECT_THROW(runner::prepare_output_dir("/proc/chatterlab_runner_test", false, "s.toml"),
               InputError);
}

TEST(RunnerOutputDir, ALockedDirectoryIsRefusedNamingTheHolderAndLeftAlone) {
  fs::path dir = fresh_dir("locked");
  auto lock = runner::prepare_output_dir(dir, false, "first.toml");
  write(dir / "results.csv", "the first run's\n");
  for (bool resume : {false, true}) {
    try {
      runner::prepare_output_dir(dir, resume, "second.toml");
      ADD_FAILURE() << "a second run took a locked directory";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("is in use by another chatterlab run (PID " + std::to_string(::getpid()) +
                       " on host "),
                std::string::npos)
          << m;
      EXPECT_NE(m.find("first.toml since "), std::string::npos) << m;
      EXPECT_NE(m.find("nothing was changed"), std::string::npos) << m;
    }
  }
  EXPECT_EQ(runner::read_file(dir / "results.csv"), "the first run's\n");
  lock.reset();  // released: the next run may take it
  EXPECT_NO_THROW(runner::prepare_output_dir(dir, true, "second.toml"));
}

TEST(RunnerJournalWriter, LinesReachTheFileWithinTheFlushIntervalWithoutAnotherPoint) {
  fs::path dir = fresh_dir("writer");
  fs::create_directories(dir);
  const fs::path file = dir / "points-1-0.jsonl";
  runner::JournalWriter writer(file, "header\n");
  EXPECT_EQ(runner::read_file(file), "header\n");
  writer.append("one\n");
  // No further append, no flush(): the writer thread must put it on disk by itself (documented
  // within 0.1 s; 5 s is the allowance for a loaded machine, not the guarantee).
  const auto start = std::chrono::steady_clock::now();
  while (runner::read_file(file) != "header\none\n" &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(5))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(runner::read_file(file), "header\none\n");
  writer.append("two\n");
  writer.flush();
  EXPECT_EQ(runner::read_file(file), "header\none\ntwo\n");
  EXPECT_EQ(writer.error(), "");
  EXPECT_THROW(runner::JournalWriter(file, "again\n"), std::runtime_error);  // never reused
}

TEST(RunnerWorkerProtocol, FramesAndTheStudyCrossTheSocketUnchanged) {
  int sockets[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, sockets), 0);
  const std::string big(200000, 'x');  // larger than a socket buffer: sent in pieces
  std::thread sender([&] {
    EXPECT_TRUE(runner::worker::write_frame(sockets[0], "first"));
    EXPECT_TRUE(runner::worker::write_frame(sockets[0], ""));
    EXPECT_TRUE(runner::worker::write_frame(sockets[0], big));
    ::close(sockets[0]);
  });
  EXPECT_EQ(runner::worker::read_frame(sockets[1]), "first");
  EXPECT_EQ(runner::worker::read_frame(sockets[1]), "");
  EXPECT_EQ(runner::worker::read_frame(sockets[1]), big);
  EXPECT_EQ(runner::worker::read_frame(sockets[1]), std::nullopt);  // the peer is gone
  sender.join();
  ::close(sockets[1]);
  EXPECT_FALSE(runner::worker::write_frame(sockets[1], "x"));  // never a SIGPIPE

  Study study = two_axis_study();
  study.document["model"]["a"] = 0.1 + 0.2;  // a double that must survive exactly
  study.plugin_libraries = {"/p/libx.so"};
  const Study back = runner::worker::study_from_json(
      Json::parse(runner::json_text(runner::worker::study_to_json(study))));
  EXPECT_EQ(back.kind, study.kind);
  EXPECT_EQ(back.file, study.file);
  EXPECT_EQ(back.plugin_libraries, study.plugin_libraries);
  EXPECT_EQ(back.point_count(), study.point_count());
  for (std::size_t p = 0; p < study.point_count(); ++p)
    EXPECT_EQ(back.point_document(p), study.point_document(p)) << p;
  const double a = back.document["model"]["a"].get<double>(), want = 0.1 + 0.2;
  EXPECT_EQ(std::memcmp(&a, &want, sizeof a), 0);
}

TEST(RunnerOutputDir, JournalSessionsCount) {
  fs::path dir = fresh_dir("sessions");
  EXPECT_EQ(runner::next_journal_session(dir), 1);
  write(runner::journal_file(dir, 1, 0), "");
  write(runner::journal_file(dir, 2, 1), "");
  write(runner::journal_dir(dir) / "notes.txt", "");
  write(runner::journal_dir(dir) / "points-x-0.jsonl", "");
  auto files = runner::journal_files(dir);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].filename(), "points-1-0.jsonl");
  EXPECT_EQ(files[1].filename(), "points-2-1.jsonl");
  EXPECT_EQ(runner::next_journal_session(dir), 3);
}

TEST(RunnerProgress, BarShowsFractionCountAndEta) {
  EXPECT_EQ(runner::ProgressBar::format(5, 10, 10.0),
            "[###############...............]  50%  5/10 points  10 s elapsed  ETA 10 s");
  EXPECT_EQ(runner::ProgressBar::format(0, 10, 1.0),
            "[..............................]   0%  0/10 points  1 s elapsed  ETA ?");
  EXPECT_NE(runner::ProgressBar::format(1, 100, 60.0).find("ETA 1:39:00 h"), std::string::npos);
}

TEST(RunnerBuildInfo, VersionsAndTheBuildsRevisionWithoutTheSourceTree) {
  Json info = runner::build_info();
  EXPECT_EQ(info["chatterlab"], CHATTERLAB_VERSION);
  EXPECT_EQ(info["dependencies"]["sundials"].get<std::string>().substr(0, 2), "6.");
  // The commit recorded at build time (cmake/build_revision.cmake): 40 hex digits in a checkout.
  const std::string revision = info["git_revision"].get<std::string>();
  EXPECT_EQ(revision.size(), 40u) << revision;
  EXPECT_EQ(revision.find_first_not_of("0123456789abcdef"), std::string::npos) << revision;
  // An installed chatterlab knows nothing of the tree it was built in.
  EXPECT_EQ(info.dump().find(CHATTERLAB_SOURCE_DIR), std::string::npos) << info.dump();
}

// ------------------------------------------------------------------ run_study
// A study kind for these tests: [runner_test] x -> x^2. Negative x fails (PointFailure), x = 99
// returns a non-finite number, x = 98 throws a plain std::runtime_error.
std::atomic<int> square_calls{0};

class SquareKind final : public StudyKind {
 public:
  static PluginInfo info() {
    return testing::one_parameter_kind_info("runner_test_square", "test kind of runner_test.cpp: x squared", "x",
                                            "the number to square", 2.0);
  }
  std::vector<std::string> tables() const override { return {"runner_test"}; }
  void validate(Json& document, const SourceMap& sources) const override {
    Json table = document.contains("runner_test") ? document["runner_test"] : Json::object();
    document["runner_test"] = validate_params(table, info().params, "runner_test", sources);
  }
  std::vector<std::string> output_columns(const Json&) const override {
    return {"square", "big", "note"};
  }
  std::vector<Json> run_point(const Json& point, const PointContext&) const override {
    ++square_calls;
    double x = point.at("runner_test").at("x").get<double>();
    if (x < 0) throw PointFailure("negative x,\nno square");
    if (x == 98) throw std::runtime_error("plain exception");
    if (x == 99) return {std::numeric_limits<double>::infinity(), true, "inf"};
    return {x * x, x > 1, "x, squared"};
  }
  void write_artifacts(const Study&, const ResultTable& results,
                       const fs::path& out) const override {
    write(out / "artifact.txt", std::to_string(results.rows.size()) + "\n");
  }
};

const Registry<StudyKind>& square_kind_registered() {
  static const bool added = (add_study_kind<SquareKind>(study_kind_registry()), true);
  (void)added;
  return study_kind_registry();
}

Study square_study(std::vector<Json> xs) {
  square_kind_registered();
  Study study;
  study.file = "square.toml";
  study.kind = "runner_test_square";
  study.document = {{"study", {{"kind", "runner_test_square"}}}, {"runner_test", {{"x", 1.0}}}};
  study.grid = {GridAxis{"x", "runner_test.x", std::move(xs), {}}};
  return study;
}

RunOptions quiet(const fs::path& out, int threads = 2) {
  RunOptions options;
  options.out_dir = out;
  options.threads = threads;
  options.progress = false;
  return options;
}

TEST(RunStudy, RecordsFailuresAndWritesEveryFile) {
  Study study = square_study({-1.0, 0.5, 2.0, 99.0, 98.0, 3.0});
  fs::path out = fresh_dir("run");
  RunSummary summary = run_study(study, quiet(out));
  EXPECT_EQ(summary.points, 6u);
  EXPECT_EQ(summary.failed, 3u);
  EXPECT_EQ(summary.resumed, 0u);
  EXPECT_EQ(summary.exit_code(), 1);

  EXPECT_EQ(runner::read_file(out / "results.csv"),
            "x,square,big,note,status\n"
            "-1,,,,\"failed: negative x, no square\"\n"
            "0.5,0.25,false,\"x, squared\",ok\n"
            "2,4,true,\"x, squared\",ok\n"
            "99,,,,failed: square is not finite (inf)\n"
            "98,,,,failed: plain exception\n"
            "3,9,true,\"x, squared\",ok\n");
  EXPECT_EQ(runner::read_file(out / "artifact.txt"), "6\n");

  Json meta = Json::parse(runner::read_file(out / "meta.json"));
  EXPECT_EQ(meta["state"], "complete");
  EXPECT_EQ(meta["points"], 6);
  EXPECT_EQ(meta["points_failed"], 3);
  ASSERT_EQ(meta["failed_points"].size(), 3u);
  EXPECT_EQ(meta["failed_points"][0]["point"], 0);
  EXPECT_EQ(meta["failed_points"][0]["grid"]["x"], -1.0);
  EXPECT_EQ(meta["failed_points"][0]["reason"], "negative x, no square");
  EXPECT_EQ(meta["run"]["points_computed"], 6);
  EXPECT_EQ(meta["run"]["points_resumed"], 0);
  EXPECT_EQ(meta["run"]["threads_per_rank"], 2);
  EXPECT_EQ(meta["run"]["ranks"], 1);
  EXPECT_EQ(meta["study"]["runner_test"]["x"], 1.0);
  EXPECT_TRUE(meta["timings"]["wall_s"].is_number());
  EXPECT_TRUE(meta["plot_errors"].empty());

  auto journal = runner::parse_journal(runner::read_file(runner::journal_file(out, 1, 0)));
  EXPECT_TRUE(journal.header_found);
  EXPECT_EQ(journal.records.size(), 6u);
}

TEST(RunStudy, ResumeTakesFinishedPointsFromTheJournalWithoutRecomputing) {
  Study study = square_study({1.0, 2.0, 3.0, 4.0, 5.0});
  fs::path out = fresh_dir("resume");
  run_study(study, quiet(out));
  const std::string complete = runner::read_file(out / "results.csv");

  // An interrupted run: points 1 and 3 finished, a third line cut by the kill. Their journal
  // values are marked (-7, -9) so the results show whether they were taken over or recomputed.
  std::vector<std::string> columns{"square", "big", "note"};
  std::string journal =
      runner::journal_header_line({runner::study_fingerprint(study, columns), 5, columns});
  journal += runner::journal_line(1, ok({-7.0, true, "x, squared"}));
  journal += runner::journal_line(3, ok({-9.0, true, "x, squared"}));
  journal += runner::journal_line(4, ok({25.0, true, "x, squared"})).substr(0, 20);
  fs::remove_all(runner::journal_dir(out));
  fs::remove(out / "results.csv");
  write(runner::journal_file(out, 1, 0), journal);

  const int calls_before = square_calls;
  RunSummary summary = run_study(study, [&] {
    auto o = quiet(out);
    o.resume = true;
    return o;
  }());
  EXPECT_EQ(square_calls - calls_before, 3);  // points 0, 2, 4 only
  EXPECT_EQ(summary.resumed, 2u);
  EXPECT_EQ(summary.failed, 0u);
  std::vector<std::string> rows = lines_of(runner::read_file(out / "results.csv"));
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[2], "2,-7,true,\"x, squared\",ok");
  EXPECT_EQ(rows[4], "4,-9,true,\"x, squared\",ok");
  EXPECT_EQ(rows[5], "5,25,true,\"x, squared\",ok");
  Json meta = Json::parse(runner::read_file(out / "meta.json"));
  EXPECT_EQ(meta["run"]["points_resumed"], 2);
  EXPECT_EQ(meta["run"]["points_computed"], 3);
  EXPECT_EQ(meta["run"]["journal_lines_ignored"]["truncated"], 1);
  EXPECT_EQ(meta["run"]["journal_session"], 2);  // a new journal file; the cut one is left as is

  // Resuming a complete run recomputes nothing and rewrites the same results.
  const int calls_complete = square_calls;
  RunSummary again = run_study(study, [&] {
    auto o = quiet(out, 1);
    o.resume = true;
    return o;
  }());
  EXPECT_EQ(square_calls, calls_complete);
  EXPECT_EQ(again.resumed, 5u);

  // Without --resume the journal is discarded and everything recomputed.
  run_study(study, quiet(out, 1));
  EXPECT_EQ(runner::read_file(out / "results.csv"), complete);
  EXPECT_EQ(square_calls - calls_complete, 5);
}

TEST(RunStudy, ResumeRefusesTheJournalOfAnotherStudy) {
  fs::path out = fresh_dir("resume_other");
  run_study(square_study({1.0, 2.0}), quiet(out));
  const std::string meta = runner::read_file(out / "meta.json");
  const std::string results = runner::read_file(out / "results.csv");
  RunOptions options = quiet(out);
  options.resume = true;
  try {
    run_study(square_study({1.0, 2.5}), options);
    ADD_FAILURE() << "resumed from another study's journal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot resume from"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("run without --resume"), std::string::npos) << e.what();
  }
  EXPECT_EQ(runner::read_file(out / "meta.json"), meta);  // the earlier run is left as it was
  EXPECT_EQ(runner::read_file(out / "results.csv"), results);
}

TEST(RunStudy, RetryFailedComputesOnlyTheFailedPointsAgain) {
  Study study = square_study({-1.0, 2.0, 98.0, 3.0});
  fs::path out = fresh_dir("retry");
  run_study(study, quiet(out));
  RunOptions options = quiet(out);
  options.resume = true;
  const int before = square_calls;
  EXPECT_EQ(run_study(study, options).resumed, 4u);
  EXPECT_EQ(square_calls, before);  // failed points are results too
  options.retry_failed = true;
  RunSummary retried = run_study(study, options);
  EXPECT_EQ(square_calls - before, 2);  // -1 and 98 again
  EXPECT_EQ(retried.resumed, 2u);
  EXPECT_EQ(retried.failed, 2u);
}

TEST(RunStudy, AnOutputThatCannotBeWrittenIsExitCode3WithMetaJsonSayingSo) {
  Study study = square_study({1.0, 2.0});
  fs::path out = fresh_dir("output_failure");
  run_study(study, quiet(out));
  fs::remove(out / "results.csv");
  fs::create_directories(out / "results.csv" / "in_the_way");
  RunOptions options = quiet(out);
  options.resume = true;
  RunSummary summary = run_study(study, options);
  EXPECT_EQ(summary.exit_code(), 3);
  EXPECT_NE(summary.output_error.find("results.csv"), std::string::npos) << summary.output_error;
  Json meta = Json::parse(runner::read_file(out / "meta.json"));
  EXPECT_EQ(meta["state"], "output_failed");
  EXPECT_EQ(meta["output_error"], summary.output_error);
  for (const auto& entry : fs::recursive_directory_iterator(out))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  EXPECT_FALSE(fs::exists(out / runner::output_reserve_name));
}

TEST(RunStudy, ALockedOutputDirectoryIsRefusedBeforeAnyPoint) {
  fs::path out = fresh_dir("run_locked");
  run_study(square_study({1.0}), quiet(out));
  runner::OutputLock holder(out, "holder.toml");
  const int calls_before = square_calls;
  try {
    run_study(square_study({5.0, 6.0}), quiet(out));
    ADD_FAILURE() << "ran into a locked directory";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("in use by another chatterlab run"), std::string::npos);
  }
  EXPECT_EQ(square_calls, calls_before);
  EXPECT_EQ(runner::read_file(out / "results.csv"), "x,square,big,note,status\n1,1,false,\"x, squared\",ok\n");
}

TEST(RunStudy, UnusableOutputDirectoryFailsBeforeAnyPoint) {
  const int calls_before = square_calls;
  EXPECT_THROW(run_study(square_study({1.0}), quiet("/proc/chatterlab_runner_test/out")),
               InputError);
  EXPECT_EQ(square_calls, calls_before);
}

TEST(RunStudy, ResultsDoNotDependOnThreadCount) {
  std::vector<Json> xs;
  for (int i = 0; i < 200; ++i) xs.push_back(0.37 * i - 3.0);
  Study study = square_study(xs);
  fs::path one = fresh_dir("threads1"), four = fresh_dir("threads4");
  run_study(study, quiet(one, 1));
  run_study(study, quiet(four, 4));
  EXPECT_EQ(runner::read_file(one / "results.csv"), runner::read_file(four / "results.csv"));
}

}  // namespace
}  // namespace chatterlab
