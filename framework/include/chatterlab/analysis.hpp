#pragma once
// Base class of analysis plugins (MODELS.md N chaos, C monitoring, W waviness, E roundness): an
// analysis takes one uniformly sampled series (a vibration signal over time, or a surface profile
// over length or angle) and returns named results. Study kinds pick analyses by registered name,
// e.g. `[analysis] methods = ["embedding", "lyapunov"]`, so a new method is one plugin folder.
//
// Results are JSON objects so that every method can report what it needs; the convention for a
// scalar estimate is an object
//     { "value": v, "ci_low": a, "ci_high": b, "quality": "good" | "uncertain" | "failed",
//       "reason": "..." }
// and curves (e.g. AMI over lag) as arrays under their own keys, which plot() draws.
//
// Capabilities beyond analyse() are typed interfaces an analysis class may also derive from; a
// study kind finds the analyses that have one through the accessor (the analysis returns `this`),
// never by a plugin's name or its result keys:
//   ProfileQualityMeasurement (below)   part quality of a surface profile (waviness, roundness)
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"

namespace chatterlab {

// A series as analyses read it: a non-owning view of the samples plus their spacing. Analyses
// only read, so the samples stay where they are: a numpy array passed from Python (issue 24:
// 10^7 samples without a copy), a column of an input table, a simulation's output. Whoever
// produces samples either keeps them alive for as long as the series is used (view()) or hands
// them to the series (owning()), which then shares them with its copies.
struct SampledSeries {
  std::span<const double> values;  // the samples, read-only; valid while their owner lives
  double sample_interval = 1.0;    // in sample_unit: s for signals, mm for open profiles, rad or
                                   // deg for closed (circumferential) profiles
  std::string sample_unit = "s";
  bool closed = false;             // one full revolution: values wrap around (periodic)
  std::string name;                // e.g. the input column, for plot titles

  double sample_rate() const { return 1.0 / sample_interval; }  // samples per sample_unit

  // A series that keeps `samples` (moved in, shared by copies of the series).
  static SampledSeries owning(std::vector<double> samples, double sample_interval = 1.0,
                              std::string sample_unit = "s", bool closed = false,
                              std::string name = {}) {
    SampledSeries s;
    s.set_samples(std::move(samples));
    s.sample_interval = sample_interval;
    s.sample_unit = std::move(sample_unit);
    s.closed = closed;
    s.name = std::move(name);
    return s;
  }
  // Replaces the samples with `samples`, owned by this series (and its copies).
  void set_samples(std::vector<double> samples) {
    share_samples(std::make_shared<const std::vector<double>>(std::move(samples)));
  }
  // Replaces the samples with ones owned elsewhere and kept alive by `samples` (e.g. a column of
  // the run's parsed input table, through an aliasing shared_ptr): no copy.
  void share_samples(std::shared_ptr<const std::vector<double>> samples) {
    values = std::span<const double>(*samples);
    storage_ = std::move(samples);
  }

 private:
  std::shared_ptr<const std::vector<double>> storage_;  // null: values is the caller's memory
};

class ProfileQualityMeasurement;

class Analysis {
 public:
  virtual ~Analysis() = default;

  // Results of this analysis (with the parameters it was built with) on `series`. `context` holds
  // results of analyses run earlier in the same study, keyed by plugin name (e.g. a Lyapunov
  // estimate reads "embedding" for delay and dimension when its own parameters say "auto").
  // Throws InputError when the series cannot be analysed as configured (too short for the
  // dimension, constant, non-finite), naming the minimum; PointFailure for numerical failure.
  virtual Json analyse(const SampledSeries& series, const Json& context) const = 0;

  // Plots (PNG + SVG through chatterlab/plot.hpp) of a result from analyse(), file stems starting
  // with the plugin name. Default: none.
  virtual void plot(const Json& /*result*/, const SampledSeries& /*series*/,
                    const std::filesystem::path& /*out_dir*/) const {}

  // ---- capabilities (null: the analysis does not have it)
  virtual const ProfileQualityMeasurement* profile_quality() const { return nullptr; }
};

// ------------------------------------------------------------------ profile quality

// The speeds that cut a profile (0: unknown): frequency-resolved waviness bands (W2) need both.
struct ProfileSpeeds {
  double wheel_speed_rpm = 0.0;
  double work_speed_rpm = 0.0;
};

// Part quality of one surface profile: the figures a grinding engineer specifies a part by.
struct ProfileQuality {
  std::optional<double> waviness_wt_um;     // Wt: total height of the waviness profile (W1)
  std::optional<double> waviness_wz_um;     // Wz: mean maximum height of the waviness profile (W1)
  std::optional<double> roundness_ront_um;  // RONt about the least-squares circle (closed profiles)
  // The speeds the frequency bands used: the measurement's own settings, else the caller's.
  std::optional<ProfileSpeeds> speeds;
  bool speeds_from_caller = false;
  Json report;  // the whole evaluation (filter, every parameter, bands), for summary files
};

// Capability of an analysis: measures the quality of a surface profile given in metres.
class ProfileQualityMeasurement {
 public:
  virtual ~ProfileQualityMeasurement() = default;
  // The settings a caller offers its users for the measurement (e.g. the simulate kind's
  // [surface] table): the analysis's parameters without those the call itself fixes (the unit).
  virtual std::vector<ParamSpec> measurement_params() const = 0;
  // A setting of this instance that cannot apply to a profile of the given kind (e.g. a cut-off
  // in mm for a closed profile, which takes it in undulations per revolution): its key and why,
  // so that the caller refuses the study with the setting's file and line. Nothing: all apply.
  struct SettingProblem {
    std::string key;
    Json value;
    std::string reason;  // what is wrong, and what to give instead
  };
  virtual std::optional<SettingProblem> setting_problem(bool closed_profile) const = 0;
  // Quality of `profile_m` (values in metres; closed: one revolution, sample unit deg or rad;
  // open: mm). `speeds` (when known) give the frequency bands unless the analysis's own settings
  // do. Throws InputError when the profile cannot be evaluated as configured (too few samples per
  // cut-off, ...), naming the setting.
  virtual ProfileQuality measure_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds) const = 0;
  // Figures of that measurement (PNG + SVG) in out_dir, file stems starting with the plugin name.
  virtual void plot_profile(const SampledSeries& profile_m, const ProfileSpeeds& speeds,
                            const std::filesystem::path& out_dir) const = 0;
};

}  // namespace chatterlab
