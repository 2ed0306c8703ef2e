#pragma once
// Units and conversions shared by the FRF readers (framework/src/frf/).
#include <optional>
#include <string>
#include <string_view>

#include "chatterlab/frf.hpp"

namespace chatterlab {

// A value unit of an FRF column: which quantity it is and its factor to SI (m/N, (m/s)/N,
// (m/s^2)/N).
struct FrfUnit {
  FrfQuantity quantity = FrfQuantity::receptance;
  double to_si = 1.0;
};

// "m/N", "um/N", "µm/N", "(m/s)/N", "m/s/N", "m/(N s)", "(m/s^2)/N", "m/s²/N", "g/N", ... (case and
// blanks ignored); nullopt for anything else.
std::optional<FrfUnit> parse_frf_unit(std::string_view unit);

// "Hz", "kHz", "rad/s": the factor to Hz.
std::optional<double> frequency_unit_to_hz(std::string_view unit);

// SI value of `quantity` at frequency_hz -> receptance [m/N], and back.
Complex to_receptance(Complex value_si, FrfQuantity quantity, double frequency_hz);
Complex from_receptance(Complex receptance_m_per_n, FrfQuantity quantity, double frequency_hz);

// At least 4 lines, all values finite (InputError naming `file`).
void check_frf_lines(const MeasuredFrf& frf, const std::string& file);

}  // namespace chatterlab
