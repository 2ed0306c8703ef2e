#include "study_kinds/chatter_monitor/chatter_monitor.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>

#include "chatterlab/analysis_arrays.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/kit/output.hpp"
#include "chatterlab/kit/plots.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"
#include "chatterlab/signal_io.hpp"
#include "shared/monitoring/features.hpp"
#include "shared/monitoring/monitor_common.hpp"

namespace chatterlab {

namespace {

namespace fs = std::filesystem;

constexpr const char* time_column = "t_s";       // a simulate study's timeseries.csv
constexpr std::size_t shading_lines = 1500;      // vertical lines drawing the alarm shading
constexpr std::size_t plot_buckets = 10000;      // signal plot: each bucket's min and max
constexpr double uniform_tolerance = 1e-6;       // relative spread of t_s steps accepted

// alarms.csv (~45 bytes per evaluation) and features.csv (~75 bytes per window): for a signal
// of 10^7 samples 170 MB, more than the run holds in memory. Written by default up to 10^6
// samples, above that only on request ([monitor] series_csv = "always").
const kit::OnRequestFile series_csv_file{
    "monitor", "series_csv",
    "alarms.csv and features.csv (a row per detector evaluation, per network window)", 1'000'000};

// [input] and the kind's own [monitor] keys, declared once.
struct MonitorInput {
  std::string file;
  std::optional<std::string> column;     // absent: the only column besides t_s
  std::optional<double> sample_rate_hz;  // absent: WAV header or a uniform t_s column
};

const ParamTable<MonitorInput>& input_table() {
  static const ParamTable<MonitorInput> table = [] {
    ParamTable<MonitorInput> t;
    t.add(&MonitorInput::file, "file", "",
          "signal file: CSV / whitespace columns or WAV (relative to the study file)")
        .required();
    t.add(&MonitorInput::column, "column", "",
          "column name or 1-based number (default: the only column besides t_s)");
    t.add(&MonitorInput::sample_rate_hz, "sample_rate_hz", "Hz",
          "sample rate (default: from a WAV header or a uniform t_s column)")
        .positive();
    return t;
  }();
  return table;
}

struct MonitorSettings {
  std::optional<std::vector<double>> snapshot_times_s;  // absent: the detector's own choice
};

const ParamTable<MonitorSettings>& monitor_table() {
  static const ParamTable<MonitorSettings> table = [] {
    ParamTable<MonitorSettings> t;
    t.add(&MonitorSettings::snapshot_times_s, "snapshot_times_s", "s",
          "times at which density snapshots are drawn (default: first window, first rbf_density "
          "alarm, last window)")
        .non_negative();
    return t;
  }();
  return table;
}

// The kind's own [monitor] keys.
std::vector<ParamSpec> monitor_specs() {
  std::vector<ParamSpec> specs = monitor_table().specs();
  specs.push_back(series_csv_file.spec());
  return specs;
}

const Registry<Analysis>::Entry& detector_entry(const std::string& name) {
  return analysis_registry().at(name);
}

std::unique_ptr<Analysis> build_detector(const std::string& name, const Json& table) {
  return detector_entry(name).create(ParamValues(table));
}

const monitor::Detector& as_detector(const Analysis& a) {
  return dynamic_cast<const monitor::Detector&>(a);
}

std::vector<std::string> enabled_detectors(const Json& monitor) {
  std::vector<std::string> out;
  for (const char* name : ChatterMonitor::detector_names)
    if (monitor.contains(name)) out.emplace_back(name);
  return out;
}

// The sample rate from a t_s column: uniform steps (to rounding) required.
double rate_from_time_column(const std::vector<double>& t, const DataTable& table,
                             const std::string& where) {
  if (t.size() < 2)
    throw InputError(fmt::format("{}: {}: a t_s column of {} value(s) gives no sample rate", where,
                                 table.file.string(), t.size()));
  const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(dt > 0.0) || std::abs((t[i] - t[i - 1]) - dt) > uniform_tolerance * dt)
      throw InputError(fmt::format(
          "{}: {}: line {}: t_s is not uniformly spaced (step {} s, mean step {} s); give "
          "input.sample_rate_hz or resample the signal",
          where, table.file.string(), table.source_line(i),
          t[i] - t[i - 1], dt));
  return 1.0 / dt;
}

// [input]: validated, file made absolute, column and sample rate resolved in place.
void validate_input(Json& document, const SourceMap& sources) {
  if (!document.contains("input") || !document["input"].is_object())
    throw InputError(fmt::format(
        "{}: missing table [input] (file = \"signal.csv\", column = \"...\", sample_rate_hz = "
        "...)",
        sources.locate("input").str()));
  kit::integer_columns_as_names(document["input"], {"column"});
  Json input = validate_params(document["input"], input_table().specs(), "input", sources);
  const std::string where = sources.locate("input.file").str();
  input["file"] = kit::resolve_data_file(input["file"], "input.file", sources).string();
  const std::shared_ptr<const DataTable> shared_table =
      kit::read_shared_table_at(input["file"].get<std::string>(), "input.file", sources);
  const DataTable& table = *shared_table;
  if (input["column"].is_null()) {
    std::vector<std::string> candidates;
    for (const auto& name : table.names)
      if (name != time_column) candidates.push_back(name);
    if (candidates.size() != 1)
      throw InputError(fmt::format(
          "{}: missing key 'input.column': {} has the columns {}; say which one to monitor",
          sources.locate("input").str(), table.file.string(), fmt::join(table.names, ", ")));
    input["column"] = candidates.front();
  }
  try {
    (void)table.column(input["column"].get<std::string>());
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: input.column = \"{}\": {}",
                                 sources.locate("input.column").str(),
                                 input["column"].get<std::string>(), e.what()));
  }
  if (input["sample_rate_hz"].is_null()) {
    if (table.sample_rate_hz) {
      input["sample_rate_hz"] = *table.sample_rate_hz;
    } else if (std::find(table.names.begin(), table.names.end(), time_column) !=
               table.names.end()) {
      input["sample_rate_hz"] = rate_from_time_column(table.column(time_column), table, where);
    } else {
      throw InputError(fmt::format(
          "{}: missing key 'input.sample_rate_hz': {} has no t_s column and no WAV header to "
          "take the sample rate from",
          sources.locate("input").str(), table.file.string()));
    }
  }
  document["input"] = std::move(input);
}

