#pragma once
// Surface evaluation of one profile (docs/analysis/surface.md): filter (ISO 16610-21/-31),
// waviness parameters (W1), MOTIF (ISO 12085, open profiles), roundness about four reference
// circles (closed profiles), frequency-resolved Wz|f (W2, closed profiles with speeds).
// Used by the `surface` study kind and, for simulated work surfaces (a `simulate` study's
// angle_deg, work_surface_m), by whoever wants part quality from a dynamics run:
//
//     SampledSeries s{values_m, 360.0 / n, "deg", true};
//     SurfaceSettings settings;  settings.value_to_um = 1e6;  settings.cutoff_upr = 50;
//     Json summary = evaluate_surface(s, settings);
#include <optional>
#include <span>
#include <vector>

#include "shared/metrology/profile_filter.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::surface {

// Smallest cut-off, in samples, the filters accept: ISO 12181-2's rule of at least 7 samples
// per undulation at the cut-off (the sampled Gaussian still has its transmission there: the
// aliases of its spectrum are below exp(-17)).
inline constexpr double min_samples_per_cutoff = 7.0;

struct SurfaceSettings {
  FilterType filter = FilterType::gaussian;
  std::optional<double> cutoff_mm;   // open profiles (series.sample_unit "mm")
  std::optional<double> cutoff_upr;  // closed profiles (series.sample_unit "deg" or "rad");
                                     // default 50 UPR (ISO 12181-2)
  int max_iterations = 50;           // robust filter reweighting passes
  double value_to_um = 1.0;          // profile values * this = micrometres
  int sampling_lengths = 1;          // W parameters averaged over this many sampling lengths
  std::optional<double> wheel_speed_rpm, work_speed_rpm;  // both: Wz|f bands (W2)
  std::optional<std::pair<double, double>> low_band_upr, high_band_upr;  // override the bands
  double motif_a_mm = 0.5, motif_b_mm = 2.5;  // ISO 12085 limits A (roughness), B (waviness)
};

// Everything one evaluation produces: the summary (see docs/analysis/surface.md for its keys)
// and the filtered profiles in micrometres for filtered.csv and plots. Two arrays per sample, not
// four: positions and roughness follow from them (a 10^7-sample profile evaluates in a few arrays'
// worth of memory, issue 23).
//
// profile_um is the series' own samples when they are in um already (no copy), else a scaled copy
// held here: an evaluation is valid while the series' samples are (moved, never copied).
struct SurfaceEvaluation {
  Json summary;
  std::span<const double> profile_um;
  std::vector<double> waviness_um;
  double position_step = 1.0;  // x_mm (open) or angle_deg (closed) between samples
  std::vector<double> scaled_profile_um;  // profile_um's samples when the series is not in um

  SurfaceEvaluation() = default;
  SurfaceEvaluation(SurfaceEvaluation&&) = default;
  SurfaceEvaluation& operator=(SurfaceEvaluation&&) = default;
  SurfaceEvaluation(const SurfaceEvaluation&) = delete;  // profile_um would view the original
  SurfaceEvaluation& operator=(const SurfaceEvaluation&) = delete;

  std::size_t samples() const { return profile_um.size(); }
  double position(std::size_t i) const { return static_cast<double>(i) * position_step; }
  double roughness_um(std::size_t i) const { return profile_um[i] - waviness_um[i]; }
};

// Throws InputError when the series cannot be evaluated as configured (too few samples per
// cut-off, cut-off longer than the profile, unit/settings mismatch).
SurfaceEvaluation evaluate_surface_profile(const SampledSeries& series,
                                           const SurfaceSettings& settings);

// The filter a series gets with these settings (cut-off in samples), after the checks
// evaluate_surface_profile makes: >= 4 samples, unit mm (open) or deg/rad (closed, exactly one
// revolution), cutoff_mm (open) or cutoff_upr (closed, >= 1; default 50), cut-off not longer
// than the profile, >= min_samples_per_cutoff samples per cut-off. Throws InputError naming the
// setting and the limit. `filter_json` receives the filter's summary entry.
FilterSettings resolve_filter(const SampledSeries& series, const SurfaceSettings& settings,
                              Json& filter_json);

// The summary alone (the link for dynamics studies).
Json evaluate_surface(const SampledSeries& series, const SurfaceSettings& settings);


}  // namespace chatterlab::surface
