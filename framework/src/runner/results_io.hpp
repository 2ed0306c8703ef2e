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
  std::string status;         // "ok" or "failed: <reason>"
};

// "failed: <reason>" on one line: line breaks in exception texts would split CSV rows for line
// tools (awk, grep) even though quoting keeps the CSV itself valid.
std::string failure_status(std::string_view reason);

// ------------------------------------------------------------------ journal
// File layout: a header line, then one line per finished point, each a complete JSON object
// terminated by '\n'. A reader therefore recognises a line cut by a kill (no '\n') and drops it.
//   {"chatterlab_journal":1,"study":"<fingerprint>","points":N,"columns":[...]}
//   {"i":<point>,"out":[...],"status":"ok"}
struct JournalHeader {
  std::string study_fingerprint;
  std::size_t points = 0;
  std::vector<std::string> columns;
};

// Identifies a resolved study (kind, document, grid, output columns): a journal is only reused
// for the very same computation. FNV-1a over the canonical JSON text, as 16 hex digits.
std::string study_fingerprint(const Study& study, const std::vector<std::string>& columns);

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

// Records only (no header line): the format ranks use to send their points to rank 0.
JournalContents parse_journal_records(std::string_view text, std::size_t points,
                                      std::size_t columns);

// ------------------------------------------------------------------ grid order
// The result table in grid order: row i = grid values of point i, then its outputs. Every point
// must be done (a programming error otherwise: std::logic_error).
ResultTable assemble_results(const Study& study, const std::vector<std::string>& output_columns,
                             const std::vector<PointResult>& results);

// ------------------------------------------------------------------ files
using chatterlab::write_file_atomically;  // chatterlab/output_files.hpp

std::string read_file(const std::filesystem::path& path);

}  // namespace chatterlab::runner
