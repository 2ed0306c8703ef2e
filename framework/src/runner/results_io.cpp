#include "runner/results_io.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "chatterlab/input_files.hpp"

namespace chatterlab::runner {

namespace {

std::string_view without_cr(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

}  // namespace

bool parse_journal_record(std::string_view line, std::size_t points, std::size_t columns,
                  std::pair<std::size_t, PointResult>& record) {
  Json j = Json::parse(without_cr(line), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) return false;
  auto i = j.find("i");
  auto out = j.find("out");
  auto status = j.find("status");
  if (i == j.end() || !i->is_number_unsigned() || out == j.end() || !out->is_array() ||
      status == j.end() || !status->is_string())
    return false;
  std::size_t point = i->get<std::size_t>();
  if (point >= points || out->size() != columns) return false;
  const std::string& text = status->get_ref<const std::string&>();
  if (text != "ok" && text.rfind("failed: ", 0) != 0 && text.rfind("timeout: ", 0) != 0)
    return false;
  record.first = point;
  record.second.done = true;
  record.second.outputs.assign(out->begin(), out->end());
  record.second.status = text;
  if (auto elapsed = j.find("elapsed_s"); elapsed != j.end() && elapsed->is_number())
    record.second.elapsed_s = elapsed->get<double>();
  return true;
}

namespace {

// Splits text into '\n'-terminated lines; an unterminated tail is reported separately.
template <class OnLine>
std::size_t for_each_line(std::string_view text, OnLine&& on_line) {
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) return 1;  // cut by a kill: the caller drops it
    on_line(without_cr(text.substr(begin, end - begin)));
    begin = end + 1;
  }
  return 0;
}

}  // namespace

std::string json_text(const Json& value, int indent) {
  return value.dump(indent, ' ', false, Json::error_handler_t::replace);
}

