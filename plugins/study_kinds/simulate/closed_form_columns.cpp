#include "study_kinds/simulate/closed_form_columns.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/closed_form.hpp"

namespace chatterlab::simulate_closed_forms {

namespace {

constexpr const char* col_steady_amplitude = "steady_amplitude_m";
constexpr const char* col_note = "closed_form_note";
constexpr double kSteadyTolerance = 0.01;

// Indices of the model's indicators that predict the steady amplitude.
std::vector<std::size_t> predicting(const ClosedFormIndicators& indicators) {
  std::vector<std::size_t> out;
  const std::vector<ClosedFormIndicatorSpec> specs = indicators.indicator_specs();
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (specs[i].predicts == ClosedFormIndicatorSpec::Predicts::steady_amplitude) out.push_back(i);
  return out;
}

// Half peak-to-peak of x over samples [from, to). No line is removed: over a few cycles a wave
// itself correlates with time, so a fitted line would tilt it (the closed forms' case has no drift).
double half_peak_to_peak(const SimulationResult& r, std::size_t from, std::size_t to) {
  const auto first = r.displacement_m.begin() + static_cast<std::ptrdiff_t>(from);
  const auto [lo, hi] = std::minmax_element(first, first + static_cast<std::ptrdiff_t>(to - from));
  return 0.5 * (*hi - *lo);
}

// Why the run is not the closed forms' case (constant nominal speeds, contact kept), or "".
std::string not_the_case(const TimeDomainModel& model, const SimulationResult& r) {
  for (Rotor rotor : {Rotor::wheel, Rotor::work}) {
    const std::vector<double>& rpm = r.speed_rpm[static_cast<std::size_t>(rotor)];
    const double nominal = model.nominal_speed_rpm(rotor);
    const auto [lo, hi] = std::minmax_element(rpm.begin(), rpm.end());
    if (!rpm.empty() && std::max(std::abs(*lo - nominal), std::abs(*hi - nominal)) > 1e-9 * nominal)
      return fmt::format("does not apply: the {} speed varies ({:.6g}..{:.6g} rpm, nominal {:.6g}); the closed "
                         "form is the steady state at constant nominal speeds",
                         to_string(rotor), *lo, *hi, nominal);
  }
  if (r.contact_loss_time_s > 0.0)
    return fmt::format("does not apply: the contact opened ({:.3g} s in all); the closed form keeps it closed",
                       r.contact_loss_time_s);
  if (r.diverged) return "does not apply: the run diverged";
  return "";
}

}  // namespace

std::vector<std::string> columns(const Model& model) {
  const ClosedFormIndicators* indicators = model.closed_forms();
  if (!indicators) return {};
  const std::vector<std::size_t> which = predicting(*indicators);
  if (which.empty()) return {};
  const std::vector<ClosedFormIndicatorSpec> specs = indicators->indicator_specs();
  std::vector<std::string> out{col_steady_amplitude};
  for (std::size_t i : which) out.push_back(specs[i].name);
  out.emplace_back(col_note);
  return out;
}

SteadyAmplitude steady_amplitude(const SimulationResult& r) {
  SteadyAmplitude out;
  const std::size_t n = r.displacement_m.size(), fifth = n / 5;
  if (fifth < 32) return out;
  // Whole cycles between upward crossings of the last fifth's mean (an offset of the mean moves
  // every crossing by the same phase, so they stay a cycle apart).
  const std::size_t begin = n - fifth;
  double mean = 0.0;
  for (std::size_t i = begin; i < n; ++i) mean += r.displacement_m[i] / static_cast<double>(fifth);
  std::vector<std::size_t> up;
  for (std::size_t i = begin + 1; i < n; ++i)
    if (r.displacement_m[i - 1] < mean && r.displacement_m[i] >= mean) up.push_back(i);
  if (up.size() < 5) {  // fewer than 4 cycles: the amplitude of the whole fifth, not judged steady
    out.amplitude_m = half_peak_to_peak(r, begin, n);
    out.change = 1.0;
    return out;
  }
  const std::size_t cycles = (up.size() - 1) - (up.size() - 1) % 2;  // even
  const std::size_t from = up[up.size() - 1 - cycles], middle = up[up.size() - 1 - cycles / 2], to = up.back();
  out.amplitude_m = half_peak_to_peak(r, from, to);
  const double first = half_peak_to_peak(r, from, middle), second = half_peak_to_peak(r, middle, to);
  out.change = std::abs(second - first) / std::max(std::max(first, second), 1e-300);
  out.steady = out.change <= kSteadyTolerance;
  return out;
}

std::vector<Json> values(const Model& model, const TimeDomainModel& time_domain, const SimulationResult& run) {
  const ClosedFormIndicators* indicators = model.closed_forms();
  const std::vector<std::size_t> which = indicators ? predicting(*indicators) : std::vector<std::size_t>{};
  if (which.empty()) return {};
  const std::vector<Json> all = indicators->indicator_values();
  const SteadyAmplitude simulated = steady_amplitude(run);
  std::vector<Json> out{simulated.amplitude_m};
  std::string note = not_the_case(time_domain, run);
  for (std::size_t i : which) {
    const bool applies = note.empty() && all.at(i).is_number() && std::isfinite(all.at(i).get<double>());
    out.push_back(applies ? all.at(i) : Json());
    if (note.empty() && !applies) note = "does not apply at these parameters (e.g. an undamped resonance)";
  }
  if (note.empty())
    note = simulated.steady ? "applies; the simulated response is steady"
                            : fmt::format("applies, but the simulated response is not steady yet (the halves of the "
                                          "last tenth differ by {:.2g} %): run longer to compare",
                                          100.0 * simulated.change);
  out.emplace_back(note);
  return out;
}

}  // namespace chatterlab::simulate_closed_forms
