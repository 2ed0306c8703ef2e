// Measured FRFs from CSV (chatterlab/frf.hpp): one header row naming each column with its unit in
// brackets, e.g.
//
//   # G8 grinder, wheel-work contact, x direction
//   frequency [Hz], real [m/N], imag [m/N], coherence [1]
//   20.0, 3.1e-8, -1.2e-10, 0.98
//
// Values are the real and imaginary parts or the magnitude and phase of a receptance, mobility or
// accelerance; the unit of the value columns says which. docs/analysis/frf.md is the user's page.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <numbers>
#include <optional>

#include "chatterlab/errors.hpp"
#include "chatterlab/frf.hpp"
#include "frf/frf_units.hpp"

namespace chatterlab {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}

std::optional<double> parse_number(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = trim(s.substr(1, s.size() - 2));
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double value = 0.0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

std::vector<std::string_view> split(std::string_view line, char separator) {
  std::vector<std::string_view> cells;
  for (std::size_t start = 0;;) {
    const std::size_t end = line.find(separator, start);
    cells.push_back(trim(line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start)));
    if (end == std::string_view::npos) return cells;
    start = end + 1;
  }
}

enum class Role { frequency, real, imag, magnitude, phase, coherence };

struct Column {
  Role role;
  std::string name;  // as written
  std::string unit;  // as written (inside the brackets)
};

// "real [m/N]" -> name "real", unit "m/N" (also "real (m/N)").
std::pair<std::string, std::string> name_and_unit(std::string_view cell) {
  cell = trim(cell);
  if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') cell = trim(cell.substr(1, cell.size() - 2));
  for (auto [open, close] : {std::pair{'[', ']'}, std::pair{'(', ')'}}) {
    const std::size_t at = cell.find(open);
    if (at != std::string_view::npos && cell.back() == close)
      return {std::string(trim(cell.substr(0, at))), std::string(trim(cell.substr(at + 1, cell.size() - at - 2)))};
  }
  return {std::string(cell), ""};
}

constexpr const char* recognised_columns =
    "frequency [Hz|kHz|rad/s]; real and imag, or magnitude and phase [deg|rad], in a receptance "
    "(m/N, mm/N, um/N, nm/N), mobility ((m/s)/N, (mm/s)/N) or accelerance ((m/s^2)/N, g/N) unit; "
    "optional coherence [1]";

std::optional<Role> role_of(const std::string& name) {
  const std::string n = lower(name);
  for (const char* f : {"frequency", "freq", "f"}) if (n == f) return Role::frequency;
  for (const char* r : {"real", "re", "real part"}) if (n == r) return Role::real;
  for (const char* i : {"imag", "imaginary", "im", "imaginary part"}) if (n == i) return Role::imag;
  for (const char* m : {"magnitude", "mag", "abs", "amplitude"}) if (n == m) return Role::magnitude;
  for (const char* p : {"phase", "arg", "angle"}) if (n == p) return Role::phase;
  if (n == "coherence") return Role::coherence;
  return std::nullopt;
}

struct Header {
  std::vector<Column> columns;
  char separator = ',';
  FrfUnit value_unit;
  double frequency_to_hz = 1.0;
  double phase_to_rad = 1.0;
  bool polar = false;
  std::size_t index[6] = {};  // column of each Role
  bool has[6] = {};
};

