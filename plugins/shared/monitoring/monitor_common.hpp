#pragma once
// Shared pieces of the chatter monitors (MODELS.md C1-C3): a detector turns a signal into a score
// per evaluation time (causal: each score uses only samples up to that time), and one alarm rule
// with persistence turns scores into alarm intervals. Used by the analysis plugins bp_network and
// rbf_density and by the study kind chatter_monitor. docs/analysis/monitoring.md.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::monitor {

// Scores of one detector over a signal. t_s[k] is the time of the last sample the k-th score
// uses (the earliest moment a streaming monitor could know it).
struct ScoreTrack {
  std::string detector;     // plugin name
  std::string score_label;  // for plots, e.g. "network output"
  std::vector<double> t_s, score;
  double threshold = 0.0;   // a score >= threshold flags chatter at that evaluation
};

struct AlarmInterval {
  double start_s = 0.0;  // time the alarm was raised
  double end_s = 0.0;    // time it was cleared, or the end of the signal when still on
  bool open = false;     // still on at the end of the signal
};

// Persistence rule (debounce): the alarm is raised at the evaluation that completes
// `persistence` consecutive flagged evaluations (score >= threshold), and cleared at the
// evaluation that completes `persistence` consecutive unflagged ones. persistence = 1 is the raw
// per-window decision. A single flagged window in a stable signal therefore never raises it, at
// the price of a detection delay of persistence - 1 evaluation intervals.
struct AlarmReport {
  std::vector<bool> alarm;  // state after each evaluation
  std::vector<AlarmInterval> intervals;
  std::optional<double> first_alarm_s;
  std::optional<double> first_flag_s;  // first single flagged evaluation (before persistence)
};

AlarmReport track_alarms(const ScoreTrack& track, std::size_t persistence, double signal_end_s);

// {"first_alarm_s": v|null, "first_flag_s": ..., "intervals": [[start, end], ...],
//  "alarm_open_at_end": bool}
Json alarm_json(const AlarmReport& report);

// The `persistence_windows` parameter, shared by every detector plugin (defaults differ: windows
// that overlap give correlated flags and need a longer run).
ParamSpec persistence_spec(int default_windows);

// A positive integer count parameter (window_samples, hop_samples, nodes ...) with a default and
// a minimum.
ParamSpec count_spec(const std::string& key, const std::string& description,
                     std::int64_t default_value, std::int64_t min);

// A detector plugin (an Analysis that also offers its scores to chatter_monitor).
class Detector {
 public:
  virtual ~Detector() = default;
  // Throws InputError when `series` cannot be monitored as configured (window longer than the
  // signal, labelled ranges outside it ...), naming the key and the limit.
  virtual void check(const SampledSeries& series) const = 0;
  // Scores over the whole series; `details` receives detector-specific results (training
  // summary, test confusion, density snapshots).
  virtual ScoreTrack scores(const SampledSeries& series, Json& details) const = 0;
  virtual std::size_t persistence() const = 0;
  // The state behind the score of the window ending at sample `last_sample`, for "stable vs
  // chatter" snapshot figures (plot_density_snapshots): an amplitude-density detector gives its
  // density on a grid; null for a detector without such a state.
  virtual Json snapshot(const SampledSeries& /*series*/, std::size_t /*last_sample*/) const {
    return nullptr;
  }
};

// Detector::check, scores and track_alarms as one result (merged: what analyse() returns):
// details + {"threshold", "persistence_windows", "t_s": [...], "score": [...], "alarm": [...],
// "alarms": alarm_json}; t_s, score and alarm, one value per evaluation, as arrays
// (chatterlab/analysis_arrays.hpp).
ResultWithArrays detector_result(const Detector& detector, const SampledSeries& series);

// A detector_result() with its per-evaluation series as vectors (ResultWithArrays moved apart):
// what a caller that keeps 10^6 evaluations per detector holds instead of JSON arrays.
struct DetectorTrack {
  Json result;                  // everything else (alarms, threshold, training ...); no t_s, score, alarm
  std::vector<double> t_s;      // time of each evaluation, increasing
  std::vector<double> score;
  std::vector<double> alarm;    // state after each evaluation, 0 / 1
};
DetectorTrack detector_track(ResultWithArrays&& result);
// Whether the alarm is on at any time in [t0_s, t1_s]: on at t0_s, or switched on by an
// evaluation in (t0_s, t1_s]. A plot's shading line stands for its whole time bucket, so an
// alarm shorter than a bucket (10^7 samples: 1500 lines of ~0.8 s) is drawn, not lost between
// two lines.
bool alarm_within(const DetectorTrack& track, double t0_s, double t1_s);

// Plot of a detector_result(): scores over time, the alarm state (0/1, after persistence) as a
// step line and the threshold dashed; <stem>.png/.svg in out_dir.
void plot_scores(const Json& result, const std::string& title, const std::string& score_label,
                 const std::filesystem::path& out_dir, const std::string& stem);
void plot_scores(const DetectorTrack& track, const std::string& title,
                 const std::string& score_label, const std::filesystem::path& out_dir,
                 const std::string& stem);

// A figure of density snapshots (Detector::snapshot: "t_s", "x", "density", "mean", "x_max",
// "ratio", "flagged"), each window scaled to its own |x_max - mean|; <stem>.png/.svg in out_dir.
void plot_density_snapshots(const std::vector<Json>& snapshots, const std::string& title,
                            const std::string& signal_unit, const std::filesystem::path& out_dir,
                            const std::string& stem);

// Time of the last sample of a series (t = 0 at the first sample).
double end_time_s(const SampledSeries& series);

// Throws InputError unless the series has at least `samples` finite values; `what` names the
// setting, e.g. "bp_network.window_samples = 10".
void require_samples(const SampledSeries& series, std::size_t samples, const std::string& what);

// splitmix64: a small portable generator, so a seed gives the same numbers on every platform
// (std:: distributions are implementation-defined). Network initial weights and the synthetic
// test signals use it.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  double uniform01();  // [0, 1)
  double normal();     // standard normal (Box-Muller)

 private:
  std::uint64_t state_;
};

// A synthetic stable -> chatter transition (known answers for tests, the shipped study signal):
// white Gaussian noise of standard deviation noise_rms, plus from onset_s on a sine of
// chatter_frequency_hz with random phase whose amplitude grows exponentially at growth_per_s from
// initial_amplitude and saturates at saturation_amplitude (logistic law, as chatter limited by
// loss of contact):  a(t) = a_sat / (1 + (a_sat/a0 - 1) exp(-g (t - onset))).
struct TransitionSignal {
  double sample_rate_hz = 8000.0;
  double duration_s = 1.0;
  double noise_rms = 1.0;
  double onset_s = 0.5;
  double chatter_frequency_hz = 360.0;
  double initial_amplitude = 0.05;
  double growth_per_s = 25.0;
  double saturation_amplitude = 8.0;
  std::uint64_t seed = 1;

  double amplitude(double t) const;    // a(t), 0 before the onset
  double time_of_amplitude(double a) const;  // inverse of a(t) for a0 < a < a_sat
  std::vector<double> samples() const;
};

}  // namespace chatterlab::monitor