// The signal for a plot: fewer than 2 x plot_buckets samples whole, longer ones as the lowest
// and highest sample of each of ~plot_buckets buckets in time order, so the plot stays small and
// shows the extremes.
plot::Series signal_series(const SampledSeries& s) {
  return kit::decimated(
      s.name, s.values.size(), [&](std::size_t i) { return static_cast<double>(i) * s.sample_interval; },
      [&](std::size_t i) { return s.values[i]; }, plot_buckets);
}

// Alarm state at time t: the state after the latest evaluation at or before t.
// Draws every figure even when one fails; the failures go to summary.json.
class Figures {
 public:
  template <class Draw>
  void attempt(Draw&& draw) {
    try {
      std::forward<Draw>(draw)();
    } catch (const std::exception& e) {
      errors.push_back(e.what());
    }
  }
  std::vector<std::string> errors;
};

using Tracks = std::map<std::string, monitor::DetectorTrack>;  // by detector name

void plot_point(const SampledSeries& series, const Tracks& results,
                const std::vector<Json>& snapshots, const fs::path& dir, Figures& figures) {
  const double end = monitor::end_time_s(series);
  double amplitude = 0.0;
  for (double v : series.values) amplitude = std::max(amplitude, std::abs(v));
  if (!(amplitude > 0.0)) amplitude = 1.0;
  for (const auto& [name, track] : results) {
    const Json& alarms = track.result.at("alarms");
    const std::string first =
        alarms.at("first_alarm_s").is_number()
            ? fmt::format("first alarm at {:.4g} s", alarms.at("first_alarm_s").get<double>())
            : std::string("no alarm");

    plot::Curves signal;
    signal.title = fmt::format("{} with {} alarms shaded ({})", series.name, name, first);
    signal.x_label = "time [s]";
    signal.y_label = series.name;
    plot::Series shade{fmt::format("{} alarm on", name), {}, {}, "impulses"};
    for (std::size_t k = 0; k < shading_lines; ++k) {
      const double bucket_s = end / static_cast<double>(shading_lines - 1);
      const double tk = end * static_cast<double>(k) / static_cast<double>(shading_lines - 1);
      if (!monitor::alarm_within(track, tk - 0.5 * bucket_s, tk + 0.5 * bucket_s)) continue;
      for (double y : {amplitude, -amplitude}) {
        shade.x.push_back(tk);
        shade.y.push_back(y);
      }
    }
    if (!shade.x.empty()) signal.series.push_back(std::move(shade));
    signal.series.push_back(signal_series(series));
    figures.attempt([&] { plot::render(signal, dir, "signal_alarms_" + name); });

    figures.attempt([&] {
      monitor::plot_scores(track, fmt::format("{} score over time ({})", name, first),
                           name == "bp_network"
                               ? "network output (0 stable, 1 chatter onset)"
                               : "|x_at_max_density - mean| / |x_max - mean| (5-22)",
                           dir, "scores_" + name);
    });
  }
  if (!snapshots.empty())
    figures.attempt([&] {
      monitor::plot_density_snapshots(
          snapshots, fmt::format("{}: RBF amplitude densities, stable vs chatter", series.name),
          series.name, dir, "density_snapshots");
    });
}

}  // namespace

