#pragma once
#include <filesystem>
#include <optional>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"
#include "shared/metrology/surface.hpp"

namespace chatterlab::surface {

// Analysis plugin `surface_profile` (analysis_registry): the same evaluation for a series another study
// kind already holds, e.g. a simulated work surface (`unit = "m"`, closed, sample unit deg).
// Parameters: the study kind's [filter], [process] and [parameters] keys plus `unit`, flat.
// analyse() returns the summary.json object of the study kind; plot() draws its polar roundness
// plot (and the Wz|f bands with speeds) of a closed profile: surface_profile_polar(.png/.svg),
// surface_profile_wz_f_bands. The constructor throws InputError on inconsistent [process] keys
// (one speed without the other, a band with from > to), naming the flat key.
// For array callers (the Python API) it adds the filtered (waviness) profile, `waviness_um`, one
// value per input sample, which the summary does not hold (chatterlab/analysis_arrays.hpp).
// It is the ProfileQualityMeasurement of the build (chatterlab/analysis.hpp): the simulate kind
// measures its final work surface through that capability.
class SurfaceAnalysis final : public Analysis, public AnalysisWithArrays, public ProfileQualityMeasurement {
 public:
  static PluginInfo info();
  explicit SurfaceAnalysis(const ParamValues& params);
  Json analyse(const SampledSeries& series, const Json& context) const override;
  ResultWithArrays analyse_with_arrays(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;

  const ProfileQualityMeasurement* profile_quality() const override { return this; }
  std::vector<ParamSpec> measurement_params() const override;  // every parameter but `unit`
  std::optional<SettingProblem> setting_problem(bool closed_profile) const override;
  ProfileQuality measure_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds) const override;
  void plot_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds,
                    const std::filesystem::path& out_dir) const override;

 private:
  SurfaceSettings settings() const;
  // The settings for a profile in metres; the caller's speeds where the parameters give none.
  SurfaceSettings settings_in_metres(const ProfileSpeeds& speeds, bool& speeds_from_caller) const;
  void plot_closed(const SampledSeries& series, const SurfaceSettings& settings,
                   const std::filesystem::path& out_dir) const;
  Json params_;
};

}  // namespace chatterlab::surface
