#include "study_kinds/signal_analysis/signal_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kit/data.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"
#include "chatterlab/signal_io.hpp"

namespace chatterlab {

namespace fs = std::filesystem;

namespace {

// The default methods: everything a chaos claim needs (surrogates gate it).
const std::vector<std::string> default_methods{"embedding", "correlation_dimension", "lyapunov",
                                               "surrogates"};

// Headline estimates: (summary key and results.csv column stem, method, key in its result).
// The largest exponent is per second with a sample rate, per sample without (key decided at run
// time from the series' unit).
struct Headline {
  std::string key;
  const char* method;
  std::string result_key;
  bool with_interval;  // results.csv also gets <key>_ci_low, _ci_high and _quality
};
std::vector<Headline> headlines(bool per_second) {
  const std::string lyapunov = per_second ? "lyapunov_max_per_s" : "lyapunov_max_per_sample";
  return {{"delay_samples", "embedding", "delay_samples", false},
          {"embedding_dimension", "embedding", "embedding_dimension", false},
          {"correlation_dimension", "correlation_dimension", "correlation_dimension", true},
          {lyapunov, "lyapunov", lyapunov, true}};
}
// The [input] table, declared once.
struct SignalInput {
  std::string file;
  std::optional<std::string> column;        // absent: the only column
  std::optional<double> sample_rate_hz;     // absent: time counted in samples (unless WAV)
};

const ParamTable<SignalInput>& input_table() {
  static const ParamTable<SignalInput> table = [] {
    ParamTable<SignalInput> t;
    t.add(&SignalInput::file, "file", "",
          "data file: CSV/whitespace columns or WAV (relative to the study file)")
        .required();
    t.add(&SignalInput::column, "column", "",
          "column: header name or 1-based index (\"2\" or 2; absent: the only column)");
    t.add(&SignalInput::sample_rate_hz, "sample_rate_hz", "Hz",
          "samples per second (absent: the WAV header's, else time is counted in samples and "
          "every rate is per sample)")
        .positive();
    return t;
  }();
  return table;
}

bool per_second(const Json& input) { return input_table().read(input).sample_rate_hz.has_value(); }

std::string json_list(const std::vector<std::string>& names) {
  return fmt::format("{}", fmt::join(names, ", "));
}

// The analysis plugin `name` built from its validated override table.
std::unique_ptr<Analysis> build(const std::string& name, const Json& params) {
  return analysis_registry().at(name).create(ParamValues(params));
}

}  // namespace

PluginInfo SignalAnalysis::info() {
  return plugin_info("signal_analysis", "N1-N4",
                     // The [input] table; [analysis] holds `methods` (a list of analysis names, default
                     // embedding, correlation_dimension, lyapunov, surrogates) and one optional table per method.
                     input_table().specs(),
                     {{"file", "signal.csv"}, {"column", "x"}, {"sample_rate_hz", 1000.0}},
                     "nonlinear analysis of one measured or simulated signal: embedding, correlation "
                     "dimension, Lyapunov exponents, surrogates (any registered analysis), a verdict on chaos "
                     "gated by the surrogate tests, with summary.json");
}

SampledSeries SignalAnalysis::load_series(const Json& input) {
  const SignalInput in = input_table().read(input);
  // validated: column chosen, rate resolved
  const std::shared_ptr<const DataTable> table = read_shared_data_table(in.file);
  SampledSeries s;
  const std::string column = in.column.value();
  // The run's parsed column itself, kept alive by the series (no copy of 10^7 samples).
  s.share_samples(std::shared_ptr<const std::vector<double>>(table, &table->column(column)));
  if (in.sample_rate_hz) {
    s.sample_interval = 1.0 / *in.sample_rate_hz;
    s.sample_unit = "s";
  } else {
    // No sample rate: time is counted in samples and every rate is per sample.
    s.sample_interval = 1.0;
    s.sample_unit = "sample";
  }
  s.name = fmt::format("{} [{}]", fs::path(in.file).filename().string(), column);
  return s;
}

namespace {

// The validated [input] table with the column chosen and the table read.
struct Input {
  Json table;  // the validated [input]
  fs::path file;
  DataTable data;
  std::string column;
};

// The column named in [input], or the only one.
std::string choose_column(const Json& input, const DataTable& table, const fs::path& file,
                          const SourceMap& sources) {
  auto where = [&](const std::string& path) { return sources.locate(path).str(); };
  if (input["column"].is_string()) {
    const std::string column = input["column"].get<std::string>();
    try {
      (void)table.column(column);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: input.column = \"{}\": {}", where("input.column"), column,
                                   e.what()));
    }
    return column;
  }
  if (table.names.size() == 1) return table.names.front();
  throw InputError(fmt::format("{}: missing key 'input.column': {} has {} columns ({})",
                               where("input"), file.string(), table.names.size(),
                               json_list(table.names)));
}

