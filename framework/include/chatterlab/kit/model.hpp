#pragma once
// Study kit: the [model] table of a study, its linear stability and its time-domain form, the way
// every study kind needs them (stability_map, feed_risk, suppression_map, stability_lobes, ...).
#include <memory>
#include <optional>
#include <string>

#include "chatterlab/model.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/roots.hpp"

namespace chatterlab::kit {

// What a kind needs of the study's model; validate_model refuses a model without it (exit 2,
// naming model.type), so a study does not fail at thousands of points for one reason.
enum class ModelNeeds { nothing = 0, characteristic = 1, time_domain = 2 };
constexpr ModelNeeds operator|(ModelNeeds a, ModelNeeds b) {
  return static_cast<ModelNeeds>(static_cast<int>(a) | static_cast<int>(b));
}
constexpr bool has(ModelNeeds set, ModelNeeds need) {
  return (static_cast<int>(set) & static_cast<int>(need)) != 0;
}

// Validates the document's [model] table against the model registry (type and parameters, with
// defaults filled in), writes it back, builds the model once and checks `needs`. Returns the
// built model (for further study-level checks).
std::unique_ptr<Model> validate_model(Json& document, ModelNeeds needs, const std::string& kind,
                                      const SourceMap& sources);

// The model plugin named by model_table["type"], created from the table's other keys.
std::unique_ptr<Model> build_model(const Json& model_table);

// ------------------------------------------------------------------ linear stability

// Settings of the certified rightmost-root search: the [stability] table of stability_map and
// of every kind that computes roots.
struct StabilitySettings {
  // Search band |Im s| <= 2 pi max_frequency_hz; default: default_band_multiple x the model's
  // highest structural natural frequency.
  std::optional<double> max_frequency_hz;
  int max_newton_iterations = RootSearchOptions{}.max_newton_iterations;
  double newton_relative_tolerance = RootSearchOptions{}.newton_relative_tolerance;
  long max_function_evaluations = RootSearchOptions{}.max_function_evaluations;
  // A spindle holds its speed only within a tolerance: every verdict is also evaluated with each
  // rotor's speed anywhere in [1 - tol, 1 + tol] x nominal (models with process conditions). A
  // verdict that holds at the nominal speeds alone may rest on an exact speed ratio, where the
  // wheel's and the work's delay lattices coincide and the rightmost root jumps.
  double speed_tolerance = 0.005;
};

// Regenerative chatter locks onto a structural mode; at 4 x its frequency the structure's
// dynamic compliance is down to about 1/15 of its static value, so roots beyond the band belong
// to the (stable) delay chains.
inline constexpr double default_band_multiple = 4.0;

const ParamTable<StabilitySettings>& stability_settings_table();

// Also refuses (InputError at [stability]) a model that has no characteristic function or, with
// no max_frequency_hz, no structural frequency to derive the band from.
StabilitySettings validate_stability(Json& document, const Model& model, const SourceMap& sources);

RootSearchOptions root_search_options(const StabilitySettings& settings,
                                      const CharacteristicFunction& characteristic);

// The certified rightmost root of `model`. Throws PointFailure when the model has no
// characteristic function or no root was found.
RightmostRoot rightmost_root(const Model& model, const StabilitySettings& settings);

// The rightmost root over the speed-tolerance band: the worst (largest) growth rate among the
// nominal root and roots at speeds sampled across the band: each rotor's speed swept with the
// other at nominal (odd sample counts, four per regenerative lobe the nominal chatter frequency
// passes through in the band, at least 3, at most 33) and the four corners where both deviate.
// A sampled worst case: a lobe narrower than the sampling can still be missed.
struct SpeedBandVerdict {
  bool applies = false;  // the model declares process conditions and the tolerance is > 0
  double worst_growth_rate_per_s = 0.0;
  double worst_chatter_frequency_hz = 0.0;
  double worst_wheel_speed_rpm = 0.0, worst_work_speed_rpm = 0.0;
  bool stable_over_band = false;
  bool certified = false;     // every sampled root certified
  std::size_t samples = 0;    // roots evaluated (the nominal one included)
  // The nominal wheel/work speed ratio as p/q when it is one of small whole numbers (q <= 12):
  // the delay lattices then share roots, and the nominal verdict is not robust by itself.
  std::string exact_speed_ratio;
};
// `model` is built from `model_table` (the band's models differ from it by their speeds only).
SpeedBandVerdict speed_band_verdict(const Json& model_table, const Model& model,
                                    const StabilitySettings& settings, const RightmostRoot& nominal);

// "p/q" when a/b equals p/q (q <= max_denominator) to 1e-9 relative; empty otherwise.
std::string exact_ratio(double a, double b, int max_denominator = 12);

// The quantities derived from a rightmost root that every kind reports the same way.
struct StabilityVerdict {
  double growth_rate_per_s = 0.0;      // Re s
  double chatter_frequency_hz = 0.0;   // |Im s| / 2 pi
  std::optional<double> growth_rate_per_wheel_rev;  // G3: Tg Re s / 2 pi, models with a wheel
  bool stable = false;                 // Re s < 0
};
StabilityVerdict verdict(const RightmostRoot& root, const Model& model);

}  // namespace chatterlab::kit
