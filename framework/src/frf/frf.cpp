// Measured FRFs: units, conversions, reading a file whatever its format, and the interpolant the
// imaginary-axis criterion uses between measured lines (chatterlab/frf.hpp).
#include "chatterlab/frf.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "chatterlab/errors.hpp"
#include "frf/frf_units.hpp"

namespace chatterlab {

namespace fs = std::filesystem;

std::string_view to_string(FrfQuantity quantity) {
  switch (quantity) {
    case FrfQuantity::receptance: return "receptance";
    case FrfQuantity::mobility: return "mobility";
    case FrfQuantity::accelerance: return "accelerance";
  }
  return "?";
}

namespace {

// Lower case, blanks, '*', '.' and '(' ')' removed, micro signs as 'u', superscript two as '2',
// "^2" as "2": "(m/s^2)/N" -> "m/s2/n", "µm/N" -> "um/n", "m/(N s)" -> "m/ns".
std::string normalised_unit(std::string_view unit) {
  std::string out;
  for (std::size_t i = 0; i < unit.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(unit[i]);
    if (c == 0xC2 && i + 1 < unit.size() && static_cast<unsigned char>(unit[i + 1]) == 0xB5) {  // µ (U+00B5)
      out += 'u';
      ++i;
    } else if (c == 0xCE && i + 1 < unit.size() && static_cast<unsigned char>(unit[i + 1]) == 0xBC) {  // μ (U+03BC)
      out += 'u';
      ++i;
    } else if (c == 0xC2 && i + 1 < unit.size() && static_cast<unsigned char>(unit[i + 1]) == 0xB2) {  // ²
      out += '2';
      ++i;
    } else if (std::isspace(c) || c == '*' || c == '.' || c == '(' || c == ')' || c == '^') {
      continue;
    } else {
      out += static_cast<char>(std::tolower(c));
    }
  }
  return out;
}

}  // namespace

std::optional<FrfUnit> parse_frf_unit(std::string_view unit) {
  const std::string u = normalised_unit(unit);
  if (u == "g/n") return FrfUnit{FrfQuantity::accelerance, 9.80665};
  const std::pair<const char*, double> lengths[] = {{"m", 1.0}, {"mm", 1e-3}, {"um", 1e-6}, {"nm", 1e-9}};
  for (const auto& [length, factor] : lengths) {
    const std::string l = length;
    if (u == l + "/n") return FrfUnit{FrfQuantity::receptance, factor};
    for (const std::string& form : {l + "/s/n", l + "/n/s", l + "/ns", l + "/sn"})
      if (u == form) return FrfUnit{FrfQuantity::mobility, factor};
    for (const std::string& form : {l + "/s2/n", l + "/n/s2", l + "/ns2", l + "/s2n"})
      if (u == form) return FrfUnit{FrfQuantity::accelerance, factor};
  }
  return std::nullopt;
}

std::optional<double> frequency_unit_to_hz(std::string_view unit) {
  const std::string u = normalised_unit(unit);
  if (u == "hz") return 1.0;
  if (u == "khz") return 1e3;
  if (u == "rad/s") return 1.0 / (2.0 * std::numbers::pi);
  return std::nullopt;
}

Complex to_receptance(Complex value_si, FrfQuantity quantity, double frequency_hz) {
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  switch (quantity) {
    case FrfQuantity::receptance: return value_si;
    case FrfQuantity::mobility: return value_si / Complex(0.0, w);  // Y = j w H
    case FrfQuantity::accelerance: return -value_si / (w * w);      // A = -w^2 H
  }
  return value_si;
}

Complex from_receptance(Complex receptance_m_per_n, FrfQuantity quantity, double frequency_hz) {
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  switch (quantity) {
    case FrfQuantity::receptance: return receptance_m_per_n;
    case FrfQuantity::mobility: return receptance_m_per_n * Complex(0.0, w);
    case FrfQuantity::accelerance: return -receptance_m_per_n * (w * w);
  }
  return receptance_m_per_n;
}

void check_frf_lines(const MeasuredFrf& frf, const std::string& file) {
  constexpr std::size_t min_lines = 4;
  if (frf.frequency_hz.size() < min_lines)
    throw InputError(fmt::format("{}: {} frequency lines above 0 Hz; an FRF needs at least {}", file,
                                 frf.frequency_hz.size(), min_lines));
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i)
    if (!std::isfinite(frf.receptance_m_per_n[i].real()) || !std::isfinite(frf.receptance_m_per_n[i].imag()))
      throw InputError(fmt::format("{}: the value at {} Hz is not finite after conversion to receptance", file,
                                   frf.frequency_hz[i]));
}

// ---------------------------------------------------------------- reading a file

