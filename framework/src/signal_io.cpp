#include "chatterlab/signal_io.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"

namespace chatterlab {

namespace fs = std::filesystem;

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string_view unquote(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

std::optional<double> parse_number(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double value = 0.0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

enum class Separator { comma, semicolon, blank };

Separator detect_separator(std::string_view line) {
  if (line.find(',') != std::string_view::npos) return Separator::comma;
  if (line.find(';') != std::string_view::npos) return Separator::semicolon;
  return Separator::blank;
}

std::vector<std::string_view> split(std::string_view line, Separator sep) {
  std::vector<std::string_view> fields;
  if (sep == Separator::blank) {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i >= line.size()) break;
      std::size_t j = i;
      while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
      fields.push_back(line.substr(i, j - i));
      i = j;
    }
    return fields;
  }
  const char c = sep == Separator::comma ? ',' : ';';
  std::size_t start = 0;
  while (true) {
    std::size_t pos = line.find(c, start);
    fields.push_back(line.substr(start, pos == std::string_view::npos ? pos : pos - start));
    if (pos == std::string_view::npos) break;
    start = pos + 1;
  }
  return fields;
}

DataTable read_text_table(const fs::path& file, std::string_view text) {
  if (text.size() >= 3 && std::memcmp(text.data(), "\xEF\xBB\xBF", 3) == 0) text.remove_prefix(3);
  DataTable table;
  table.file = file;
  std::optional<Separator> sep;
  std::size_t line_number = 0;
  // At most one row per line: reserving that many values per column avoids the reallocations
  // (and their transient 3x peak) of growing columns of 10^7 rows.
  const auto max_rows = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') {
      if (end == text.size()) break;
      continue;
    }
    if (!sep) sep = detect_separator(content);
    auto fields = split(content, *sep);
    if (table.columns.empty() && table.names.empty()) {
      bool header = std::any_of(fields.begin(), fields.end(), [](std::string_view f) {
        return !parse_number(f).has_value();
      });
      table.columns.resize(fields.size());
      for (auto& column : table.columns) column.reserve(max_rows);
      if (header) {
        for (auto f : fields) table.names.emplace_back(unquote(f));
        if (end == text.size()) break;
        continue;
      }
      for (std::size_t c = 0; c < fields.size(); ++c) table.names.push_back(std::to_string(c + 1));
    }
    if (fields.size() != table.columns.size())
      throw InputError(fmt::format("{}: line {}: {} fields, but the table has {} columns ({})",
                                   file.string(), line_number, fields.size(),
                                   table.columns.size(), fmt::join(table.names, ", ")));
    for (std::size_t c = 0; c < fields.size(); ++c) {
      auto value = parse_number(fields[c]);
      if (!value)
        throw InputError(fmt::format("{}: line {}: column '{}': '{}' is not a number",
                                     file.string(), line_number, table.names[c],
                                     std::string(trim(fields[c]))));
      if (!std::isfinite(*value))
        throw InputError(fmt::format("{}: line {}: column '{}': {} is not finite", file.string(),
                                     line_number, table.names[c], std::string(trim(fields[c]))));
      table.columns[c].push_back(*value);
    }
    const std::size_t row = table.columns.front().size() - 1;
    if (table.line_runs.empty() ||
        table.line_runs.back().second + (row - table.line_runs.back().first) != line_number)
      table.line_runs.emplace_back(row, line_number);
    if (end == text.size()) break;
  }
  if (table.rows() == 0)
    throw InputError(fmt::format("{}: no data rows (only {})", file.string(),
                                 table.names.empty() ? "comments or blank lines" : "a header"));
  // Comment and blank lines reserved room for rows that never came: give it back when it is
  // more than a little (shrinking copies the column).
  for (auto& column : table.columns)
    if (column.capacity() - column.size() > column.size() / 8) column.shrink_to_fit();
  return table;
}

template <class T>
T read_le(std::string_view bytes, std::size_t offset) {
  T value{};
  std::memcpy(&value, bytes.data() + offset, sizeof(T));  // WAV is little-endian, as is x86/ARM
  return value;
}

