// Regression references of the shipped studies (tests/regression/README.md).
//
//   compare_study_outputs snapshot OUT_DIR REF_DIR SOURCE_DIR   copies OUT_DIR's result files into
//                                         REF_DIR: small ones whole, large CSV tables as digests
//   compare_study_outputs compare REF_DIR OUT_DIR SOURCE_DIR    checks OUT_DIR against REF_DIR;
//                                         prints every difference; exit 1 if there is one
// Results name input files by absolute path (a study's data file): SOURCE_DIR, the checkout the
// studies ran from, is written as "<source>" in references and compared that way, so references
// made in one checkout hold in any other.
//
// Result files are every *.csv and *.json under an output directory except meta.json (timings,
// host), the resume journal, simulated time series and surface snapshots (megabytes of samples;
// the quantities fitted from them are in results.csv and summary.json) and plot data (*.dat).
// Numbers agree when |a - b| <= 1e-12 max(|a|, |b|) + 1e-15 scale, scale being the largest
// magnitude of the CSV column or JSON array they belong to: thread counts change the order of
// floating-point reductions, which moves results by a few units in the last place, and a value
// that is the small difference of large ones (a growth rate near 0) moves by that much of the
// large ones. Strings and booleans must be equal. Keys that hold wall-clock times are skipped.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "study_files.hpp"

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

constexpr double relative_tolerance = 1e-12;
constexpr double scale_tolerance = 1e-15;
constexpr std::uintmax_t whole_file_limit_bytes = 64 * 1024;  // larger CSV tables: digests
constexpr const char* digest_file = "digests.json";
constexpr const char* source_placeholder = "<source>";

// The checkout the studies ran from (set once in main).
std::string source_dir;

std::string portable(std::string text) {
  if (source_dir.empty()) return text;
  for (std::size_t at = 0; (at = text.find(source_dir, at)) != std::string::npos;) {
    text.replace(at, source_dir.size(), source_placeholder);
    at += std::string_view(source_placeholder).size();
  }
  return text;
}

void make_portable(Json& value) {
  if (value.is_string()) {
    value = portable(value.get<std::string>());
  } else if (value.is_structured()) {
    for (auto& item : value) make_portable(item);
  }
}

bool is_result_file(const fs::path& relative) {
  const std::string name = relative.filename().string();
  const std::string ext = relative.extension().string();
  if (ext != ".csv" && ext != ".json") return false;
  if (name == "meta.json" || name == digest_file || name == "timeseries.csv") return false;
  if (name.rfind("surfaces_", 0) == 0) return false;
  for (const auto& part : relative)
    if (part == "journal") return false;
  return true;
}

bool is_timing_key(const std::string& key) {
  return key == "wall_s" || key.find("wall_time") != std::string::npos ||
         key.find("elapsed") != std::string::npos;
}

std::vector<fs::path> result_files(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file()) {
      fs::path relative = fs::relative(entry.path(), dir);
      if (is_result_file(relative)) files.push_back(relative);
    }
  std::sort(files.begin(), files.end());
  return files;
}

using study_files::parse_number;
using study_files::read_text;
using study_files::Table;

// A CSV table with input paths written portably.
Table read_csv(const fs::path& file) {
  Table table = study_files::read_csv(file);
  for (auto& column : table.columns)
    for (auto& cell : column) cell = portable(cell);
  return table;
}

bool numeric_column(const std::vector<std::string>& cells) {
  double v = 0.0;
  for (const auto& cell : cells)
    if (!cell.empty() && !parse_number(cell, v)) return false;
  return true;
}

double column_scale(const std::vector<std::string>& cells) {
  double scale = 0.0, v = 0.0;
  for (const auto& cell : cells)
    if (parse_number(cell, v) && std::isfinite(v)) scale = std::max(scale, std::abs(v));
  return scale;
}

bool close(double a, double b, double scale) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::abs(a - b) <= relative_tolerance * std::max(std::abs(a), std::abs(b)) +
                                scale_tolerance * scale;
}