namespace {

std::string read_bytes(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(fmt::format("{}: no such file", file.string()));
  if (fs::is_directory(file, ec))
    throw InputError(fmt::format("{}: is a directory, not an FRF file", file.string()));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot be opened for reading", file.string()));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return std::move(buffer).str();
}

// A UFF file starts with a "-1" delimiter line (after optional blank lines).
bool looks_like_uff(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && (bytes[i] == ' ' || bytes[i] == '\n' || bytes[i] == '\r' || bytes[i] == '\t')) ++i;
  return bytes.substr(i, 2) == "-1";
}

std::string describe(const MeasuredFrf& frf) {
  return fmt::format("{} ({} lines, {:g}-{:g} Hz{})", frf.source, frf.frequency_hz.size(), frf.frequency_hz.front(),
                     frf.frequency_hz.back(), frf.description.empty() ? "" : ", \"" + frf.description + "\"");
}

}  // namespace

std::vector<MeasuredFrf> read_frfs(const fs::path& file) {
  const std::string bytes = read_bytes(file);
  const std::string name = file.string();
  if (looks_like_uff(bytes)) return parse_uff58(bytes, name);
  return {parse_frf_csv(bytes, name)};
}

MeasuredFrf read_frf(const fs::path& file, int dataset) {
  std::vector<MeasuredFrf> frfs = read_frfs(file);
  if (dataset == 0) {
    if (frfs.size() == 1) return std::move(frfs.front());
    std::string list;
    for (std::size_t i = 0; i < frfs.size(); ++i) list += fmt::format("\n  {}: {}", i + 1, describe(frfs[i]));
    throw InputError(fmt::format("{}: holds {} FRFs; choose one by its number (frf_dataset):{}", file.string(),
                                 frfs.size(), list));
  }
  if (dataset < 1 || static_cast<std::size_t>(dataset) > frfs.size())
    throw InputError(fmt::format("{}: FRF number {} does not exist: the file holds {} FRF{}", file.string(), dataset,
                                 frfs.size(), frfs.size() == 1 ? "" : "s"));
  return std::move(frfs[static_cast<std::size_t>(dataset - 1)]);
}

// ---------------------------------------------------------------- interpolant

FrfInterpolant::FrfInterpolant(const MeasuredFrf& frf)
    : f_(frf.frequency_hz), h_(frf.receptance_m_per_n), slope_(frf.frequency_hz.size()) {
  // Natural cubic spline: second derivatives M_i from the tridiagonal system (Thomas algorithm),
  // M_0 = M_{n-1} = 0; stored as slope_ = M (complex).
  const std::size_t n = f_.size();
  if (n < 2) throw std::invalid_argument("FrfInterpolant: fewer than two lines");
  std::vector<double> diagonal(n, 1.0), upper(n, 0.0);
  std::vector<Complex> rhs(n, 0.0);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double a = f_[i] - f_[i - 1], b = f_[i + 1] - f_[i];
    const double lower = a / 6.0;
    diagonal[i] = (a + b) / 3.0;
    upper[i] = b / 6.0;
    rhs[i] = (h_[i + 1] - h_[i]) / b - (h_[i] - h_[i - 1]) / a;
    // eliminate the sub-diagonal
    const double m = lower / diagonal[i - 1];
    diagonal[i] -= m * upper[i - 1];
    rhs[i] -= m * rhs[i - 1];
  }
  slope_[n - 1] = 0.0;
  for (std::size_t i = n - 1; i-- > 1;) slope_[i] = (rhs[i] - upper[i] * slope_[i + 1]) / diagonal[i];
  slope_[0] = 0.0;
}

std::optional<FrfInterpolant::Value> FrfInterpolant::at(double frequency_hz) const {
  if (!(frequency_hz >= f_.front() && frequency_hz <= f_.back())) return std::nullopt;
  std::size_t i = static_cast<std::size_t>(std::upper_bound(f_.begin(), f_.end(), frequency_hz) - f_.begin());
  i = std::clamp<std::size_t>(i, 1, f_.size() - 1) - 1;  // interval [f_i, f_{i+1}]
  const double h = f_[i + 1] - f_[i];
  const double a = (f_[i + 1] - frequency_hz) / h, b = (frequency_hz - f_[i]) / h;
  const Complex& m0 = slope_[i];
  const Complex& m1 = slope_[i + 1];
  Value v;
  v.receptance_m_per_n =
      a * h_[i] + b * h_[i + 1] + ((a * a * a - a) * m0 + (b * b * b - b) * m1) * (h * h / 6.0);
  v.derivative_m_per_n_hz = (h_[i + 1] - h_[i]) / h + ((1.0 - 3.0 * a * a) * m0 + (3.0 * b * b - 1.0) * m1) * (h / 6.0);
  return v;
}

}  // namespace chatterlab
