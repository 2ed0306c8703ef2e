// The claims a shipped study states in its header hold in its outputs (tests/regression/README.md).
//
//   check_study_claims STUDIES_DIR OUT_DIR
//
// Every studies/<name>.toml states what it shows in machine-readable comment lines beside its prose:
//
//   # claim: FILE LHS [OP RHS [TOLERANCE]]   -- why (optional prose)
//
// evaluated against OUT_DIR/<name>/FILE (a path inside the study's output directory). Operands:
//   - a number, "a string", true or false;
//   - in a .json file, a JSON pointer: /peaks/0/frequency_hz;
//   - in a .csv file, a column reduced over its rows: max(c) min(c) mean(c) sd(c) (population
//     standard deviation) sum(c) count(c) all(c) any(c) (all/any: cells true/false or 1/0), or a
//     bare column c, which must hold
//     exactly one row; rows are selected by c[key=value], c[key<value], c[key>value], joined by &
//     (values compared as numbers when both are numbers, else as text): max(x[k=2e4&mode=a]);
//   - an operand may name another file of the outputs: points/000001/timeseries.csv:sd(x).
// OP is one of > >= < <= == != or ~ (approximately: RHS then TOLERANCE, relative "2%" or an
// absolute number); without OP the left side must be true. A study without a claim, a claim
// that cannot be evaluated (file, column or key missing) and a claim that is false each fail,
// with the study, its line, the claim's text and the values found. Exit 0 when every claim of
// every study holds, 1 otherwise, 2 on usage errors.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "study_files.hpp"

namespace fs = std::filesystem;
using study_files::parse_number;
using study_files::Table;

namespace {

using Value = std::variant<double, bool, std::string>;

struct Claim {
  int line = 0;
  std::string text;  // as written after "claim:", prose included
  std::string file;
  std::string lhs, op, rhs, tolerance;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::string show(const Value& v) {
  if (const double* d = std::get_if<double>(&v)) {
    std::ostringstream s;
    s.precision(6);
    s << *d;
    return s.str();
  }
  if (const bool* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  return '"' + std::get<std::string>(v) + '"';
}

// Whitespace-separated tokens; "..." is one token (quotes kept).
std::vector<std::string> tokens(const std::string& s) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < s.size()) {
    if (std::isspace(static_cast<unsigned char>(s[i]))) {
      ++i;
      continue;
    }
    std::size_t j = i;
    if (s[i] == '"') {
      j = s.find('"', i + 1);
      if (j == std::string::npos) throw std::runtime_error("unterminated string");
      ++j;
    } else {
      while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
    }
    out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

bool is_operator(const std::string& t) {
  return t == ">" || t == ">=" || t == "<" || t == "<=" || t == "==" || t == "!=" || t == "~";
}

Claim parse_claim(int line, const std::string& body) {
  Claim c;
  c.line = line;
  c.text = trim(body);
  const auto prose = body.find(" -- ");
  const auto t = tokens(prose == std::string::npos ? body : body.substr(0, prose));
  if (t.size() < 2) throw std::runtime_error("needs FILE and an expression");
  c.file = t[0];
  c.lhs = t[1];
  if (t.size() == 2) return c;
  if (!is_operator(t[2]) || t.size() < 4)
    throw std::runtime_error("expected an operator (> >= < <= == != ~) and a right side after " + c.lhs);
  c.op = t[2];
  c.rhs = t[3];
  if (c.op == "~") {
    if (t.size() != 5) throw std::runtime_error("~ needs a tolerance (e.g. 2% or 0.5)");
    c.tolerance = t[4];
  } else if (t.size() != 4) {
    throw std::runtime_error("unexpected text after " + c.rhs);
  }
  return c;
}

// A study's claims: its "# claim:" comment lines.
std::vector<std::pair<int, std::string>> claim_lines(const fs::path& study) {
  std::istringstream in(study_files::read_text(study));
  std::vector<std::pair<int, std::string>> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const std::string t = trim(line);
    const std::string tag = "# claim:";
    if (t.rfind(tag, 0) == 0) out.emplace_back(n, t.substr(tag.size()));
  }
  return out;
}

std::optional<bool> as_bool(const std::string& cell) {
  if (cell == "true" || cell == "1") return true;
  if (cell == "false" || cell == "0") return false;
  return std::nullopt;
}

Value cell_value(const std::string& cell) {
  double d = 0.0;
  if (parse_number(cell, d)) return d;
  if (cell == "true") return true;
  if (cell == "false") return false;
  return cell;
}

// The output files of one study, read once each.
class Outputs {
 public:
  explicit Outputs(fs::path dir) : dir_(std::move(dir)) {}

