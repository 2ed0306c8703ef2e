#pragma once
// Study kit: the files a grid point writes into its artefact directory (PointContext): tables and
// the summary. Nothing is written when the context has no directory (unit tests, benchmarks).
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/output_files.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::kit {

// <artifact_dir>/<name>: a CSV table of numeric columns (csv_text), written atomically.
void write_table(const PointContext& context, const std::string& name,
                 const std::vector<std::string>& header,
                 const std::vector<std::vector<double>>& columns);

// <artifact_dir>/summary.json, written atomically.
void write_summary(const PointContext& context, const Json& summary);

// csv_text's table streamed to `path` (atomically, as AtomicFileWriter) in blocks of rows, for
// tables of 10^6 rows and more that are not held whole: fill_row(r, cells) sets the
// header.size() numbers of row r. The file is exactly csv_text of the same numbers.
void write_csv_streamed(const std::filesystem::path& path, const std::vector<std::string>& header,
                        std::size_t rows,
                        const std::function<void(std::size_t row, std::span<double> cells)>& fill_row);

// A file that grows with the input: a row per sample, window or evaluation, tens of bytes of text
// per input sample (surface's filtered.csv, chatter_monitor's alarms.csv and features.csv). For
// inputs of 10^7 samples and more such files outweigh everything else a run writes, so they are
// written by default only up to `auto_samples` input samples, above that only on request. The
// study key takes "auto" (the default), "always" or "never".
struct OnRequestFile {
  std::string table;         // the key's table, e.g. "parameters"
  std::string key;           // the key in it, e.g. "filtered_csv"
  std::string contents;      // what the file holds, e.g. "filtered.csv (... per sample)"
  std::size_t auto_samples;  // "auto" writes the file for inputs of up to this many samples

  // The key's declaration (string, the three choices, default "auto"), for `describe`.
  ParamSpec spec() const;
  // Null when the file is to be written (`choice` "always", or "auto" and samples <=
  // auto_samples); else the sentence summary.json records in its place, e.g. "not written:
  // 2000000 samples > 1000000 (parameters.filtered_csv = "auto") (parameters.filtered_csv =
  // "always" writes it)".
  std::optional<std::string> skipped(const std::string& choice, std::size_t samples) const;
};

}  // namespace chatterlab::kit
