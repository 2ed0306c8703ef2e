// Universal File Format dataset 58 ("function at nodal DOF"), ASCII and binary (58b), and the
// units dataset 164 (chatterlab/frf.hpp). A UFF file is a sequence of datasets, each between two
// lines holding "-1" in columns 1-6; the line after the opening delimiter holds the dataset number
// (I6), followed for a binary dataset by 'b' and its layout: byte order (1 little, 2 big endian),
// floating-point format (2 = IEEE 754), number of ASCII lines, number of bytes. Dataset 58 then has
// 11 ASCII records (five ID lines; DOF identification; data form; abscissa, ordinate numerator,
// ordinate denominator and z-axis characteristics) and its values, as fixed-width Fortran fields
// (ASCII) or raw IEEE numbers (binary). Datasets other than 58 and 164 are skipped.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>

#include "chatterlab/errors.hpp"
#include "chatterlab/frf.hpp"
#include "frf/frf_units.hpp"

namespace chatterlab {

namespace {

// Position in the file, for messages: the physical line (1-based) of a byte offset.
class Cursor {
 public:
  Cursor(std::string_view bytes, const std::string& file) : bytes_(bytes), file_(file) {}

  bool at_end() const { return pos_ >= bytes_.size(); }
  std::size_t position() const { return pos_; }
  int line_of(std::size_t offset) const {
    return 1 + static_cast<int>(std::count(bytes_.begin(), bytes_.begin() + static_cast<std::ptrdiff_t>(std::min(offset, bytes_.size())), '\n'));
  }
  std::string where(std::size_t offset) const { return fmt::format("{}:{}", file_, line_of(offset)); }
  std::string where() const { return where(pos_); }

  // The next line without its end ("\n" or "\r\n"); advances past it.
  std::string_view line() {
    const std::size_t end = bytes_.find('\n', pos_);
    std::string_view l = bytes_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
    pos_ = end == std::string_view::npos ? bytes_.size() : end + 1;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    return l;
  }
  std::string_view take(std::size_t n) {
    std::string_view block = bytes_.substr(pos_, n);
    pos_ += block.size();
    return block;
  }