// A digest of one column: for numbers, statistics that move with any value of the column (the
// position-weighted sum catches two values swapping places); for strings, the exact values'
// FNV-1a hash.
Json column_digest(const std::vector<std::string>& cells) {
  Json d;
  d["rows"] = cells.size();
  if (numeric_column(cells)) {
    double lo = INFINITY, hi = -INFINITY, sum = 0.0, abs_sum = 0.0, weighted = 0.0, v = 0.0;
    std::size_t blanks = 0;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (!parse_number(cells[i], v) || !std::isfinite(v)) {
        ++blanks;
        continue;
      }
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      sum += v;
      abs_sum += std::abs(v);
      weighted += v * static_cast<double>(i + 1) / static_cast<double>(cells.size());
    }
    d["non_finite_or_blank"] = blanks;
    // A column without a finite value has no extremes: null, as its stored reference reads back
    // (JSON has no infinity).
    const bool none = blanks == cells.size();
    d["min"] = none ? Json() : Json(lo);
    d["max"] = none ? Json() : Json(hi);
    d["sum"] = sum;
    d["abs_sum"] = abs_sum;
    d["weighted_sum"] = weighted;
  } else {
    std::uint64_t hash = 1469598103934665603ull;
    for (const auto& cell : cells) {
      for (unsigned char c : cell) hash = (hash ^ c) * 1099511628211ull;
      hash = (hash ^ 0xffu) * 1099511628211ull;
    }
    d["fnv1a"] = std::to_string(hash);
  }
  return d;
}

Json table_digest(const Table& table) {
  Json d = Json::object();
  for (std::size_t c = 0; c < table.header.size(); ++c)
    d[table.header[c]] = column_digest(table.columns[c]);
  return d;
}

class Report {
 public:
  void difference(const std::string& where, const std::string& what) {
    if (++count_ <= 40) std::cout << where << ": " << what << '\n';
  }
  int count() const { return count_; }

 private:
  int count_ = 0;
};

std::string show(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

void compare_tables(const Table& ref, const Table& out, const std::string& file, Report& report) {
  if (ref.header != out.header) {
    report.difference(file, "columns differ");
    return;
  }
  for (std::size_t c = 0; c < ref.header.size(); ++c) {
    const auto& a = ref.columns[c];
    const auto& b = out.columns[c];
    const std::string where = file + " column " + ref.header[c];
    if (a.size() != b.size()) {
      report.difference(where, "rows " + std::to_string(a.size()) + " -> " + std::to_string(b.size()));
      continue;
    }
    const double scale = std::max(column_scale(a), column_scale(b));
    for (std::size_t r = 0; r < a.size(); ++r) {
      double x = 0.0, y = 0.0;
      const bool numbers = parse_number(a[r], x) && parse_number(b[r], y);
      if (numbers ? !close(x, y, scale) : a[r] != b[r])
        report.difference(where + " row " + std::to_string(r + 1), a[r] + " -> " + b[r]);
    }
  }
}

// ------------------------------------------------------------------ JSON
double json_scale(const Json& v) {
  double scale = 0.0;
  if (v.is_number()) return std::abs(v.get<double>());
  if (v.is_array())
    for (const auto& e : v) scale = std::max(scale, json_scale(e));
  return scale;
}

void compare_json(const Json& a, const Json& b, const std::string& where, double scale,
                  Report& report) {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>(), y = b.get<double>();
    if (!close(x, y, scale)) report.difference(where, show(x) + " -> " + show(y));
    return;
  }
  if (a.type() != b.type()) {
    report.difference(where, a.dump() + " -> " + b.dump());
    return;
  }
  if (a.is_object()) {
    for (const auto& [key, value] : a.items()) {
      if (is_timing_key(key)) continue;
      if (!b.contains(key)) {
        report.difference(where + "." + key, "missing");
        continue;
      }
      compare_json(value, b.at(key), where + "." + key, 0.0, report);
    }
    for (const auto& [key, value] : b.items())
      if (!a.contains(key) && !is_timing_key(key)) report.difference(where + "." + key, "new key");
    return;
  }
  if (a.is_array()) {
    if (a.size() != b.size()) {
      report.difference(where, "length " + std::to_string(a.size()) + " -> " + std::to_string(b.size()));
      return;
    }
    const double s = std::max({scale, json_scale(a), json_scale(b)});
    for (std::size_t i = 0; i < a.size(); ++i)
      compare_json(a[i], b[i], where + "[" + std::to_string(i) + "]", s, report);
    return;
  }
  if (a != b) report.difference(where, a.dump() + " -> " + b.dump());
}

