#pragma once
// Text formats of the study runner: results.csv cells, the per-point journal (JSON lines) that
// makes runs resumable, and atomic file replacement. Kept apart from run_study() so the formats
// are unit-tested on their own (tests/unit/runner_test.cpp).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/output_files.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::runner {

// JSON text for files and messages. Doubles print in a round-trip form (a journal line read back
// gives the identical double); invalid UTF-8 (an exception text, a path) is replaced, never
// thrown about at the end of a long run.
std::string json_text(const Json& value, int indent = -1);

// ------------------------------------------------------------------ results.csv
// One cell: numbers in shortest round-trip form (fmt "{}": the same double always prints the same
// text, whichever rank or thread computed it), booleans as true/false, null as an empty cell,
// strings quoted per RFC 4180 only when they hold a comma, quote, line break or outer blank.
std::string format_cell(const Json& value);
std::string csv_field(std::string_view text);

// The complete results.csv text: header (grid keys as written, outputs, `status`), then one line
// per row. Lines end in "\n". Long tables are formatted on `threads` OpenMP threads.
std::string format_csv(const ResultTable& table, int threads = 1);

// ------------------------------------------------------------------ per-point results
struct PointResult {
  bool done = false;
  std::vector<Json> outputs;  // one per output column; null cells for a failed point
  std::string status;         // "ok", "failed: <reason>" or "timeout: <reason>"
  double elapsed_s = 0.0;     // timeouts only: how long the point ran before it was stopped
};

// "failed: <reason>" on one line: line breaks in exception texts would split CSV rows for line
// tools (awk, grep) even though quoting keeps the CSV itself valid.
std::string failure_status(std::string_view reason);
// "timeout: <reason>", for a point stopped at its time limit.
std::string timeout_status(std::string_view reason);

// What a status says: ok, failed or timeout, and the reason after the prefix.
enum class PointOutcome { ok, failed, timeout };
PointOutcome outcome_of(std::string_view status);
std::string_view reason_of(std::string_view status);

// ------------------------------------------------------------------ journal
// File layout: a header line, then one line per finished point, each a complete JSON object
// terminated by '\n'. A reader therefore recognises a line cut by a kill (no '\n') and drops it.
//   {"chatterlab_journal":2,"study":"<fingerprint>","points":N,"columns":[...],"inputs":{...}}
//   {"i":<point>,"out":[...],"status":"ok"}          (timeouts add "elapsed_s")
struct JournalHeader {
  std::string study_fingerprint;
  std::size_t points = 0;
  std::vector<std::string> columns;
  Json inputs = Json::object();  // result_inputs(): names the file when a resume is refused
};

// Identifies everything that decides a run's numbers: the kind, the resolved document (keys
// sorted, without [study] name and description, [run] and [output]: they change no number),
// the grid axes in order, the output columns, and the content hashes of the data files and
// plugin libraries. A journal is only reused for the very same computation. SHA-256 of that canonical
// text, 64 hex digits.
std::string study_fingerprint(const Study& study, const std::vector<std::string>& columns);

// A study document without what changes no result: [study] name and description, [run], [output].
Json result_relevant(const Json& document);

// The input files that decide results (data, plugin libraries) as {path: sha256}.
Json result_inputs(const Study& study);

std::string journal_header_line(const JournalHeader& header);
std::string journal_line(std::size_t point, const PointResult& result);

struct JournalContents {
  bool header_found = false;  // false: empty file or header cut by a kill (no records usable)
  JournalHeader header;
  std::vector<std::pair<std::size_t, PointResult>> records;
  std::size_t truncated_lines = 0;  // an unterminated last line
  std::size_t invalid_lines = 0;    // terminated but unparsable / inconsistent (recomputed)
};

// Parses journal text. Records must have `columns` outputs and a point index below `points`
// (from the header); anything else counts as invalid and is left for recomputation.
JournalContents parse_journal(std::string_view text);

// One record line (its '\n' removed), or false when it is not a consistent record of a journal
// of `points` points and `columns` output columns.
bool parse_journal_record(std::string_view line, std::size_t points, std::size_t columns,
                          std::pair<std::size_t, PointResult>& record);

// Records only (no header line): the format ranks use to send their points to rank 0.
JournalContents parse_journal_records(std::string_view text, std::size_t points,
                                      std::size_t columns);

// ------------------------------------------------------------------ grid order
// The result table in grid order: row i = grid values of point i, then its outputs. Every point
// must be done (a programming error otherwise: std::logic_error).
// The results are moved into the table (for a large grid they are most of rank 0's memory).
ResultTable assemble_results(const Study& study, const std::vector<std::string>& output_columns,
                             std::vector<PointResult> results);

// ------------------------------------------------------------------ files
using chatterlab::write_file_atomically;  // chatterlab/output_files.hpp

std::string read_file(const std::filesystem::path& path);

// The current time as "2026-01-01T12:00:00Z".
std::string utc_now();

}  // namespace chatterlab::runner