Input validate_input(Json& document, const SourceMap& sources) {
  auto where = [&](const std::string& path) { return sources.locate(path).str(); };
  if (!document.contains("input") || !document["input"].is_object())
    throw InputError(fmt::format(
        "{}: missing table [input] (file = \"...\", column = \"...\", sample_rate_hz = ...)",
        where("input")));
  kit::integer_columns_as_names(document["input"], {"column"});
  Input in;
  in.table = validate_params(document["input"], input_table().specs(), "input", sources);
  in.file = kit::resolve_data_file(in.table["file"], "input.file", sources);
  in.data = kit::read_table_at(in.file, "input.file", sources);
  in.column = choose_column(in.table, in.data, in.file, sources);
  // Without a sample rate (and not a WAV file) time is counted in samples: every rate is then
  // reported per sample (lyapunov_max_per_sample instead of lyapunov_max_per_s).
  Json& rate = in.table["sample_rate_hz"];
  const auto& wav_rate = in.data.sample_rate_hz;
  if (rate.is_null()) {
    if (wav_rate) rate = *wav_rate;
  } else if (wav_rate && std::abs(*wav_rate - rate.get<double>()) > 1e-9 * *wav_rate) {
    throw InputError(fmt::format("{}: input.sample_rate_hz = {}: the WAV file says {} Hz",
                                 where("input.sample_rate_hz"), rate.get<double>(), *wav_rate));
  }
  in.table["file"] = in.file.string();
  in.table["column"] = in.column;
  return in;
}

// analysis.methods (default_methods when absent).
std::vector<std::string> listed_methods(const Json& analysis, const SourceMap& sources) {
  if (!analysis.contains("methods")) return default_methods;
  const Json& m = analysis["methods"];
  if (!m.is_array() || m.empty() ||
      !std::all_of(m.begin(), m.end(), [](const Json& v) { return v.is_string(); }))
    throw InputError(fmt::format(
        "{}: analysis.methods = {}: expected a non-empty list of analysis names, e.g. "
        "[\"embedding\", \"lyapunov\"]",
        sources.locate("analysis.methods").str(), m.dump()));
  return m.get<std::vector<std::string>>();
}