SampledSeries monitor_input_signal(const Json& input) {
  // The column of the run's parsed table itself, kept alive by an aliasing pointer: a copy would
  // cost 8 bytes per sample beside the table (and the file's bytes) the run keeps anyway.
  const std::shared_ptr<const DataTable> table =
      read_shared_data_table(input.at("file").get<std::string>());
  SampledSeries s;
  s.share_samples(std::shared_ptr<const std::vector<double>>(
      table, &table->column(input.at("column").get<std::string>())));
  s.sample_interval = 1.0 / input.at("sample_rate_hz").get<double>();
  s.sample_unit = "s";
  s.name = input.at("column").get<std::string>();
  return s;
}

PluginInfo ChatterMonitor::info() {
  return plugin_info("chatter_monitor", "C1, C2, C3",
                     monitor_specs(),
                     Json::object(),
                     "chatter onset monitoring of one signal (window features, 3-4-1 network, RBF amplitude "
                     "density): alarm times, scores, training and test results");
}

void ChatterMonitor::validate(Json& document, const SourceMap& sources) const {
  validate_input(document, sources);

  if (!document.contains("monitor") || !document["monitor"].is_object())
    throw InputError(fmt::format(
        "{}: missing table [monitor]: enable detectors with [monitor.bp_network] and/or "
        "[monitor.rbf_density]",
        sources.locate("monitor").str()));
  Json monitor = document["monitor"];
  Json own = Json::object();
  Json validated_detectors = Json::object();
  for (auto& [key, value] : monitor.items()) {
    const bool detector = std::find(std::begin(detector_names), std::end(detector_names), key) !=
                          std::end(detector_names);
    if (!detector) {
      const auto specs = monitor_specs();
      if (std::none_of(specs.begin(), specs.end(), [&](const ParamSpec& s) { return s.key == key; })) {
        std::vector<std::string> valid(std::begin(detector_names), std::end(detector_names));
        for (const ParamSpec& spec : specs) valid.push_back(spec.key);
        throw InputError(fmt::format("{}: unknown key 'monitor.{}' (valid: {})",
                                     sources.locate("monitor." + key).str(), key,
                                     fmt::join(valid, ", ")));
      }
      own[key] = value;
      continue;
    }
    if (!value.is_object())
      throw InputError(fmt::format("{}: monitor.{} = {}: expected a table [monitor.{}]",
                                   sources.locate("monitor." + key).str(), key, value.dump(), key));
    validated_detectors[key] = validate_params(value, detector_entry(key).info.params,
                                               "monitor." + key, sources);
  }
  own = validate_params(own, monitor_specs(), "monitor", sources);
  if (validated_detectors.empty())
    throw InputError(fmt::format(
        "{}: [monitor] enables no detector: add [monitor.bp_network] (with stable_s and onset_s, "
        "or weights_file) and/or [monitor.rbf_density]",
        sources.locate("monitor").str()));
  if (validated_detectors.contains("bp_network")) {
    Json& bp = validated_detectors["bp_network"];
    if (bp.contains("weights_file") && bp["weights_file"].is_string())
      bp["weights_file"] = kit::resolve_data_file(
                               bp["weights_file"], "monitor.bp_network.weights_file", sources)
                               .string();
  }

  // Data-dependent limits (window longer than the signal, labels outside it): exit 2 now.
  const SampledSeries series = monitor_input_signal(document["input"]);
  for (auto& [name, table] : validated_detectors.items()) {
    try {
      as_detector(*build_detector(name, table)).check(series);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {} (signal: {}, {} samples at {} Hz, {:.6g} s)",
                                   sources.locate("monitor." + name).str(), e.what(),
                                   document["input"]["file"].get<std::string>(),
                                   series.values.size(), series.sample_rate(),
                                   monitor::end_time_s(series)));
    }
  }
  for (double t : monitor_table().read(own).snapshot_times_s.value_or(std::vector<double>{}))
    if (t > monitor::end_time_s(series))
      throw InputError(fmt::format(
          "{}: monitor.snapshot_times_s: {} s is after the end of the signal ({:.6g} s)",
          sources.locate("monitor.snapshot_times_s").str(), t, monitor::end_time_s(series)));
  for (auto& [name, table] : validated_detectors.items()) own[name] = table;
  document["monitor"] = std::move(own);
}