 private:
  std::string_view bytes_;
  const std::string& file_;
  std::size_t pos_ = 0;
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool is_delimiter(std::string_view line) { return trim(line) == "-1"; }

// A Fortran number: E or D exponent, blanks around.
std::optional<double> fortran_real(std::string_view field) {
  std::string s(trim(field));
  if (s.empty()) return std::nullopt;
  for (char& c : s)
    if (c == 'D' || c == 'd') c = 'E';
  const char* begin = s.data() + (s.front() == '+' ? 1 : 0);
  double value = 0.0;
  auto [end, ec] = std::from_chars(begin, s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}
std::optional<long> fortran_integer(std::string_view field) {
  std::string_view s = trim(field);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  long value = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return value;
}

// Fixed-width fields of a record line; a line written free-format (blank-separated, as some
// writers do) is accepted when it has exactly as many blank-separated tokens as fields.
std::vector<std::string_view> fields(std::string_view line, std::initializer_list<std::size_t> widths) {
  std::vector<std::string_view> tokens;
  for (std::size_t i = 0; i < line.size();) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  std::vector<std::string_view> fixed;
  std::size_t at = 0;
  for (std::size_t w : widths) {
    fixed.push_back(at < line.size() ? line.substr(at, w) : std::string_view());
    at += w;
  }
  if (tokens.size() == widths.size() && !std::all_of(fixed.begin(), fixed.end(), [](std::string_view f) {
        return fortran_real(f).has_value();
      }))
    return tokens;
  return fixed;
}

struct Record {
  const Cursor* cursor;
  std::size_t offset;
  std::string name;  // "record 7"
  std::vector<std::string_view> values;

  long integer(std::size_t i, const char* what) const {
    const std::optional<long> v = i < values.size() ? fortran_integer(values[i]) : std::nullopt;
    if (!v)
      throw InputError(fmt::format("{}: dataset 58 {}, field {} ({}): '{}' is not an integer",
                                   cursor->where(offset), name, i + 1, what, i < values.size() ? trim(values[i]) : ""));
    return *v;
  }
  double real(std::size_t i, const char* what) const {
    const std::optional<double> v = i < values.size() ? fortran_real(values[i]) : std::nullopt;
    if (!v || !std::isfinite(*v))
      throw InputError(fmt::format("{}: dataset 58 {}, field {} ({}): '{}' is not a finite number",
                                   cursor->where(offset), name, i + 1, what, i < values.size() ? trim(values[i]) : ""));
    return *v;
  }
};

// Dataset 164: the file's unit system. Factors convert SI to file units (file value = SI value x
// factor), so a receptance in file units (length/force) is SI x length/force.
struct Units {
  double length = 1.0, force = 1.0;
};

Units parse_units_164(Cursor& c) {
  const std::size_t start = c.position();
  c.line();  // units code, description, temperature mode
  std::vector<double> factors;
  while (!c.at_end()) {
    const std::size_t at = c.position();
    std::string_view line = c.line();
    if (is_delimiter(line)) {
      if (factors.size() < 2)
        throw InputError(fmt::format("{}: dataset 164 ends before its length and force factors", c.where(at)));
      if (!(factors[0] > 0.0) || !(factors[1] > 0.0))
        throw InputError(fmt::format("{}: dataset 164: length factor {} and force factor {} must be > 0",
                                     c.where(start), factors[0], factors[1]));
      return {factors[0], factors[1]};
    }
    for (std::size_t i = 0; i < line.size();) {
      while (i < line.size() && line[i] == ' ') ++i;
      const std::size_t s = i;
      while (i < line.size() && line[i] != ' ') ++i;
      if (i == s) continue;
      const std::optional<double> v = fortran_real(line.substr(s, i - s));
      if (!v) throw InputError(fmt::format("{}: dataset 164: '{}' is not a number", c.where(at), line.substr(s, i - s)));
      factors.push_back(*v);
    }
  }
  throw InputError(fmt::format("{}: dataset 164 is not closed by a '-1' line", c.where(start)));
}

struct BinaryLayout {
  bool big_endian = false;
};

struct Header58 {
  std::string id1;
  long function_type = 0;
  long response_node = 0, response_direction = 0, reference_node = 0, reference_direction = 0;
  long ordinate_type = 0;  // 2 real single, 4 real double, 5 complex single, 6 complex double
  long points = 0;
  bool even = false;
  double abscissa_min = 0.0, abscissa_increment = 0.0;
  long abscissa_type = 0, numerator_type = 0, denominator_type = 0;
  std::string numerator_units_label;
  std::size_t offset = 0;  // of the dataset number line

  bool is_complex() const { return ordinate_type == 5 || ordinate_type == 6; }
  bool is_double() const { return ordinate_type == 4 || ordinate_type == 6; }
  std::size_t values_per_point() const { return (is_complex() ? 2u : 1u) + (even ? 0u : 1u); }
};

std::string direction_name(long d) {
  static const char* names[] = {"-RZ", "-RY", "-RX", "-Z", "-Y", "-X", "scalar", "+X", "+Y", "+Z", "+RX", "+RY", "+RZ"};
  return d >= -6 && d <= 6 ? names[d + 6] : fmt::format("{}", d);
}

Header58 parse_header_58(Cursor& c, std::size_t dataset_offset) {
  Header58 h;
  h.offset = dataset_offset;
  h.id1 = std::string(trim(c.line()));
  for (int i = 0; i < 4; ++i) c.line();  // ID lines 2-5
  auto record = [&](const char* name, std::initializer_list<std::size_t> widths) {
    const std::size_t at = c.position();
    if (c.at_end()) throw InputError(fmt::format("{}: dataset 58 ends before its {}", c.where(at), name));
    return Record{&c, at, name, fields(c.line(), widths)};
  };
  const Record r6 = record("record 6", {5, 10, 5, 10, 11, 10, 4, 11, 10, 4});
  h.function_type = r6.integer(0, "function type");
  h.response_node = r6.values.size() == 10 ? r6.integer(5, "response node") : 0;
  h.response_direction = r6.values.size() == 10 ? r6.integer(6, "response direction") : 0;
  h.reference_node = r6.values.size() == 10 ? r6.integer(8, "reference node") : 0;
  h.reference_direction = r6.values.size() == 10 ? r6.integer(9, "reference direction") : 0;
  const Record r7 = record("record 7", {10, 10, 10, 13, 13, 13});
  h.ordinate_type = r7.integer(0, "ordinate data type");
  if (h.ordinate_type != 2 && h.ordinate_type != 4 && h.ordinate_type != 5 && h.ordinate_type != 6)
    throw InputError(fmt::format("{}: dataset 58 record 7: ordinate data type {} is not 2, 4, 5 or 6 (real/complex, "
                                 "single/double)",
                                 c.where(r7.offset), h.ordinate_type));
  h.points = r7.integer(1, "number of values");
  if (h.points < 1 || h.points > 50'000'000)
    throw InputError(fmt::format("{}: dataset 58 record 7: {} values (must be 1..5e7)", c.where(r7.offset), h.points));
  const long spacing = r7.integer(2, "abscissa spacing");
  if (spacing != 0 && spacing != 1)
    throw InputError(fmt::format("{}: dataset 58 record 7: abscissa spacing {} is not 0 (uneven) or 1 (even)",
                                 c.where(r7.offset), spacing));
  h.even = spacing == 1;
  if (h.even) {
    h.abscissa_min = r7.real(3, "abscissa minimum");
    h.abscissa_increment = r7.real(4, "abscissa increment");
    if (!(h.abscissa_increment > 0.0))
      throw InputError(fmt::format("{}: dataset 58 record 7: abscissa increment {} must be > 0", c.where(r7.offset),
                                   h.abscissa_increment));
  }
  const Record r8 = record("record 8", {10, 5, 5, 5, 21, 21});
  h.abscissa_type = r8.integer(0, "abscissa specific data type");
  const Record r9 = record("record 9", {10, 5, 5, 5, 21, 21});
  h.numerator_type = r9.integer(0, "ordinate specific data type");
  if (r9.values.size() >= 6) h.numerator_units_label = std::string(trim(r9.values[5]));
  const Record r10 = record("record 10", {10, 5, 5, 5, 21, 21});
  h.denominator_type = r10.integer(0, "ordinate denominator specific data type");
  record("record 11", {10, 5, 5, 5, 21, 21});
  return h;
}

// The values of an ASCII dataset 58: fixed-width fields (E13.5 for single precision; E20.12 for
// double, after an E13.5 abscissa when uneven), or blank-separated numbers.
std::vector<double> ascii_values(Cursor& c, const Header58& h) {
  std::vector<std::size_t> widths;
  if (!h.is_double()) widths.assign(6, 13);
  else if (h.even) widths.assign(4, 20);
  else if (h.is_complex()) widths = {13, 20, 20};
  else widths = {13, 20, 13, 20};
  const std::size_t expected = static_cast<std::size_t>(h.points) * h.values_per_point();
  std::vector<double> values;
  values.reserve(expected);
  while (true) {
    const std::size_t at = c.position();
    if (c.at_end()) throw InputError(fmt::format("{}: dataset 58 is not closed by a '-1' line", c.where(at)));
    std::string_view line = c.line();
    if (is_delimiter(line)) break;
    std::vector<double> parsed;
    bool fixed_ok = true;
    std::size_t pos = 0;
    for (std::size_t k = 0; pos < line.size(); k = (k + 1) % widths.size()) {
      std::string_view field = line.substr(pos, widths[k]);
      pos += widths[k];
      if (trim(field).empty()) continue;
      const std::optional<double> v = fortran_real(field);
      if (!v) { fixed_ok = false; break; }
      parsed.push_back(*v);
    }
    if (!fixed_ok) {
      parsed.clear();
      for (std::size_t i = 0; i < line.size();) {
        while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        const std::size_t s = i;
        while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
        if (i == s) continue;
        const std::optional<double> v = fortran_real(line.substr(s, i - s));
        if (!v)
          throw InputError(fmt::format("{}: dataset 58 data: '{}' is not a number", c.where(at), line.substr(s, i - s)));
        parsed.push_back(*v);
      }
    }
    for (double v : parsed) {
      if (!std::isfinite(v)) throw InputError(fmt::format("{}: dataset 58 data: a value is not finite", c.where(at)));
      values.push_back(v);
    }
  }
  if (values.size() != expected)
    throw InputError(fmt::format("{}: dataset 58 (line {}) declares {} points ({} numbers) but holds {} numbers",
                                 c.where(h.offset), c.line_of(h.offset), h.points, expected, values.size()));
  return values;
}

template <class T>
T load(const char* p, bool big_endian) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) {
    auto* bytes = reinterpret_cast<unsigned char*>(&value);
    std::reverse(bytes, bytes + sizeof(T));
  }
  return value;
}

std::vector<double> binary_values(Cursor& c, const Header58& h, const BinaryLayout& layout) {
  const std::size_t size = h.is_double() ? 8 : 4;
  const std::size_t count = static_cast<std::size_t>(h.points) * h.values_per_point();
  const std::size_t start = c.position();
  // The block length comes from record 7 (points, type); the header's byte count is not trusted
  // because some writers store it wrong for complex data.
  const std::string_view block = c.take(count * size);
  if (block.size() != count * size)
    throw InputError(fmt::format("{}: binary dataset 58 (line {}) needs {} bytes of data but the file ends after {} "
                                 "(byte offset {})",
                                 c.where(start), c.line_of(h.offset), count * size, block.size(), start));
  std::vector<double> values(count);
  for (std::size_t i = 0; i < count; ++i) {
    values[i] = size == 8 ? load<double>(block.data() + 8 * i, layout.big_endian)
                          : static_cast<double>(load<float>(block.data() + 4 * i, layout.big_endian));
    if (!std::isfinite(values[i]))
      throw InputError(fmt::format("{}: binary dataset 58 (line {}): value {} (byte offset {}) is not finite",
                                   c.where(start), c.line_of(h.offset), i + 1, start + size * i));
  }
  // The closing delimiter follows the data, on the same or the next line.
  std::size_t at = c.position();
  std::string_view rest = c.line();
  if (trim(rest).empty() && !c.at_end()) {
    at = c.position();
    rest = c.line();
  }
  if (!is_delimiter(rest))
    throw InputError(fmt::format("{}: binary dataset 58 (line {}): expected the closing '-1' after its {} bytes of data "
                                 "(byte offset {}), found '{}'",
                                 c.where(at), c.line_of(h.offset), count * size, at, trim(rest).substr(0, 20)));
  return values;
}

FrfQuantity quantity_of(const Header58& h, const Cursor& c) {
  switch (h.numerator_type) {
    case 8: return FrfQuantity::receptance;
    case 11: return FrfQuantity::mobility;
    case 12: return FrfQuantity::accelerance;
    default: break;
  }
  // Unknown or general type: the units label may still say it ("m", "m/s", "m/s^2").
  if (const std::optional<FrfUnit> unit = parse_frf_unit(h.numerator_units_label + "/N")) return unit->quantity;
  throw InputError(fmt::format("{}: dataset 58 record 9: ordinate specific data type {} (units '{}') is not a "
                               "displacement (8), velocity (11) or acceleration (12): cannot tell receptance, mobility "
                               "or accelerance",
                               c.where(h.offset), h.numerator_type, h.numerator_units_label));
}

MeasuredFrf to_frf(const Header58& h, const std::vector<double>& values, const Units& units, int number,
                   const Cursor& c, const std::string& file) {
  if (h.abscissa_type != 18 && h.abscissa_type != 0)
    throw InputError(fmt::format("{}: dataset 58 FRF (record 8): abscissa specific data type {} is not frequency (18)",
                                 c.where(h.offset), h.abscissa_type));
  if (!h.is_complex())
    throw InputError(fmt::format("{}: dataset 58 FRF (record 7): ordinate data type {} is real; an FRF needs complex "
                                 "values (5 or 6)",
                                 c.where(h.offset), h.ordinate_type));
  if (h.denominator_type != 13 && h.denominator_type != 9 && h.denominator_type != 0)
    throw InputError(fmt::format("{}: dataset 58 record 10: ordinate denominator specific data type {} is not a force "
                                 "(13 excitation, 9 reaction)",
                                 c.where(h.offset), h.denominator_type));
  MeasuredFrf frf;
  frf.measured_as = quantity_of(h, c);
  frf.description = h.id1 == "NONE" ? "" : h.id1;
  frf.source = fmt::format("{}, FRF {} (line {}: response {}:{}, reference {}:{})", file, number, c.line_of(h.offset),
                           h.response_node, direction_name(h.response_direction), h.reference_node,
                           direction_name(h.reference_direction));
  const std::size_t stride = h.values_per_point();
  const double to_si = units.force / units.length;  // file units (length/force) -> m/N
  double previous = -1.0;
  for (long p = 0; p < h.points; ++p) {
    const std::size_t i = static_cast<std::size_t>(p) * stride;
    const double hz = h.even ? h.abscissa_min + static_cast<double>(p) * h.abscissa_increment : values[i];
    if (hz < 0.0 || hz <= previous)
      throw InputError(fmt::format("{}: dataset 58 FRF {}: point {} at {} Hz is {}", c.where(h.offset), number, p + 1,
                                   hz, hz < 0.0 ? "negative" : fmt::format("not above the previous {} Hz", previous)));
    previous = hz;
    if (hz == 0.0) continue;  // no dynamics at 0 Hz; mobility and accelerance cannot be converted there
    const std::size_t v = i + (h.even ? 0 : 1);
    frf.frequency_hz.push_back(hz);
    frf.receptance_m_per_n.push_back(to_receptance(Complex(values[v], values[v + 1]) * to_si, frf.measured_as, hz));
  }
  check_frf_lines(frf, frf.source);
  return frf;
}

BinaryLayout parse_binary_layout(std::string_view line, const Cursor& c, std::size_t at) {
  // (I6,1A1,I6,I6,I12,I12,I6,I6,I12,I12)
  const std::vector<std::string_view> f = fields(line.substr(std::min<std::size_t>(7, line.size())), {6, 6, 12, 12});
  auto field = [&](std::size_t i) { return i < f.size() ? trim(f[i]) : std::string_view(); };
  // -1 stands for "absent or not a number" (no valid field value is negative).
  auto value = [&](std::size_t i) { return fortran_integer(field(i)).value_or(-1L); };
  const long order = value(0), format = value(1), lines = value(2);
  if (order != 1 && order != 2)
    throw InputError(fmt::format("{}: binary dataset header: byte ordering '{}' is not 1 (little endian) or 2 (big "
                                 "endian)",
                                 c.where(at), field(0)));
  if (format != 2)
    throw InputError(fmt::format("{}: binary dataset header: floating-point format '{}' is not 2 (IEEE 754)", c.where(at),
                                 field(1)));
  if (lines != 11)
    throw InputError(fmt::format("{}: binary dataset 58 header: '{}' ASCII lines declared; dataset 58 has 11",
                                 c.where(at), field(2)));
  BinaryLayout layout;
  layout.big_endian = order == 2;
  return layout;
}

// Skips a dataset this reader does not use: ASCII up to its closing delimiter; binary by its
// declared ASCII lines and byte count.
void skip_dataset(Cursor& c, std::string_view header, long number, std::size_t at) {
  if (header.size() > 6 && (header[6] == 'b' || header[6] == 'B')) {
    const std::vector<std::string_view> f = fields(header.substr(7), {6, 6, 12, 12});
    const long lines = f.size() > 2 ? fortran_integer(f[2]).value_or(-1L) : -1L;
    const long bytes = f.size() > 3 ? fortran_integer(f[3]).value_or(-1L) : -1L;
    if (lines < 0 || bytes < 0)
      throw InputError(fmt::format("{}: binary dataset {}: cannot skip it (its header gives no line and byte counts)",
                                   c.where(at), number));
    for (long i = 0; i < lines; ++i) c.line();
    c.take(static_cast<std::size_t>(bytes));
  }
  while (!c.at_end())
    if (is_delimiter(c.line())) return;
  throw InputError(fmt::format("{}: dataset {} is not closed by a '-1' line", c.where(at), number));
}

}  // namespace

std::vector<MeasuredFrf> parse_uff58(std::string_view bytes, const std::string& file) {
  Cursor c(bytes, file);
  std::vector<MeasuredFrf> frfs;
  std::vector<std::string> other_functions;
  Units units;
  while (!c.at_end()) {
    std::size_t at = c.position();
    std::string_view line = c.line();
    if (trim(line).empty()) continue;
    if (!is_delimiter(line))
      throw InputError(fmt::format("{}: expected a '    -1' line opening a dataset, found '{}'", c.where(at),
                                   trim(line).substr(0, 40)));
    at = c.position();
    if (c.at_end()) break;
    const std::string_view header = c.line();
    const std::optional<long> number = fortran_integer(header.substr(0, 6));
    if (!number)
      throw InputError(fmt::format("{}: '{}' is not a dataset number (columns 1-6)", c.where(at), trim(header).substr(0, 20)));
    const bool binary = header.size() > 6 && (header[6] == 'b' || header[6] == 'B');
    if (*number == 164 && !binary) {
      units = parse_units_164(c);
    } else if (*number == 58) {
      BinaryLayout layout;
      if (binary) layout = parse_binary_layout(header, c, at);
      const Header58 h = parse_header_58(c, at);
      const std::vector<double> values = binary ? binary_values(c, h, layout) : ascii_values(c, h);
      if (h.function_type == 4)
        frfs.push_back(to_frf(h, values, units, static_cast<int>(frfs.size()) + 1, c, file));
      else
        other_functions.push_back(fmt::format("line {}: function type {}", c.line_of(at), h.function_type));
    } else {
      skip_dataset(c, header, *number, at);
    }
  }
  if (frfs.empty())
    throw InputError(fmt::format("{}: no FRF in the file (a dataset 58 with function type 4){}", file,
                                 other_functions.empty() ? std::string()
                                                         : fmt::format("; its datasets 58 hold: {}",
                                                                       fmt::join(other_functions, "; "))));
  return frfs;
}

// ---------------------------------------------------------------- writing

std::string uff58_bytes(const MeasuredFrf& frf, UffEncoding encoding, FrfQuantity quantity) {
  const bool binary = encoding != UffEncoding::ascii;
  const std::size_t n = frf.frequency_hz.size();
  // Even spacing only when record 7's E13.5 fields hold the start and step exactly.
  bool even = n >= 2;
  const double f0 = frf.frequency_hz.front(), df = n >= 2 ? frf.frequency_hz[1] - frf.frequency_hz[0] : 0.0;
  auto exact_e13 = [](double v) { return fortran_real(fmt::format("{:13.5E}", v)) == v; };
  even = even && exact_e13(f0) && exact_e13(df);
  for (std::size_t i = 0; even && i < n; ++i) even = f0 + static_cast<double>(i) * df == frf.frequency_hz[i];
  std::vector<double> values;
  for (std::size_t i = 0; i < n; ++i) {
    if (!even) values.push_back(frf.frequency_hz[i]);
    const Complex v = from_receptance(frf.receptance_m_per_n[i], quantity, frf.frequency_hz[i]);
    values.push_back(v.real());
    values.push_back(v.imag());
  }
  const int numerator = quantity == FrfQuantity::receptance ? 8 : quantity == FrfQuantity::mobility ? 11 : 12;
  const char* unit_label = quantity == FrfQuantity::receptance ? "m" : quantity == FrfQuantity::mobility ? "m/s" : "m/s^2";
  std::string out = fmt::format("{:>6}\n{:>6}{:74}\n{:>10}{:<20}{:>10}\n", -1, 164, "", 1, "SI", 2);
  out += fmt::format("{:25.16E}{:25.16E}{:25.16E}\n{:25.16E}\n{:>6}\n", 1.0, 1.0, 1.0, 273.15, -1);
  const bool big = encoding == UffEncoding::binary_big_endian;
  out += fmt::format("{:>6}\n{:>6}", -1, 58);
  if (binary)
    out += fmt::format("b{:>6}{:>6}{:>12}{:>12}{:>6}{:>6}{:>12}{:>12}\n", big ? 2 : 1, 2, 11, values.size() * 8, 0, 0, 0, 0);
  else
    out += fmt::format("{:74}\n", "");
  out += fmt::format("{:<80}\n{:<80}\n{:<80}\n{:<80}\n{:<80}\n", frf.description.empty() ? "NONE" : frf.description,
                     "chatterlab", "NONE", "NONE", "NONE");
  out += fmt::format("{:>5}{:>10}{:>5}{:>10} {:<10}{:>10}{:>4} {:<10}{:>10}{:>4}\n", 4, 1, 1, 0, "NONE", 1, 1, "NONE", 1, 1);
  out += fmt::format("{:>10}{:>10}{:>10}{:13.5E}{:13.5E}{:13.5E}\n", 6, n, even ? 1 : 0, even ? f0 : 0.0,
                     even ? df : 0.0, 0.0);
  out += fmt::format("{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n", 18, 0, 0, 0, "Frequency", "Hz");
  out += fmt::format("{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n", numerator, 1, 0, 0, to_string(quantity), unit_label);
  out += fmt::format("{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n", 13, 0, 1, 0, "Force", "N");
  out += fmt::format("{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n", 0, 0, 0, 0, "NONE", "NONE");
  if (binary) {
    for (double v : values) {
      char b[8];
      std::memcpy(b, &v, 8);
      if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + 8);
      out.append(b, 8);
    }
    out += '\n';
  } else if (even) {
    for (std::size_t i = 0; i < values.size(); ++i) out += fmt::format("{:20.11E}{}", values[i], (i % 4 == 3 || i + 1 == values.size()) ? "\n" : "");
  } else {
    for (std::size_t i = 0; i < values.size(); i += 3)
      out += fmt::format("{:13.5E}{:20.11E}{:20.11E}\n", values[i], values[i + 1], values[i + 2]);
  }
  out += fmt::format("{:>6}\n", -1);
  return out;
}

}  // namespace chatterlab