// The [analysis] table: the methods and each one's validated parameter table.
Json validate_analysis(const Json& document, const SourceMap& sources) {
  auto where = [&](const std::string& path) { return sources.locate(path).str(); };
  const Json analysis = document.contains("analysis") ? document["analysis"] : Json::object();
  if (!analysis.is_object())
    throw InputError(fmt::format("{}: analysis = {}: expected a table [analysis]",
                                 where("analysis"), analysis.dump()));
  const std::vector<std::string> methods = listed_methods(analysis, sources);
  Json validated{{"methods", methods}};
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const auto* entry = analysis_registry().find(methods[i]);
    if (!entry) {
      std::vector<std::string> names;
      for (const auto* e : analysis_registry().sorted()) names.push_back(e->info.name);
      throw InputError(fmt::format("{}: analysis.methods.{} = \"{}\": no such analysis (valid: {})",
                                   where(fmt::format("analysis.methods.{}", i)), i, methods[i],
                                   json_list(names)));
    }
    if (std::count(methods.begin(), methods.end(), methods[i]) > 1)
      throw InputError(fmt::format("{}: analysis.methods: \"{}\" is listed twice",
                                   where("analysis.methods"), methods[i]));
    Json overrides = analysis.contains(methods[i]) ? analysis[methods[i]] : Json::object();
    if (!overrides.is_object())
      throw InputError(fmt::format("{}: analysis.{} = {}: expected a table [analysis.{}] of that "
                                   "analysis's parameters",
                                   where("analysis." + methods[i]), methods[i], overrides.dump(),
                                   methods[i]));
    validated[methods[i]] =
        validate_params(overrides, entry->info.params, "analysis." + methods[i], sources);
  }
  for (const auto& [key, value] : analysis.items())
    if (key != "methods" && !validated.contains(key))
      throw InputError(fmt::format(
          "{}: analysis.{}: not a listed method (methods = [{}]); [analysis.<method>] tables "
          "hold the parameters of listed methods",
          where("analysis." + key), key, json_list(methods)));
  return validated;
}

// An explicit Theiler window W must leave every delay vector at least minimum_vectors candidate
// neighbours (vectors - (2 W + 1)): a wider one excludes every pair a neighbour statistic needs.
void check_theiler_windows(std::size_t samples, const Json& analysis, const std::string& what,
                           const SourceMap& sources) {
  for (const auto& m : analysis["methods"].get<std::vector<std::string>>()) {
    const ParamValues p(analysis[m]);
    const auto theiler = nonlinear::given_integer(p, "theiler_window_samples");
    if (!theiler) continue;
    const int d = int(nonlinear::given_integer(p, "embedding_dimension").value_or(2));
    const int tau = int(nonlinear::given_integer(p, "delay_samples").value_or(1));
    const std::size_t vectors = nonlinear::vector_count(samples, d, tau);
    const std::size_t most =
        vectors > nonlinear::minimum_vectors ? (vectors - nonlinear::minimum_vectors - 1) / 2 : 0;
    if (std::size_t(*theiler) <= most) continue;
    const std::string key = fmt::format("analysis.{}.theiler_window_samples", m);
    throw InputError(fmt::format(
        "{}: {} = {}: too few neighbours: {} has {} delay vectors (dimension {}, delay {}), and "
        "a Theiler window of {} samples leaves fewer than {} candidate neighbours per vector; "
        "at most {} samples",
        sources.locate(key).str(), key, *theiler, what, vectors, d, tau, *theiler,
        nonlinear::minimum_vectors, most));
  }
}

// The signal itself: finite, not constant, long enough for the methods and for every explicit
// embedding, with room for neighbours outside every explicit Theiler window.
void check_signal(const Input& in, const Json& analysis, const SourceMap& sources) {
  const std::string where = sources.locate("input.column").str();
  const std::vector<double>& values = in.data.column(in.column);
  const std::string what = fmt::format("{} column '{}'", in.file.string(), in.column);
  int needed_dimension = 2, needed_delay = 1;
  std::size_t needed = nonlinear::minimum_samples(2, 1);
  for (const auto& m : analysis["methods"].get<std::vector<std::string>>()) {
    const ParamValues values_of_method(analysis[m]);
    const int d = int(nonlinear::given_integer(values_of_method, "embedding_dimension").value_or(2));
    const int tau = int(nonlinear::given_integer(values_of_method, "delay_samples").value_or(1));
    if (nonlinear::minimum_samples(d, tau) > needed) {
      needed = nonlinear::minimum_samples(d, tau);
      needed_dimension = d;
      needed_delay = tau;
    }
  }
  try {
    nonlinear::check_series(values, needed_dimension, needed_delay, what);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", where, e.what()));
  }
  if (values.size() < nonlinear::minimum_series_samples)
    throw InputError(fmt::format(
        "{}: {}: {} samples are too short: the nonlinear analyses need at least {} samples "
        "(delay vectors in up to 10 embedding dimensions, 2000 pairs inside a scaling region, "
        "divergence followed for 30 samples)",
        where, what, values.size(), nonlinear::minimum_series_samples));
  check_theiler_windows(values.size(), analysis, what, sources);
}

}  // namespace

