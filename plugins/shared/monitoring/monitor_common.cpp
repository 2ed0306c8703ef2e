#include "shared/monitoring/monitor_common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab::monitor {

AlarmReport track_alarms(const ScoreTrack& track, std::size_t persistence, double signal_end_s) {
  if (persistence == 0) persistence = 1;
  AlarmReport report;
  bool on = false;
  std::size_t run = 0;  // consecutive evaluations disagreeing with the current state
  for (std::size_t k = 0; k < track.score.size(); ++k) {
    const bool flagged = track.score[k] >= track.threshold;
    if (flagged && !report.first_flag_s) report.first_flag_s = track.t_s[k];
    run = flagged != on ? run + 1 : 0;
    if (run >= persistence) {
      on = !on;
      run = 0;
      if (on) {
        report.intervals.push_back({track.t_s[k], signal_end_s, true});
        if (!report.first_alarm_s) report.first_alarm_s = track.t_s[k];
      } else {
        report.intervals.back().end_s = track.t_s[k];
        report.intervals.back().open = false;
      }
    }
    report.alarm.push_back(on);
  }
  return report;
}

Json alarm_json(const AlarmReport& report) {
  Json intervals = Json::array();
  for (const auto& i : report.intervals) intervals.push_back({i.start_s, i.end_s});
  return {{"first_alarm_s", report.first_alarm_s ? Json(*report.first_alarm_s) : Json()},
          {"first_flag_s", report.first_flag_s ? Json(*report.first_flag_s) : Json()},
          {"intervals", std::move(intervals)},
          {"alarm_open_at_end", !report.intervals.empty() && report.intervals.back().open}};
}

ParamSpec persistence_spec(int default_windows) {
  ParamSpec spec = param_spec(
      "persistence_windows", ValueKind::integer, "1",
      "consecutive flagged evaluations that raise the alarm (and unflagged ones that clear it); "
      "1 = raw per-window decision");
  spec.default_value = default_windows;
  spec.min = 1;
  spec.max = 1000;
  return spec;
}

ParamSpec count_spec(const std::string& key, const std::string& description,
                     std::int64_t default_value, std::int64_t min) {
  ParamSpec spec = param_spec(key, ValueKind::integer, "1", description);
  spec.default_value = default_value;
  spec.min = static_cast<double>(min);
  return spec;
}

ResultWithArrays detector_result(const Detector& detector, const SampledSeries& series) {
  detector.check(series);
  ResultWithArrays out;
  ScoreTrack track = detector.scores(series, out.result);
  const AlarmReport report = track_alarms(track, detector.persistence(), end_time_s(series));
  out.result["threshold"] = track.threshold;
  out.result["persistence_windows"] = detector.persistence();
  out.add("t_s", std::move(track.t_s));
  out.add("score", std::move(track.score));
  out.add("alarm", std::vector<double>(report.alarm.begin(), report.alarm.end()), /*boolean=*/true);
  out.result["alarms"] = alarm_json(report);
  return out;
}

DetectorTrack detector_track(ResultWithArrays&& result) {
  DetectorTrack track;
  for (ResultArray& a : result.arrays) {
    std::vector<double>* to = a.key == "t_s"     ? &track.t_s
                              : a.key == "score" ? &track.score
                              : a.key == "alarm" ? &track.alarm
                                                 : nullptr;
    if (!to) throw std::logic_error("detector_track: unexpected series '" + a.key + "'");
    *to = std::move(a.values);
    result.result.erase(a.key);
  }
  track.result = std::move(result.result);
  return track;
}

void plot_scores(const Json& result, const std::string& title, const std::string& score_label,
                 const std::filesystem::path& out_dir, const std::string& stem) {
  DetectorTrack track;
  track.result = {{"threshold", result.at("threshold")},
                  {"persistence_windows", result.at("persistence_windows")}};
  track.t_s = result.at("t_s").get<std::vector<double>>();
  track.score = result.at("score").get<std::vector<double>>();
  for (const Json& a : result.at("alarm")) track.alarm.push_back(a.get<bool>() ? 1.0 : 0.0);
  plot_scores(track, title, score_label, out_dir, stem);
}