std::vector<std::string> ChatterMonitor::output_columns(const Json& document) const {
  std::vector<std::string> columns;
  for (const auto& name : enabled_detectors(document.at("monitor"))) {
    columns.push_back(name + "_first_alarm_s");
    columns.push_back(name + "_alarm_intervals");
  }
  return columns;
}

namespace {

// One detector's entry in summary.json: alarm times, threshold, parameters, training and test.
Json detector_summary(const monitor::DetectorTrack& track, const Json& parameters) {
  const Json& r = track.result;
  const Json& alarms = r.at("alarms");
  Json entry = {{"first_alarm_s", alarms.at("first_alarm_s")},
                {"first_flag_s", alarms.at("first_flag_s")},
                {"alarm_intervals_s", alarms.at("intervals")},
                {"alarm_open_at_end", alarms.at("alarm_open_at_end")},
                {"threshold", r.at("threshold")},
                {"persistence_windows", r.at("persistence_windows")},
                {"evaluations", track.t_s.size()},
                {"parameters", parameters}};
  for (const char* key : {"training", "test"})
    if (r.contains(key)) entry[key] = r[key];
  return entry;
}

// Density snapshots of a detector with a density state: at monitor.snapshot_times_s when given,
// else the detector's own (first window, first alarm, last window).
std::vector<Json> density_snapshots(const monitor::Detector& detector, const Json& r,
                                    const Json& monitor, const std::string& name,
                                    const SampledSeries& series) {
  const std::optional<std::vector<double>> times = monitor_table().read(monitor).snapshot_times_s;
  if (!times) return r.at("snapshots").get<std::vector<Json>>();
  const std::size_t window = monitor.at(name).at("window_samples").get<std::size_t>();
  std::vector<Json> out;
  for (double t : *times) {
    auto last = static_cast<std::size_t>(std::llround(t * series.sample_rate()));
    out.push_back(detector.snapshot(series, std::clamp(last, window - 1, series.values.size() - 1)));
  }
  return out;
}

// alarms.csv: every evaluation of every detector, in time order, streamed. Each detector's
// evaluations are in time order already, so the file is their merge; at equal times the
// detectors keep their order in `tracks` (the order a stable sort of all rows by time gives).
void write_alarms_csv(const Tracks& tracks, const fs::path& path) {
  struct Cursor {
    const std::string* name;
    const monitor::DetectorTrack* track;
    std::size_t next = 0;
  };
  std::vector<Cursor> cursors;
  for (const auto& [name, track] : tracks) {
    if (!std::is_sorted(track.t_s.begin(), track.t_s.end()))
      throw std::logic_error(fmt::format("alarms.csv: {} evaluations out of time order", name));
    cursors.push_back({&name, &track});
  }
  constexpr std::size_t block_bytes = 1 << 20;  // text handed to the file at a time
  AtomicFileWriter out(path);
  std::string text = "t_s,detector,score,alarm\n";
  for (;;) {
    Cursor* earliest = nullptr;
    for (Cursor& c : cursors)
      if (c.next < c.track->t_s.size() &&
          (!earliest || c.track->t_s[c.next] < earliest->track->t_s[earliest->next]))
        earliest = &c;
    if (!earliest) break;
    const std::size_t k = earliest->next++;
    const monitor::DetectorTrack& t = *earliest->track;
    fmt::format_to(std::back_inserter(text), "{},{},{},{}\n", t.t_s[k], *earliest->name,
                   t.score[k], t.alarm[k] != 0.0 ? 1 : 0);
    if (text.size() >= block_bytes) {
      out.write(text);
      text.clear();
    }
  }
  out.write(text);
  out.commit();
}

// features.csv: C1 features over the network's windows (10 samples unless configured), the
// windows of feature_series(values, window, window, ...) computed as they are written.
void write_features_csv(const SampledSeries& series, const Json& monitor, const fs::path& path) {
  const std::size_t window = monitor.contains("bp_network")
                                 ? monitor.at("bp_network").at("window_samples").get<std::size_t>()
                                 : 10;
  if (series.values.size() < window) return;
  kit::write_csv_streamed(path, {"t_s", "variance", "rho1", "residual_variance"},
                          series.values.size() / window, [&](std::size_t w, std::span<double> cells) {
                            const std::size_t first = w * window;
                            const WindowFeatures f = window_features(series.values.subspan(first, window));
                            cells[0] = static_cast<double>(first + window - 1) * series.sample_interval;
                            cells[1] = f.variance;
                            cells[2] = f.rho1;
                            cells[3] = f.residual_variance;
                          });
}

}  // namespace

