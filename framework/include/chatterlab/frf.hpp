#pragma once
// Measured frequency response functions (FRFs): what an engineer brings from an impact-hammer tap
// test at the wheel-work contact. Read from
//   - CSV with the units in the header ("frequency [Hz], real [m/N], imag [m/N]" or magnitude and
//     phase), docs/analysis/frf.md lists the accepted names and units;
//   - Universal File Format dataset 58 ("function at nodal DOF"), ASCII or binary (58b), every
//     ordinate type (real/complex, single/double, even/uneven abscissa), with dataset 164's unit
//     factors when the file has one;
// and held as receptance H(j 2 pi f) = X/F in m/N (mobility and accelerance are converted:
// H = Y/(j w), H = -A/w^2), sign convention e^{+j w t}. Bad files are InputErrors naming the file,
// its line (or byte offset in a binary block), the field and what is wrong.
#include <complex>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace chatterlab {

using Complex = std::complex<double>;

// What the file measured (the response quantity over force).
enum class FrfQuantity { receptance, mobility, accelerance };
std::string_view to_string(FrfQuantity quantity);

struct MeasuredFrf {
  std::vector<double> frequency_hz;         // strictly increasing, > 0
  std::vector<Complex> receptance_m_per_n;  // H = X/F [m/N] at each frequency
  std::vector<double> coherence;            // empty when the file has none; else in [0, 1]
  FrfQuantity measured_as = FrfQuantity::receptance;
  std::string source;       // file name, and for UFF the dataset and its DOFs
  std::string description;  // UFF ID line 1 / CSV "# " comment, if any
};

// The FRFs of a file: CSV (one FRF) or UFF (every dataset 58 whose function type is an FRF, in
// file order). The format is recognised from the contents (a UFF file starts with "    -1").
// Throws InputError.
std::vector<MeasuredFrf> read_frfs(const std::filesystem::path& file);

// One FRF of a file: `dataset` counts the file's FRFs from 1; 0 accepts a file holding exactly
// one (else InputError listing them).
MeasuredFrf read_frf(const std::filesystem::path& file, int dataset = 0);

// The parsers behind read_frfs, on bytes already read; `file` names the file in messages.
MeasuredFrf parse_frf_csv(std::string_view text, const std::string& file);
std::vector<MeasuredFrf> parse_uff58(std::string_view bytes, const std::string& file);

// A UFF dataset 58 of `frf` (receptance, complex double, uneven abscissa unless the lines are
// evenly spaced), preceded by a dataset 164 (SI units): for exporting a synthesised FRF and for
// tests. `quantity` converts the receptance back (mobility: j w H, accelerance: -w^2 H).
enum class UffEncoding { ascii, binary_little_endian, binary_big_endian };
std::string uff58_bytes(const MeasuredFrf& frf, UffEncoding encoding,
                        FrfQuantity quantity = FrfQuantity::receptance);

// H and dH/df between the measured lines: a natural cubic spline through the complex values
// (real and imaginary parts alike), so that a criterion evaluated at any frequency of the measured
// band sees a smooth (C2) function of the data; its error is fourth order in the line spacing
// over the modal bandwidth. Outside the band: nullopt.
class FrfInterpolant {
 public:
  explicit FrfInterpolant(const MeasuredFrf& frf);
  struct Value {
    Complex receptance_m_per_n;
    Complex derivative_m_per_n_hz;  // dH/df
  };
  std::optional<Value> at(double frequency_hz) const;
  double min_frequency_hz() const { return f_.front(); }
  double max_frequency_hz() const { return f_.back(); }

 private:
  std::vector<double> f_;
  std::vector<Complex> h_, slope_;
};

}  // namespace chatterlab