void SignalAnalysis::validate(Json& document, const SourceMap& sources) const {
  Input input = validate_input(document, sources);
  Json analysis = validate_analysis(document, sources);
  check_signal(input, analysis, sources);
  document["input"] = std::move(input.table);
  document["analysis"] = std::move(analysis);
}

std::vector<std::string> SignalAnalysis::output_columns(const Json& document) const {
  std::vector<std::string> columns;
  for (const auto& h : headlines(per_second(document.at("input")))) {
    columns.push_back(h.key);
    if (h.with_interval)
      for (const char* suffix : {"_ci_low", "_ci_high", "_quality"}) columns.push_back(h.key + suffix);
  }
  columns.push_back("verdict");
  return columns;
}

namespace {

// e[key] when e is an object holding a number there, else null (const access to a missing key
// would be undefined).
Json number_at(const Json& e, const char* key) {
  return e.is_object() && e.contains(key) && e[key].is_number() ? e[key] : Json();
}

std::string quality_of(const Json& e) {
  return e.is_object() && e.contains("quality") && e["quality"].is_string()
             ? e["quality"].get<std::string>()
             : "failed";
}

// What the methods' results say about chaos, each piece with the words the verdict gives it.
struct Evidence {
  std::vector<std::string> found, missing;
  std::string divergence;
  bool positive_exponent = false, saturating = false, surrogates_run = false;
  bool rejected_exponent = false, rejected_dimension = false, rejected_prediction = false;
  bool noise = false;  // a D2 noise scale, a Kantz noise floor or noise-dominated scales
};

void exponent_evidence(const Json& context, Evidence& e) {
  if (!context.contains("lyapunov")) {
    e.missing.push_back("no largest exponent (method 'lyapunov' not run)");
    return;
  }
  const Json& lyapunov = context["lyapunov"];
  e.divergence = lyapunov.value("divergence", "");
  const Json lambda_low = lyapunov.contains("lyapunov_max_per_sample")
                              ? number_at(lyapunov["lyapunov_max_per_sample"], "ci_low")
                              : Json();
  e.positive_exponent =
      e.divergence == "exponential" && lambda_low.is_number() && lambda_low.get<double>() > 0;
  e.noise = e.noise || lyapunov.value("noise_dominated_radius", Json()).is_number() ||
            lyapunov.value("noise_radius", Json()).is_number();
  if (e.positive_exponent)
    e.found.push_back("a positive largest exponent whose interval excludes zero");
  else if (e.divergence == "none")
    e.found.push_back("no exponential divergence of neighbouring trajectories");
  else
    e.missing.push_back(e.divergence == "exponential"
                            ? "the exponent's interval does not exclude zero"
                            : "the divergence curves show no exponential divergence common to "
                              "dimensions and neighbourhood sizes");
}

void dimension_evidence(const Json& context, Evidence& e) {
  if (!context.contains("correlation_dimension")) {
    e.missing.push_back("no correlation dimension (method 'correlation_dimension' not run)");
    return;
  }
  const Json& dimension = context["correlation_dimension"];
  const Json d2 = dimension.contains("correlation_dimension")
                      ? number_at(dimension["correlation_dimension"], "value")
                      : Json();
  e.saturating = d2.is_number();
  e.noise = e.noise || dimension.value("noise_level", Json()).is_number();
  if (e.saturating)
    e.found.push_back(fmt::format("a saturating correlation dimension ({:.3g})", d2.get<double>()));
  else
    e.missing.push_back("no saturating correlation dimension");
}

void surrogate_evidence(const Json& context, Evidence& e) {
  e.surrogates_run = context.contains("surrogates");
  if (!e.surrogates_run) {
    e.missing.push_back("no surrogate test (method 'surrogates' not run)");
    return;
  }
  const Json& surrogates = context["surrogates"];
  e.rejected_exponent = surrogates.value("rejected_for_exponent", false);
  e.rejected_dimension = surrogates.value("rejected_for_dimension", false);
  e.rejected_prediction = surrogates.value("rejected_for_prediction", false);
  if (e.rejected_exponent && e.rejected_dimension)
    e.found.push_back("the surrogate tests reject a linear stochastic process for the exponent "
                      "and the dimension");
  else
    e.missing.push_back(fmt::format(
        "the surrogate tests do not reject a linear stochastic process for the {}",
        !e.rejected_exponent && !e.rejected_dimension ? "exponent nor the dimension"
        : !e.rejected_exponent                        ? "exponent"
                                                      : "dimension"));
}

// The verdict and its one-line summary.
std::pair<std::string, std::string> classify(const Evidence& e) {
  const bool any_rejected = e.rejected_exponent || e.rejected_dimension || e.rejected_prediction;
  if (e.positive_exponent && e.saturating && e.surrogates_run && e.rejected_exponent &&
      e.rejected_dimension)
    return {"deterministic chaos", "every test for deterministic chaos passed"};
  if (e.surrogates_run && !any_rejected)
    return {"linear stochastic",
            "no statistic distinguishes the data from linear stochastic surrogates"};
  if (e.divergence == "none")
    return {"periodic or quasi-periodic",
            "neighbouring trajectories do not separate exponentially"};
  if (any_rejected && (!e.saturating || !e.positive_exponent) && e.noise)
    return {"noise-dominated",
            "nonlinear structure that noise hides at the scales a dimension or exponent needs"};
  return {"not determined", "the evidence for chaos is incomplete"};
}

}  // namespace