DataTable read_wav(const fs::path& file, std::string_view bytes) {
  auto fail = [&](const std::string& why) {
    return InputError(fmt::format("{}: not a readable WAV file: {}", file.string(), why));
  };
  if (bytes.size() < 12 || bytes.substr(0, 4) != "RIFF" || bytes.substr(8, 4) != "WAVE")
    throw fail("no RIFF/WAVE header");
  std::uint16_t format = 0, channels = 0, bits = 0;
  std::uint32_t rate = 0;
  std::string_view data;
  bool have_format = false;
  for (std::size_t at = 12; at + 8 <= bytes.size();) {
    std::string_view id = bytes.substr(at, 4);
    const std::uint32_t size = read_le<std::uint32_t>(bytes, at + 4);
    const std::size_t body = at + 8;
    const std::size_t available = std::min<std::size_t>(size, bytes.size() - body);
    if (id == "fmt ") {
      if (available < 16) throw fail("fmt chunk too short");
      format = read_le<std::uint16_t>(bytes, body);
      channels = read_le<std::uint16_t>(bytes, body + 2);
      rate = read_le<std::uint32_t>(bytes, body + 4);
      bits = read_le<std::uint16_t>(bytes, body + 14);
      if (format == 0xFFFE && available >= 26) format = read_le<std::uint16_t>(bytes, body + 24);
      have_format = true;
    } else if (id == "data") {
      data = bytes.substr(body, available);  // a recorder killed mid-file leaves size too large
    }
    at = body + size + (size & 1u);
  }
  if (!have_format) throw fail("no fmt chunk");
  if (data.empty()) throw fail("no data chunk");
  if (channels == 0 || rate == 0) throw fail("zero channels or sample rate");
  const bool pcm = format == 1, ieee = format == 3;
  if (!(pcm && (bits == 8 || bits == 16 || bits == 24 || bits == 32)) &&
      !(ieee && (bits == 32 || bits == 64)))
    throw fail(fmt::format("format {} with {} bits per sample is not supported (PCM 8/16/24/32 or "
                           "float 32/64)", format, bits));
  const std::size_t sample_bytes = bits / 8u;
  const std::size_t frames = data.size() / (sample_bytes * channels);
  DataTable table;
  table.file = file;
  table.sample_rate_hz = static_cast<double>(rate);
  table.columns.assign(channels, std::vector<double>(frames));
  for (std::size_t c = 0; c < channels; ++c) table.names.push_back(std::to_string(c + 1));
  for (std::size_t f = 0; f < frames; ++f)
    for (std::size_t c = 0; c < channels; ++c) {
      const std::size_t at = (f * channels + c) * sample_bytes;
      double v = 0.0;
      if (ieee) {
        v = bits == 32 ? read_le<float>(data, at) : read_le<double>(data, at);
        if (!std::isfinite(v))
          throw InputError(fmt::format("{}: channel {} frame {}: sample is not finite",
                                       file.string(), c + 1, f));
      } else if (bits == 8) {
        v = (static_cast<double>(static_cast<std::uint8_t>(data[at])) - 128.0) / 128.0;
      } else if (bits == 16) {
        v = read_le<std::int16_t>(data, at) / 32768.0;
      } else if (bits == 24) {
        std::int32_t s = static_cast<std::uint8_t>(data[at]) |
                         (static_cast<std::uint8_t>(data[at + 1]) << 8) |
                         (static_cast<std::int8_t>(data[at + 2]) * 65536);
        v = s / 8388608.0;
      } else {
        v = read_le<std::int32_t>(data, at) / 2147483648.0;
      }
      table.columns[c][f] = v;
    }
  if (frames == 0) throw fail("the data chunk holds no complete frame");
  return table;
}

bool is_wav_name(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".wav" || ext == ".wave";
}

}  // namespace

std::size_t DataTable::column_index(const std::string& column) const {
  for (std::size_t c = 0; c < names.size(); ++c)
    if (names[c] == column) return c;
  const bool digits = !column.empty() && std::all_of(column.begin(), column.end(), [](char ch) {
    return std::isdigit(static_cast<unsigned char>(ch));
  });
  if (digits) {
    const std::size_t index = std::stoul(column);
    if (index >= 1 && index <= columns.size()) return index - 1;
  }
  throw InputError(fmt::format("{}: no column '{}' (columns: {}{})", file.string(), column,
                               fmt::join(names, ", "),
                               columns.empty() ? "" : fmt::format("; or 1..{}", columns.size())));
}

std::size_t DataTable::source_line(std::size_t row) const {
  if (row >= rows() || line_runs.empty() || row < line_runs.front().first) return 0;
  // The last run starting at or before `row`.
  const auto run = std::prev(std::upper_bound(
      line_runs.begin(), line_runs.end(), row,
      [](std::size_t r, const std::pair<std::size_t, std::size_t>& entry) { return r < entry.first; }));
  return run->second + (row - run->first);
}

const std::vector<double>& DataTable::column(const std::string& name) const {
  return columns[column_index(name)];
}

// Through the run's input snapshot (chatterlab/input_files.hpp): read and parsed once per run,
// the same table for every grid point, whatever happens to the file meanwhile.
std::shared_ptr<const DataTable> read_shared_data_table(const fs::path& file) {
  return read_input_parsed<DataTable>(file, "data_table", [&](const std::string& bytes) {
    if (is_wav_name(file) || (bytes.size() >= 12 && bytes.compare(0, 4, "RIFF") == 0))
      return read_wav(file, bytes);
    return read_text_table(file, bytes);
  });
}

DataTable read_data_table(const fs::path& file) { return *read_shared_data_table(file); }

std::vector<double> read_signal_column(const fs::path& file, const std::string& column) {
  DataTable table = read_data_table(file);
  return std::move(table.columns[table.column_index(column)]);
}

}  // namespace chatterlab