std::vector<Json> ChatterMonitor::run_point(const Json& point_document,
                                            const PointContext& context) const {
  const Json& monitor = point_document.at("monitor");
  const SampledSeries series = monitor_input_signal(point_document.at("input"));
  Tracks results;
  std::vector<Json> outputs;
  Json summary = {{"input",
                   {{"file", point_document["input"]["file"]},
                    {"column", series.name},
                    {"sample_rate_hz", series.sample_rate()},
                    {"samples", series.values.size()},
                    {"duration_s", monitor::end_time_s(series)}}},
                  {"detectors", Json::object()}};
  std::vector<Json> snapshots;
  for (const auto& name : enabled_detectors(monitor)) {
    auto analysis = build_detector(name, monitor.at(name));
    // The per-evaluation series as vectors, not JSON arrays: 10^6 evaluations a detector for a
    // signal of 10^7 samples.
    monitor::DetectorTrack track = monitor::detector_track(
        dynamic_cast<const AnalysisWithArrays&>(*analysis).analyse_with_arrays(series, Json::object()));
    const Json& r = track.result;
    const Json& alarms = r.at("alarms");
    outputs.push_back(alarms.at("first_alarm_s"));
    outputs.emplace_back(alarms.at("intervals").size());
    if (r.contains("snapshots"))  // a detector with a density state (rbf_density)
      snapshots = density_snapshots(as_detector(*analysis), r, monitor, name, series);
    summary["detectors"][name] = detector_summary(track, monitor.at(name));
    results.emplace(name, std::move(track));
  }
  if (context.artifact_dir.empty()) return outputs;

  const fs::path& dir = context.artifact_dir;
  if (const auto skipped =
          series_csv_file.skipped(monitor.at("series_csv").get<std::string>(), series.values.size())) {
    summary["series_csv"] = *skipped;
  } else {
    write_alarms_csv(results, dir / "alarms.csv");
    write_features_csv(series, monitor, dir / "features.csv");
  }
  // A network trained here is saved for reuse (monitor.bp_network.weights_file).
  if (results.count("bp_network") && !ParamValues(monitor.at("bp_network")).has("weights_file"))
    write_json_file(dir / "network_weights.json", results.at("bp_network").result.at("weights"));

  if (context.plots) {
    Figures figures;
    plot_point(series, results, snapshots, dir, figures);
    if (!figures.errors.empty()) summary["plot_errors"] = figures.errors;
  }
  write_json_file(dir / "summary.json", summary);
  return outputs;
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::ChatterMonitor);