// ------------------------------------------------------------------ results.csv
std::string csv_field(std::string_view text) {
  bool quote = text.find_first_of(",\"\r\n") != std::string_view::npos ||
               (!text.empty() && (text.front() == ' ' || text.back() == ' ' ||
                                  text.front() == '\t' || text.back() == '\t'));
  if (!quote) return std::string(text);
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string format_cell(const Json& value) {
  switch (value.type()) {
    case Json::value_t::null:
      return {};
    case Json::value_t::boolean:
      return value.get<bool>() ? "true" : "false";
    case Json::value_t::number_integer:
      return fmt::format("{}", value.get<std::int64_t>());
    case Json::value_t::number_unsigned:
      return fmt::format("{}", value.get<std::uint64_t>());
    case Json::value_t::number_float:
      return fmt::format("{}", value.get<double>());
    case Json::value_t::string:
      return csv_field(value.get_ref<const std::string&>());
    default:
      return csv_field(json_text(value));  // arrays/tables used as grid values
  }
}

std::string format_csv(const ResultTable& table, int threads) {
  std::string out;
  auto header_cell = [&out](std::string_view name) {
    if (!out.empty()) out += ',';
    out += csv_field(name);
  };
  for (const auto& c : table.grid_columns) header_cell(c);
  for (const auto& c : table.output_columns) header_cell(c);
  header_cell("status");
  out += '\n';
  // Rows are formatted in parallel (number-to-text is most of the ~1 us a row costs, and this
  // runs after the grid loop, on one rank) and joined in grid order: the bytes do not depend on
  // the thread count. In blocks, so that a long table is held as text once, not twice.
  constexpr std::size_t block = 1 << 16;
  std::vector<std::string> lines;
  for (std::size_t first = 0; first < table.rows.size(); first += block) {
    const std::size_t count = std::min(block, table.rows.size() - first);
    lines.assign(count, std::string());
    const auto rows = static_cast<std::ptrdiff_t>(count);
#pragma omp parallel for schedule(static) num_threads(std::max(threads, 1)) if (rows > 1000)
    for (std::ptrdiff_t r = 0; r < rows; ++r) {
      const std::size_t row = first + static_cast<std::size_t>(r);
      std::string& line = lines[static_cast<std::size_t>(r)];
      for (const auto& cell : table.rows[row]) {
        line += format_cell(cell);
        line += ',';
      }
      line += csv_field(table.status[row]);
      line += '\n';
    }
    for (const auto& line : lines) out += line;
  }
  return out;
}

namespace {
constexpr std::string_view failed_prefix = "failed: ", timeout_prefix = "timeout: ";

std::string status_text(std::string_view prefix, std::string_view reason) {
  std::string out(prefix);
  for (char c : reason) out += (c == '\n' || c == '\r') ? ' ' : c;
  if (reason.empty()) out += "unknown error";
  // Through JSON and back: invalid UTF-8 (from an exception text) becomes U+FFFD here, as it
  // would in the journal, so every rank and a resumed run print the same status.
  return Json::parse(json_text(Json(out))).get<std::string>();
}
}  // namespace

std::string failure_status(std::string_view reason) { return status_text(failed_prefix, reason); }
std::string timeout_status(std::string_view reason) { return status_text(timeout_prefix, reason); }

PointOutcome outcome_of(std::string_view status) {
  if (status.substr(0, timeout_prefix.size()) == timeout_prefix) return PointOutcome::timeout;
  return status == "ok" ? PointOutcome::ok : PointOutcome::failed;
}

std::string_view reason_of(std::string_view status) {
  for (std::string_view prefix : {failed_prefix, timeout_prefix})
    if (status.substr(0, prefix.size()) == prefix) return status.substr(prefix.size());
  return status;
}

// ------------------------------------------------------------------ journal
Json result_inputs(const Study& study) {
  Json inputs = Json::object();
  if (!study.inputs) return inputs;
  for (const InputFileRecord& file : study.inputs->files())
    if (file.role != InputRole::study) inputs[file.path.string()] = file.sha256;
  return inputs;
}

Json result_relevant(const Json& document) {
  Json out = document;
  if (!out.is_object()) return out;
  out.erase("run");
  out.erase("output");
  if (auto it = out.find("study"); it != out.end() && it->is_object()) {
    it->erase("name");
    it->erase("description");
  }
  return out;
}

std::string study_fingerprint(const Study& study, const std::vector<std::string>& columns) {
  const Json document = result_relevant(study.document);
  // Sorted keys (nlohmann::json is a sorted map): writing the tables or keys in another order
  // is the same study. The grid's order does matter (it numbers the points) and comes next.
  const nlohmann::json canonical = nlohmann::json::parse(json_text(document));
  std::string text = study.kind + '\n' + canonical.dump(-1, ' ', false,
                                                         nlohmann::json::error_handler_t::replace);
  text += '\n';
  for (const auto& axis : study.grid) {
    Json values(axis.values);
    text += axis.key + '\n' + axis.path + '\n' + json_text(values) + '\n';
  }
  for (const auto& c : columns) text += c + '\n';
  text += json_text(result_inputs(study)) + '\n';
  return sha256_hex(text);
}

std::string journal_header_line(const JournalHeader& header) {
  Json j = {{"chatterlab_journal", 2},
            {"study", header.study_fingerprint},
            {"points", header.points},
            {"columns", header.columns},
            {"inputs", header.inputs}};
  return json_text(j) + '\n';
}

std::string journal_line(std::size_t point, const PointResult& result) {
  Json j = {{"i", point}, {"out", result.outputs}, {"status", result.status}};
  if (outcome_of(result.status) == PointOutcome::timeout) j["elapsed_s"] = result.elapsed_s;
  return json_text(j) + '\n';
}

JournalContents parse_journal_records(std::string_view text, std::size_t points,
                                      std::size_t columns) {
  JournalContents contents;
  contents.truncated_lines = for_each_line(text, [&](std::string_view line) {
    if (line.empty()) return;
    std::pair<std::size_t, PointResult> record;
    if (parse_journal_record(line, points, columns, record))
      contents.records.push_back(std::move(record));
    else
      ++contents.invalid_lines;
  });
  return contents;
}

JournalContents parse_journal(std::string_view text) {
  JournalContents contents;
  std::size_t newline = text.find('\n');
  if (newline == std::string_view::npos) {  // nothing, or a header cut short
    contents.truncated_lines = text.empty() ? 0 : 1;
    return contents;
  }
  Json h = Json::parse(without_cr(text.substr(0, newline)), nullptr, false);
  if (h.is_discarded() || !h.is_object() || h.value("chatterlab_journal", 0) != 2 ||
      !h.contains("study") || !h["study"].is_string() || !h.contains("points") ||
      !h["points"].is_number_unsigned() || !h.contains("columns") || !h["columns"].is_array()) {
    contents.invalid_lines = 1;
    return contents;
  }
  for (const auto& c : h["columns"]) {
    if (!c.is_string()) {
      contents.invalid_lines = 1;
      return contents;
    }
    contents.header.columns.push_back(c.get<std::string>());
  }
  contents.header_found = true;
  if (auto inputs = h.find("inputs"); inputs != h.end() && inputs->is_object())
    contents.header.inputs = *inputs;
  contents.header.study_fingerprint = h["study"].get<std::string>();
  contents.header.points = h["points"].get<std::size_t>();
  JournalContents body = parse_journal_records(text.substr(newline + 1), contents.header.points,
                                               contents.header.columns.size());
  contents.records = std::move(body.records);
  contents.truncated_lines = body.truncated_lines;
  contents.invalid_lines = body.invalid_lines;
  return contents;
}

// ------------------------------------------------------------------ grid order
ResultTable assemble_results(const Study& study, const std::vector<std::string>& output_columns,
                             std::vector<PointResult> results) {
  ResultTable table;
  for (const auto& axis : study.grid) table.grid_columns.push_back(axis.key);
  table.output_columns = output_columns;
  const std::size_t n = study.point_count();
  if (results.size() != n)
    throw std::logic_error(fmt::format("runner: {} results for {} points", results.size(), n));
  table.rows.reserve(n);
  table.status.reserve(n);
  for (std::size_t p = 0; p < n; ++p) {
    PointResult& r = results[p];
    if (!r.done || r.outputs.size() != output_columns.size())
      throw std::logic_error(fmt::format("runner: point {} has no complete result", p));
    std::vector<Json> row;
    row.reserve(study.grid.size() + output_columns.size());
    std::vector<std::size_t> index = study.point_indices(p);
    for (std::size_t a = 0; a < study.grid.size(); ++a)
      row.push_back(study.grid[a].values[index[a]]);
    for (Json& output : r.outputs) row.push_back(std::move(output));
    r.outputs = {};  // freed as the table grows: the peak is one copy of the results, not two
    table.rows.push_back(std::move(row));
    table.status.push_back(std::move(r.status));
  }
  return table;
}

// ------------------------------------------------------------------ files

std::string utc_now() {
  std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace chatterlab::runner