void plot_scores(const DetectorTrack& track, const std::string& title,
                 const std::string& score_label, const std::filesystem::path& out_dir,
                 const std::string& stem) {
  plot::Curves c;
  c.title = title;
  c.x_label = "time of the latest sample used [s]";
  c.y_label = score_label;
  // A long signal has 10^6 evaluations or more: the plot draws each bucket's lowest and highest
  // score and alarm state in time order (at most ~2 x plot_buckets points a series), so its
  // files stay bounded and no spike or alarm vanishes from the picture.
  constexpr std::size_t plot_buckets = 4000;
  plot::Series score = kit::decimated("score", track.t_s, track.score, plot_buckets);
  score.style = "points";
  c.series.push_back(std::move(score));
  const Json& r = track.result;
  plot::Series alarm = kit::decimated(
      fmt::format("alarm state (persistence {})", r.at("persistence_windows").get<int>()),
      track.t_s, track.alarm, plot_buckets);
  alarm.style = "steps";
  c.series.push_back(std::move(alarm));
  c.reference_y = r.at("threshold").get<double>();
  c.reference_label = fmt::format("threshold {}", r.at("threshold").get<double>());
  plot::render(c, out_dir, stem);
}

double end_time_s(const SampledSeries& series) {
  return series.values.empty() ? 0.0
                               : static_cast<double>(series.values.size() - 1) *
                                     series.sample_interval;
}

void require_samples(const SampledSeries& series, std::size_t samples, const std::string& what) {
  if (series.values.size() < samples)
    throw InputError(fmt::format("{}: the signal{} has {} samples, fewer than the {} this needs",
                                 what, series.name.empty() ? "" : " '" + series.name + "'",
                                 series.values.size(), samples));
  for (std::size_t i = 0; i < series.values.size(); ++i)
    if (!std::isfinite(series.values[i]))
      throw InputError(fmt::format("{}: sample {} of the signal is not a finite number", what, i));
}

std::uint64_t SplitMix64::next() {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double SplitMix64::uniform01() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double SplitMix64::normal() {
  const double u1 = 1.0 - uniform01();  // (0, 1]: log finite
  const double u2 = uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

double TransitionSignal::amplitude(double t) const {
  if (t < onset_s) return 0.0;
  return saturation_amplitude /
         (1.0 + (saturation_amplitude / initial_amplitude - 1.0) *
                    std::exp(-growth_per_s * (t - onset_s)));
}

double TransitionSignal::time_of_amplitude(double a) const {
  return onset_s + std::log((saturation_amplitude / initial_amplitude - 1.0) /
                            (saturation_amplitude / a - 1.0)) /
                       growth_per_s;
}

std::vector<double> TransitionSignal::samples() const {
  SplitMix64 rng(seed);
  const double phase = 2.0 * std::numbers::pi * rng.uniform01();
  const auto n = static_cast<std::size_t>(std::llround(duration_s * sample_rate_hz));
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / sample_rate_hz;
    x[i] = noise_rms * rng.normal() +
           amplitude(t) * std::sin(2.0 * std::numbers::pi * chatter_frequency_hz * t + phase);
  }
  return x;
}

void plot_density_snapshots(const std::vector<Json>& snapshots, const std::string& title,
                            const std::string& signal_unit, const std::filesystem::path& out_dir,
                            const std::string& stem) {
  plot::Curves c;
  c.title = title;
  c.x_label = fmt::format("(x - mean) / |x_max - mean|   (x in {})", signal_unit);
  c.y_label = "RBF density estimate, same scaling [1]";
  for (const Json& s : snapshots) {
    // Each window's amplitude is scaled to its own |x_max - mean| so stable and chatter windows
    // (amplitudes decades apart) share one axis; the density is rescaled to keep unit area.
    const double mean = s.at("mean").get<double>();
    double spread = std::abs(s.at("x_max").get<double>() - mean);
    if (!(spread > 0.0)) spread = 1.0;
    std::vector<double> x = s.at("x").get<std::vector<double>>();
    std::vector<double> p = s.at("density").get<std::vector<double>>();
    for (auto& v : x) v = (v - mean) / spread;
    for (auto& v : p) v *= spread;
    c.series.push_back({fmt::format("window ending t = {:.4g} s: ratio {:.2f}{}",
                                    s.at("t_s").get<double>(), s.at("ratio").get<double>(),
                                    s.at("flagged").get<bool>() ? " (chatter)" : " (stable)"),
                        std::move(x), std::move(p)});
  }
  plot::render(c, out_dir, stem);
}

bool alarm_within(const DetectorTrack& track, double t0_s, double t1_s) {
  auto it = std::upper_bound(track.t_s.begin(), track.t_s.end(), t0_s);
  const auto at = [&](auto i) { return track.alarm[static_cast<std::size_t>(i - track.t_s.begin())]; };
  if (it != track.t_s.begin() && at(it - 1) != 0.0) return true;
  for (; it != track.t_s.end() && *it <= t1_s; ++it)
    if (at(it) != 0.0) return true;
  return false;
}

}  // namespace chatterlab::monitor