Json SignalAnalysis::chaos_verdict(const Json& context) {
  Evidence e;
  exponent_evidence(context, e);
  dimension_evidence(context, e);
  surrogate_evidence(context, e);
  const auto [verdict, summary] = classify(e);
  return Json{{"verdict", verdict},
              {"reason", fmt::format("{}: {}{}", summary,
                                     e.found.empty() ? std::string("no evidence for chaos")
                                                     : fmt::format("{}", fmt::join(e.found, "; ")),
                                     e.missing.empty()
                                         ? std::string()
                                         : fmt::format("; missing: {}", fmt::join(e.missing, "; ")))},
              {"positive_exponent", e.positive_exponent},
              {"saturating_dimension", e.saturating},
              {"surrogates_reject_for_exponent", e.rejected_exponent},
              {"surrogates_reject_for_dimension", e.rejected_dimension}};
}

namespace {

// Phase portrait x(t) against x(t + tau): at most 20000 points.
void plot_phase_portrait(const SampledSeries& series, std::size_t tau, const fs::path& plot_dir) {
  plot::Curves portrait;
  portrait.title = fmt::format("{}: phase portrait (delay {} samples)", series.name, tau);
  portrait.x_label = "x(t) [signal unit]";
  portrait.y_label =
      series.sample_unit == "sample"
          ? fmt::format("x(t + {} samples) [signal unit]", tau)
          : fmt::format("x(t + {:.4g} {}) [signal unit]", double(tau) * series.sample_interval,
                        series.sample_unit);
  plot::Series points{"delay-embedded samples", {}, {}, "points"};
  const std::size_t n = series.values.size() > tau ? series.values.size() - tau : 0;
  const std::size_t stride = std::max<std::size_t>(1, n / 20000);
  for (std::size_t i = 0; i < n; i += stride) {
    points.x.push_back(series.values[i]);
    points.y.push_back(series.values[i + tau]);
  }
  portrait.series.push_back(points);
  plot::render(portrait, plot_dir, "phase_portrait");
}

}  // namespace