  const Table& table(const std::string& file) {
    for (auto& [name, t] : tables_)
      if (name == file) return t;
    require(file);
    tables_.emplace_back(file, study_files::read_csv(dir_ / file));
    return tables_.back().second;
  }
  const nlohmann::json& json(const std::string& file) {
    for (auto& [name, j] : jsons_)
      if (name == file) return j;
    require(file);
    jsons_.emplace_back(file, nlohmann::json::parse(study_files::read_text(dir_ / file)));
    return jsons_.back().second;
  }

 private:
  void require(const std::string& file) const {
    if (!fs::exists(dir_ / file)) throw std::runtime_error("no file " + (dir_ / file).string());
  }
  fs::path dir_;
  std::vector<std::pair<std::string, Table>> tables_;
  std::vector<std::pair<std::string, nlohmann::json>> jsons_;
};

// Rows of `table` that pass "key=value&key<value..."; `where` names the operand for messages.
std::vector<std::size_t> select_rows(const Table& table, const std::string& filter, const std::string& where) {
  std::vector<std::size_t> rows(table.rows());
  for (std::size_t r = 0; r < rows.size(); ++r) rows[r] = r;
  std::size_t start = 0;
  while (!filter.empty() && start <= filter.size()) {
    const auto end = std::min(filter.find('&', start), filter.size());
    const std::string cond = filter.substr(start, end - start);
    const auto at = cond.find_first_of("=<>");
    if (at == std::string::npos || at == 0) throw std::runtime_error("bad row filter '" + cond + "' in " + where);
    const std::string key = cond.substr(0, at), value = cond.substr(at + 1);
    const char op = cond[at];
    const int c = table.column(key);
    if (c < 0) throw std::runtime_error("no column '" + key + "' (filter of " + where + ")");
    double want = 0.0;
    const bool numeric = parse_number(value, want);
    std::vector<std::size_t> kept;
    for (std::size_t r : rows) {
      const std::string& cell = table.columns[c][r];
      double have = 0.0;
      bool pass = false;
      if (numeric && parse_number(cell, have)) {
        pass = op == '=' ? std::abs(have - want) <= 1e-9 * std::max(std::abs(want), 1e-300)
               : op == '<' ? have < want
                           : have > want;
      } else {
        pass = op == '=' && cell == value;
      }
      if (pass) kept.push_back(r);
    }
    rows = std::move(kept);
    start = end + 1;
  }
  return rows;
}

Value csv_operand(const Table& table, const std::string& expr) {
  std::string agg, ref = expr;
  const auto open = expr.find('(');
  if (open != std::string::npos) {
    if (expr.back() != ')') throw std::runtime_error("unbalanced parentheses in " + expr);
    agg = expr.substr(0, open);
    ref = expr.substr(open + 1, expr.size() - open - 2);
  }
  std::string name = ref, filter;
  const auto bracket = ref.find('[');
  if (bracket != std::string::npos) {
    if (ref.back() != ']') throw std::runtime_error("unbalanced brackets in " + expr);
    name = ref.substr(0, bracket);
    filter = ref.substr(bracket + 1, ref.size() - bracket - 2);
  }
  const int c = table.column(name);
  if (c < 0) throw std::runtime_error("no column '" + name + "'");
  const auto rows = select_rows(table, filter, expr);
  if (agg == "count") return static_cast<double>(rows.size());
  if (rows.empty()) throw std::runtime_error(expr + " selects no row");
  const auto& cells = table.columns[c];
  if (agg.empty()) {
    if (rows.size() != 1)
      throw std::runtime_error(expr + " selects " + std::to_string(rows.size()) +
                               " rows (reduce them with max, min, mean, all ...)");
    return cell_value(cells[rows[0]]);
  }
  if (agg == "all" || agg == "any") {
    for (std::size_t r : rows) {
      const auto b = as_bool(cells[r]);
      if (!b) throw std::runtime_error(name + " holds '" + cells[r] + "', not true/false");
      if (agg == "all" && !*b) return false;
      if (agg == "any" && *b) return true;
    }
    return agg == "all";
  }
  std::vector<double> values;
  for (std::size_t r : rows) {
    double v = 0.0;
    if (!parse_number(cells[r], v))
      throw std::runtime_error(name + " holds '" + cells[r] + "', not a number");
    values.push_back(v);
  }
  double sum = 0.0;
  for (double v : values) sum += v;
  if (agg == "max") return *std::max_element(values.begin(), values.end());
  if (agg == "min") return *std::min_element(values.begin(), values.end());
  if (agg == "sum") return sum;
  const double mean = sum / static_cast<double>(values.size());
  if (agg == "mean") return mean;
  if (agg == "sd") {  // population standard deviation: the size of a fluctuation
    double sq = 0.0;
    for (double v : values) sq += (v - mean) * (v - mean);
    return std::sqrt(sq / static_cast<double>(values.size()));
  }
  throw std::runtime_error("unknown reduction '" + agg + "' (max min mean sd sum count all any)");
}

Value json_operand(const nlohmann::json& doc, const std::string& pointer) {
  const nlohmann::json::json_pointer p(pointer);
  if (!doc.contains(p)) throw std::runtime_error("no " + pointer);
  const auto& v = doc.at(p);
  if (v.is_boolean()) return v.get<bool>();
  if (v.is_number()) return v.get<double>();
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return std::string("null");
  throw std::runtime_error(pointer + " is " + std::string(v.type_name()) + ", not a value");
}

Value operand(Outputs& out, std::string file, std::string token) {
  // "other.csv:expr" reads another file of the study's outputs.
  for (const char* ext : {".csv:", ".json:"}) {
    const auto at = token.find(ext);
    if (at != std::string::npos && token.front() != '"') {
      const auto colon = at + std::string_view(ext).size() - 1;
      file = token.substr(0, colon);
      token = token.substr(colon + 1);
      break;
    }
  }
  double d = 0.0;
  if (parse_number(token, d)) return d;
  if (token == "true") return true;
  if (token == "false") return false;
  if (token.size() >= 2 && token.front() == '"' && token.back() == '"') return token.substr(1, token.size() - 2);
  const std::string ext = fs::path(file).extension().string();
  if (ext == ".json") {
    if (token.front() != '/') throw std::runtime_error("a .json operand is a JSON pointer (/key/0/...): " + token);
    return json_operand(out.json(file), token);
  }
  if (ext == ".csv") return csv_operand(out.table(file), token);
  throw std::runtime_error("claims read .csv and .json files, not " + file);
}

bool holds(const Claim& c, const Value& lhs, const Value& rhs) {
  if (c.op.empty()) {
    if (!std::holds_alternative<bool>(lhs)) throw std::runtime_error(c.lhs + " is not true/false: give an operator");
    return std::get<bool>(lhs);
  }
  const double* a = std::get_if<double>(&lhs);
  const double* b = std::get_if<double>(&rhs);
  if (a && b) {
    if (c.op == ">") return *a > *b;
    if (c.op == ">=") return *a >= *b;
    if (c.op == "<") return *a < *b;
    if (c.op == "<=") return *a <= *b;
    if (c.op == "==") return *a == *b;
    if (c.op == "!=") return *a != *b;
    double tol = 0.0;
    if (!c.tolerance.empty() && c.tolerance.back() == '%' &&
        parse_number(c.tolerance.substr(0, c.tolerance.size() - 1), tol))
      return std::abs(*a - *b) <= tol / 100.0 * std::abs(*b);
    if (parse_number(c.tolerance, tol)) return std::abs(*a - *b) <= tol;
    throw std::runtime_error("tolerance '" + c.tolerance + "' is neither N% nor a number");
  }
  if (lhs.index() != rhs.index())
    throw std::runtime_error("compares " + show(lhs) + " with " + show(rhs) + " (different types)");
  if (c.op == "==") return lhs == rhs;
  if (c.op == "!=") return lhs != rhs;
  throw std::runtime_error(c.op + " compares numbers only");
}

// Checks one study; prints a FAIL line per failed claim; returns {claims, failures}.
std::pair<int, int> check_study(const fs::path& study, const fs::path& out_dir) {
  const std::string where = study.filename().string();
  const auto lines = claim_lines(study);
  if (lines.empty()) {
    std::cout << "FAIL: " << where << ": states no claim (add '# claim:' lines to its header; "
              << "tests/regression/README.md)\n";
    return {0, 1};
  }
  Outputs outputs(out_dir);
  int failures = 0;
  for (const auto& [line, body] : lines) {
    const std::string at = "FAIL: " + where + ":" + std::to_string(line) + ": claim '" + trim(body) + "': ";
    try {
      const Claim c = parse_claim(line, body);
      const Value lhs = operand(outputs, c.file, c.lhs);
      const Value rhs = c.op.empty() ? Value(true) : operand(outputs, c.file, c.rhs);
      if (!holds(c, lhs, rhs)) {
        std::cout << at << "found " << c.lhs << " = " << show(lhs);
        if (!c.op.empty() && c.rhs != show(rhs)) std::cout << ", " << c.rhs << " = " << show(rhs);
        std::cout << '\n';
        ++failures;
      }
    } catch (const std::exception& e) {
      std::cout << at << "cannot evaluate: " << e.what() << '\n';
      ++failures;
    }
  }
  return {static_cast<int>(lines.size()), failures};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: check_study_claims STUDIES_DIR OUT_DIR\n";
    return 2;
  }
  const fs::path studies = argv[1], out = argv[2];
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(studies))
    if (entry.path().extension() == ".toml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  int claims = 0, failures = 0;
  for (const auto& study : files) {
    const auto [n, failed] = check_study(study, out / study.stem());
    claims += n;
    failures += failed;
  }
  if (failures > 0) {
    std::cout << failures << " claims fail or are missing\n";
    return 1;
  }
  std::cout << "all " << claims << " claims of " << files.size() << " studies hold\n";
  return 0;
}