Header parse_header(std::string_view line, const std::string& where) {
  Header h;
  h.separator = line.find(',') != std::string_view::npos ? ','
                : line.find(';') != std::string_view::npos ? ';'
                                                            : '\t';
  for (std::string_view cell : split(line, h.separator)) {
    auto [name, unit] = name_and_unit(cell);
    const std::optional<Role> role = role_of(name);
    if (!role)
      throw InputError(fmt::format("{}: column '{}' is not an FRF column (recognised: {})", where, name,
                                   recognised_columns));
    const auto r = static_cast<std::size_t>(*role);
    if (h.has[r]) throw InputError(fmt::format("{}: two '{}' columns", where, name));
    h.has[r] = true;
    h.index[r] = h.columns.size();
    h.columns.push_back({*role, name, unit});
  }
  auto column = [&](Role r) -> const Column& { return h.columns[h.index[static_cast<std::size_t>(r)]]; };
  auto present = [&](Role r) { return h.has[static_cast<std::size_t>(r)]; };
  if (!present(Role::frequency))
    throw InputError(fmt::format("{}: no frequency column (write e.g. 'frequency [Hz]'; recognised: {})", where,
                                 recognised_columns));
  const std::optional<double> to_hz = frequency_unit_to_hz(column(Role::frequency).unit);
  if (!to_hz)
    throw InputError(fmt::format("{}: column '{}': unit '{}' is not a frequency unit (Hz, kHz, rad/s)", where,
                                 column(Role::frequency).name, column(Role::frequency).unit));
  h.frequency_to_hz = *to_hz;
  const bool cartesian = present(Role::real) || present(Role::imag);
  h.polar = present(Role::magnitude) || present(Role::phase);
  if (cartesian == h.polar || (cartesian && !(present(Role::real) && present(Role::imag))) ||
      (h.polar && !(present(Role::magnitude) && present(Role::phase))))
    throw InputError(fmt::format("{}: the values need either a real and an imag column or a magnitude and a "
                                 "phase column, not {}",
                                 where, fmt::join([&] {
                                   std::vector<std::string> names;
                                   for (const Column& c : h.columns) names.push_back(c.name);
                                   return names;
                                 }(), ", ")));
  std::vector<Role> value_roles = h.polar ? std::vector<Role>{Role::magnitude} : std::vector<Role>{Role::real, Role::imag};
  for (Role r : value_roles) {
    const Column& c = column(r);
    const std::optional<FrfUnit> unit = parse_frf_unit(c.unit);
    if (!unit)
      throw InputError(fmt::format("{}: column '{}': unit '{}' is not a receptance, mobility or accelerance unit "
                                   "(m/N, mm/N, um/N, nm/N, (m/s)/N, (mm/s)/N, (m/s^2)/N, g/N)",
                                   where, c.name, c.unit));
    if (r == Role::imag && (unit->quantity != h.value_unit.quantity || unit->to_si != h.value_unit.to_si))
      throw InputError(fmt::format("{}: columns '{}' and '{}' have different units ('{}' and '{}')", where,
                                   column(Role::real).name, c.name, column(Role::real).unit, c.unit));
    h.value_unit = *unit;
  }
  if (h.polar) {
    const std::string u = lower(column(Role::phase).unit);
    if (u == "deg" || u == "degree" || u == "degrees" || u == "°")
      h.phase_to_rad = std::numbers::pi / 180.0;
    else if (u == "rad" || u == "radian" || u == "radians")
      h.phase_to_rad = 1.0;
    else
      throw InputError(fmt::format("{}: column '{}': unit '{}' is not a phase unit (deg, rad)", where,
                                   column(Role::phase).name, column(Role::phase).unit));
  }
  if (present(Role::coherence)) {
    const std::string u = lower(column(Role::coherence).unit);
    if (!(u.empty() || u == "1" || u == "-"))
      throw InputError(fmt::format("{}: column '{}': coherence is dimensionless (unit [1]), not '{}'", where,
                                   column(Role::coherence).name, column(Role::coherence).unit));
  }
  return h;
}

}  // namespace

MeasuredFrf parse_frf_csv(std::string_view text, const std::string& file) {
  MeasuredFrf frf;
  frf.source = file;
  std::optional<Header> header;
  double previous_hz = -1.0;
  int line_number = 0;
  int previous_line = 0;
  for (std::size_t start = 0; start < text.size();) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line_number == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 BOM
    line = trim(line);
    if (line.empty()) continue;
    if (line.front() == '#') {
      if (frf.description.empty() && !header) frf.description = std::string(trim(line.substr(1)));
      continue;
    }
    const std::string where = fmt::format("{}:{}", file, line_number);
    if (!header) {
      header = parse_header(line, where);
      continue;
    }
    const std::vector<std::string_view> cells = split(line, header->separator);
    if (cells.size() != header->columns.size())
      throw InputError(fmt::format("{}: {} fields, but the header names {} columns", where, cells.size(),
                                   header->columns.size()));
    double values[6] = {};
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::optional<double> v = parse_number(cells[c]);
      if (!v || !std::isfinite(*v))
        throw InputError(fmt::format("{}: column '{}' = '{}': expected a finite number", where,
                                     header->columns[c].name, cells[c]));
      values[static_cast<std::size_t>(header->columns[c].role)] = *v;
    }
    const double hz = values[static_cast<std::size_t>(Role::frequency)] * header->frequency_to_hz;
    if (hz < 0.0)
      throw InputError(fmt::format("{}: frequency {} Hz is negative", where, hz));
    if (hz <= previous_hz)
      throw InputError(fmt::format("{}: frequency {} Hz is not above the previous line's {} Hz (line {}): "
                                   "lines must be in increasing frequency",
                                   where, hz, previous_hz, previous_line));
    previous_hz = hz;
    previous_line = line_number;
    // A 0 Hz line carries no dynamics (a hammer excites no static load) and cannot be converted
    // from mobility or accelerance: it is skipped.
    if (hz == 0.0) continue;
    Complex value;
    if (header->polar) {
      const double magnitude = values[static_cast<std::size_t>(Role::magnitude)];
      if (magnitude < 0.0)
        throw InputError(fmt::format("{}: magnitude {} is negative", where, magnitude));
      value = std::polar(magnitude, values[static_cast<std::size_t>(Role::phase)] * header->phase_to_rad);
    } else {
      value = {values[static_cast<std::size_t>(Role::real)], values[static_cast<std::size_t>(Role::imag)]};
    }
    frf.frequency_hz.push_back(hz);
    frf.receptance_m_per_n.push_back(to_receptance(value * header->value_unit.to_si, header->value_unit.quantity, hz));
    if (header->has[static_cast<std::size_t>(Role::coherence)]) {
      const double coherence = values[static_cast<std::size_t>(Role::coherence)];
      if (coherence < 0.0 || coherence > 1.0)
        throw InputError(fmt::format("{}: coherence {} is outside [0, 1]", where, coherence));
      frf.coherence.push_back(coherence);
    }
  }
  if (!header) throw InputError(fmt::format("{}: no header row (e.g. 'frequency [Hz], real [m/N], imag [m/N]')", file));
  frf.measured_as = header->value_unit.quantity;
  check_frf_lines(frf, file);
  return frf;
}

}  // namespace chatterlab