void compare_digests(const Json& a, const Json& b, const std::string& file, Report& report) {
  for (const auto& [column, da] : a.items()) {
    const std::string where = file + " column " + column;
    if (!b.contains(column)) {
      report.difference(where, "missing");
      continue;
    }
    const Json& db = b.at(column);
    // Sums of n values differ by up to n rounding steps of their magnitudes when the order of
    // the reductions that produced the values changes.
    const double n = da.at("rows").get<double>();
    const double abs_sum = da.value("abs_sum", 0.0);
    for (const auto& [stat, va] : da.items()) {
      if (!db.contains(stat)) {
        report.difference(where, stat + " missing");
        continue;
      }
      const Json& vb = db.at(stat);
      if (va.is_number_float() && vb.is_number()) {
        const bool summed = stat == "sum" || stat == "weighted_sum" || stat == "abs_sum";
        const double x = va.get<double>(), y = vb.get<double>();
        const double tolerance = summed ? 1e-12 * (n + 1.0) * abs_sum : 0.0;
        if (summed ? std::abs(x - y) > tolerance : !close(x, y, std::abs(x)))
          report.difference(where, stat + " " + show(x) + " -> " + show(y));
      } else if (va != vb) {
        report.difference(where, stat + " " + va.dump() + " -> " + vb.dump());
      }
    }
  }
}

int snapshot(const fs::path& out_dir, const fs::path& ref_dir) {
  fs::create_directories(ref_dir);
  Json digests = Json::object();
  for (const auto& relative : result_files(out_dir)) {
    const fs::path source = out_dir / relative;
    if (relative.extension() == ".csv" && fs::file_size(source) > whole_file_limit_bytes) {
      digests[relative.generic_string()] = table_digest(read_csv(source));
      continue;
    }
    fs::create_directories((ref_dir / relative).parent_path());
    std::ofstream(ref_dir / relative, std::ios::binary) << portable(read_text(source));
  }
  std::ofstream(ref_dir / digest_file) << digests.dump(1) << '\n';
  return 0;
}

int compare(const fs::path& ref_dir, const fs::path& out_dir) {
  Report report;
  Json digests = Json::parse(read_text(ref_dir / digest_file));
  std::vector<std::string> expected;
  for (const auto& relative : result_files(ref_dir)) expected.push_back(relative.generic_string());
  for (const auto& [file, digest] : digests.items()) expected.push_back(file);
  std::sort(expected.begin(), expected.end());

  std::vector<std::string> produced;
  for (const auto& relative : result_files(out_dir)) produced.push_back(relative.generic_string());
  for (const auto& file : produced)
    if (!std::binary_search(expected.begin(), expected.end(), file))
      report.difference(file, "new result file (not in the references)");

  for (const auto& file : expected) {
    const fs::path out_file = out_dir / file;
    if (!fs::exists(out_file)) {
      report.difference(file, "missing");
      continue;
    }
    if (digests.contains(file)) {
      compare_digests(digests.at(file), table_digest(read_csv(out_file)), file, report);
    } else if (fs::path(file).extension() == ".csv") {
      compare_tables(read_csv(ref_dir / file), read_csv(out_file), file, report);
    } else {
      Json written = Json::parse(read_text(out_file));
      make_portable(written);
      compare_json(Json::parse(read_text(ref_dir / file)), written, file, 0.0, report);
    }
  }
  if (report.count() > 40) std::cout << "... " << report.count() - 40 << " more differences\n";
  return report.count() == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string usage =
      "usage: compare_study_outputs snapshot OUT_DIR REF_DIR SOURCE_DIR | compare REF_DIR OUT_DIR SOURCE_DIR\n";
  if (argc != 5) {
    std::cerr << usage;
    return 2;
  }
  try {
    const std::string mode = argv[1];
    source_dir = fs::weakly_canonical(argv[4]).string();
    if (mode == "snapshot") return snapshot(argv[2], argv[3]);
    if (mode == "compare") return compare(argv[2], argv[3]);
    std::cerr << usage;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "compare_study_outputs: " << e.what() << '\n';
    return 2;
  }
}