Json SignalAnalysis::analyse_series(const SampledSeries& series, const Json& analysis,
                                    const fs::path& plot_dir) {
  Json context = Json::object();
  std::vector<std::string> plot_errors;
  for (const auto& method : analysis.at("methods").get<std::vector<std::string>>()) {
    auto plugin = build(method, analysis.at(method));
    Json result;
    try {
      result = plugin->analyse(series, context);
    } catch (const InputError& e) {
      throw PointFailure(fmt::format("{}: {}", method, e.what()));
    }
    if (!plot_dir.empty()) {
      try {
        plugin->plot(result, series, plot_dir);
      } catch (const std::exception& e) {
        plot_errors.push_back(fmt::format("{}: {}", method, e.what()));
      }
    }
    context[method] = std::move(result);
  }
  Json summary;
  summary["samples"] = series.values.size();
  summary["sample_unit"] = series.sample_unit;
  // The headlines come from the method that measures them; the spectrum's largest exponent is a
  // separate estimate (methods.lyapunov_spectrum), never a stand-in for the divergence one.
  for (const auto& h : headlines(series.sample_unit == "s")) {
    if (context.contains(h.method) && context[h.method].contains(h.result_key))
      summary[h.key] = context[h.method][h.result_key];
    else
      summary[h.key] = nonlinear::estimate(std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::quiet_NaN(), "failed",
                                           fmt::format("method '{}' was not run", h.method));
  }
  // Without `embedding`, a later method's own embedding choice is the best headline.
  for (const char* key : {"delay_samples", "embedding_dimension"})
    if (!context.contains("embedding"))
      for (const auto& [name, result] : context.items())
        if (result.contains(key) && result[key].is_number()) {
          const double v = result[key].get<double>();
          summary[key] = nonlinear::estimate(v, v, v, "good",
                                             fmt::format("as used by '{}' ({})", name,
                                                         result.value("embedding_source", "")));
          break;
        }
  summary["verdict"] = chaos_verdict(context);
  if (!plot_dir.empty()) {
    const Json& delay = summary["delay_samples"]["value"];
    try {
      plot_phase_portrait(series, delay.is_number() ? std::size_t(delay.get<double>()) : 1,
                          plot_dir);
    } catch (const std::exception& e) {
      plot_errors.push_back(fmt::format("phase portrait: {}", e.what()));
    }
  }
  summary["methods"] = context;
  if (!plot_errors.empty()) summary["plot_errors"] = plot_errors;
  return summary;
}

Json SignalAnalysis::analyse(const Json& point_document, const fs::path& plot_dir) {
  const Json& input = point_document.at("input");
  Json summary = analyse_series(load_series(input), point_document.at("analysis"), plot_dir);
  summary["input"] = input;
  return summary;
}

std::vector<Json> SignalAnalysis::run_point(const Json& point_document,
                                            const PointContext& context) const {
  const fs::path dir = context.artifact_dir;
  const Json summary = analyse(point_document, context.plots ? dir : fs::path());
  if (!dir.empty()) write_json_file(dir / "summary.json", summary);
  std::vector<Json> out;
  for (const auto& h : headlines(per_second(point_document.at("input")))) {
    const Json& e = summary[h.key];
    auto number = [&](const char* key) { return number_at(e, key); };
    out.push_back(number("value"));
    if (h.with_interval) {
      out.push_back(number("ci_low"));
      out.push_back(number("ci_high"));
      out.push_back(quality_of(e));
    }
  }
  out.push_back(summary["verdict"]["verdict"]);
  return out;
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::SignalAnalysis);
