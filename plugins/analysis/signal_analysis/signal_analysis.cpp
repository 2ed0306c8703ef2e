#include "analysis/signal_analysis/signal_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "analysis/study_support/study_support.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/plot.hpp"
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
bool per_second(const Json& input) { return input.contains("sample_rate_hz") && input["sample_rate_hz"].is_number(); }

ParamSpec input_file_spec() {
  return param_spec("file", ValueKind::string, "",
                    "data file: CSV/whitespace columns or WAV (relative to the study file)");
}

std::vector<ParamSpec> input_specs() {
  ParamSpec column = param_spec(
      "column", ValueKind::string, "",
      "column: header name or 1-based index (\"2\" or 2; absent: the only column)");
  column.optional = true;
  ParamSpec rate = param_spec("sample_rate_hz", ValueKind::real, "Hz",
                              "samples per second (absent: the WAV header's, else time is "
                              "counted in samples and every rate is per sample)");
  rate.min = 0;
  rate.min_exclusive = true;
  rate.optional = true;
  return {input_file_spec(), column, rate};
}

std::string json_list(const std::vector<std::string>& names) {
  return fmt::format("{}", fmt::join(names, ", "));
}

// The analysis plugin `name` built from its validated override table.
std::unique_ptr<Analysis> build(const std::string& name, const Json& params) {
  return analysis_registry().at(name).create(ParamValues(params));
}

}  // namespace

PluginInfo SignalAnalysis::info() {
  PluginInfo info;
  info.name = "signal_analysis";
  info.description =
      "nonlinear analysis of one measured or simulated signal: embedding, correlation "
      "dimension, Lyapunov exponents, surrogates (any registered analysis), a verdict on chaos "
      "gated by the surrogate tests, with summary.json";
  info.models_md_ids = "N1-N4";
  // The [input] table; [analysis] holds `methods` (a list of analysis names, default
  // embedding, correlation_dimension, lyapunov, surrogates) and one optional table per method.
  info.params = input_specs();
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"file", "signal.csv"}, {"column", "x"}, {"sample_rate_hz", 1000.0}};
  return info;
}

SampledSeries SignalAnalysis::load_series(const Json& input) {
  const DataTable table = read_data_table(input.at("file").get<std::string>());
  SampledSeries s;
  const std::string column = input.at("column").get<std::string>();
  s.values = table.column(column);
  if (per_second(input)) {
    s.sample_interval = 1.0 / input.at("sample_rate_hz").get<double>();
    s.sample_unit = "s";
  } else {
    // No sample rate: time is counted in samples and every rate is per sample.
    s.sample_interval = 1.0;
    s.sample_unit = "sample";
  }
  s.name = fmt::format("{} [{}]", fs::path(input.at("file").get<std::string>()).filename().string(),
                       column);
  return s;
}

void SignalAnalysis::validate(Json& document, const SourceMap& sources) const {
  auto where = [&](const std::string& path) { return sources.locate(path).str(); };
  // ---- [input]
  if (!document.contains("input") || !document["input"].is_object())
    throw InputError(fmt::format(
        "{}: missing table [input] (file = \"...\", column = \"...\", sample_rate_hz = ...)",
        where("input")));
  study_support::integer_columns_as_names(document["input"], {"column"});
  Json input = validate_params(document["input"], input_specs(), "input", sources);
  const fs::path file = study_support::resolve_data_file(input["file"], "input.file", sources);
  const DataTable table = study_support::read_table_at(file, "input.file", sources);
  std::string column;
  if (input["column"].is_string()) {
    column = input["column"].get<std::string>();
    try {
      (void)table.column(column);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: input.column = \"{}\": {}", where("input.column"), column,
                                   e.what()));
    }
  } else if (table.names.size() == 1) {
    column = table.names.front();
  } else {
    throw InputError(fmt::format("{}: missing key 'input.column': {} has {} columns ({})",
                                 where("input"), file.string(), table.names.size(),
                                 json_list(table.names)));
  }
  // Without a sample rate (and not a WAV file) time is counted in samples: every rate is then
  // reported per sample (lyapunov_max_per_sample instead of lyapunov_max_per_s).
  if (input["sample_rate_hz"].is_null()) {
    if (table.sample_rate_hz) input["sample_rate_hz"] = *table.sample_rate_hz;
  } else if (table.sample_rate_hz &&
             std::abs(*table.sample_rate_hz - input["sample_rate_hz"].get<double>()) >
                 1e-9 * *table.sample_rate_hz) {
    throw InputError(fmt::format("{}: input.sample_rate_hz = {}: the WAV file says {} Hz",
                                 where("input.sample_rate_hz"),
                                 input["sample_rate_hz"].get<double>(), *table.sample_rate_hz));
  }
  input["file"] = file.string();
  input["column"] = column;

  // ---- [analysis]
  Json analysis = document.contains("analysis") ? document["analysis"] : Json::object();
  if (!analysis.is_object())
    throw InputError(fmt::format("{}: analysis = {}: expected a table [analysis]",
                                 where("analysis"), analysis.dump()));
  std::vector<std::string> methods = default_methods;
  if (analysis.contains("methods")) {
    const Json& m = analysis["methods"];
    if (!m.is_array() || m.empty() ||
        !std::all_of(m.begin(), m.end(), [](const Json& v) { return v.is_string(); }))
      throw InputError(fmt::format(
          "{}: analysis.methods = {}: expected a non-empty list of analysis names, e.g. "
          "[\"embedding\", \"lyapunov\"]",
          where("analysis.methods"), m.dump()));
    methods = m.get<std::vector<std::string>>();
  }
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

  // ---- the signal itself: finite, not constant, long enough for the methods and for every
  // explicit embedding
  const std::vector<double>& values = table.column(column);
  const std::string what = fmt::format("{} column '{}'", file.string(), column);
  int needed_dimension = 2, needed_delay = 1;
  std::size_t needed = nonlinear::minimum_samples(2, 1);
  for (const auto& m : methods) {
    const Json& p = validated[m];
    const ParamValues values_of_method(p);
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
    throw InputError(fmt::format("{}: {}", where("input.column"), e.what()));
  }
  if (values.size() < nonlinear::minimum_series_samples)
    throw InputError(fmt::format(
        "{}: {}: {} samples are too short: the nonlinear analyses need at least {} samples "
        "(delay vectors in up to 10 embedding dimensions, 2000 pairs inside a scaling region, "
        "divergence followed for 30 samples)",
        where("input.column"), what, values.size(), nonlinear::minimum_series_samples));
  document["input"] = std::move(input);
  document["analysis"] = std::move(validated);
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

}  // namespace

Json SignalAnalysis::chaos_verdict(const Json& context) {
  // Evidence, each with the words the verdict gives it.
  const Json none = Json::object();
  const Json& lyapunov = context.contains("lyapunov") ? context["lyapunov"] : none;
  const Json& dimension =
      context.contains("correlation_dimension") ? context["correlation_dimension"] : none;
  const Json& surrogates = context.contains("surrogates") ? context["surrogates"] : none;
  std::vector<std::string> evidence, missing;

  const std::string divergence = lyapunov.value("divergence", "");
  const Json lambda_low = lyapunov.contains("lyapunov_max_per_sample")
                              ? number_at(lyapunov["lyapunov_max_per_sample"], "ci_low")
                              : Json();
  const bool positive_exponent =
      divergence == "exponential" && lambda_low.is_number() && lambda_low.get<double>() > 0;
  if (!context.contains("lyapunov"))
    missing.push_back("no largest exponent (method 'lyapunov' not run)");
  else if (positive_exponent)
    evidence.push_back("a positive largest exponent whose interval excludes zero");
  else if (divergence == "none")
    evidence.push_back("no exponential divergence of neighbouring trajectories");
  else
    missing.push_back(divergence == "exponential"
                          ? "the exponent's interval does not exclude zero"
                          : "the divergence curves show no exponential divergence common to "
                            "dimensions and neighbourhood sizes");

  const Json d2 = dimension.contains("correlation_dimension")
                      ? number_at(dimension["correlation_dimension"], "value")
                      : Json();
  const bool saturating = d2.is_number();
  if (!context.contains("correlation_dimension"))
    missing.push_back("no correlation dimension (method 'correlation_dimension' not run)");
  else if (saturating)
    evidence.push_back(fmt::format("a saturating correlation dimension ({:.3g})",
                                   d2.get<double>()));
  else
    missing.push_back("no saturating correlation dimension");

  const bool surrogates_run = context.contains("surrogates");
  const bool rejected_exponent = surrogates.value("rejected_for_exponent", false);
  const bool rejected_dimension = surrogates.value("rejected_for_dimension", false);
  const bool rejected_prediction = surrogates.value("rejected_for_prediction", false);
  if (!surrogates_run) {
    missing.push_back("no surrogate test (method 'surrogates' not run)");
  } else {
    if (rejected_exponent && rejected_dimension)
      evidence.push_back("the surrogate tests reject a linear stochastic process for the "
                         "exponent and the dimension");
    else
      missing.push_back(fmt::format(
          "the surrogate tests do not reject a linear stochastic process for the {}",
          !rejected_exponent && !rejected_dimension ? "exponent nor the dimension"
          : !rejected_exponent                      ? "exponent"
                                                    : "dimension"));
  }

  std::string verdict;
  std::string summary;
  const bool any_rejected = rejected_exponent || rejected_dimension || rejected_prediction;
  if (positive_exponent && saturating && surrogates_run && rejected_exponent &&
      rejected_dimension) {
    verdict = "deterministic chaos";
    summary = "every test for deterministic chaos passed";
  } else if (surrogates_run && !any_rejected) {
    verdict = "linear stochastic";
    summary = "no statistic distinguishes the data from linear stochastic surrogates";
  } else if (divergence == "none") {
    verdict = "periodic or quasi-periodic";
    summary = "neighbouring trajectories do not separate exponentially";
  } else if (any_rejected && (!saturating || !positive_exponent) &&
             (dimension.value("noise_level", Json()).is_number() ||
              lyapunov.value("noise_dominated_radius", Json()).is_number() ||
              lyapunov.value("noise_radius", Json()).is_number())) {
    verdict = "noise-dominated";
    summary = "nonlinear structure that noise hides at the scales a dimension or exponent "
              "needs";
  } else {
    verdict = "not determined";
    summary = "the evidence for chaos is incomplete";
  }
  return Json{{"verdict", verdict},
              {"reason", fmt::format("{}: {}{}", summary,
                                     evidence.empty() ? std::string("no evidence for chaos")
                                                      : fmt::format("{}", fmt::join(evidence, "; ")),
                                     missing.empty() ? std::string()
                                                     : fmt::format("; missing: {}",
                                                                   fmt::join(missing, "; ")))},
              {"positive_exponent", positive_exponent},
              {"saturating_dimension", saturating},
              {"surrogates_reject_for_exponent", rejected_exponent},
              {"surrogates_reject_for_dimension", rejected_dimension}};
}

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
    // Phase portrait x(t) vs x(t + tau): at most 20000 points.
    const Json& delay = summary["delay_samples"]["value"];
    const std::size_t tau = delay.is_number() ? std::size_t(delay.get<double>()) : 1;
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
    try {
      plot::render(portrait, plot_dir, "phase_portrait");
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

void SignalAnalysis::write_artifacts(const Study& /*study*/, const ResultTable& /*results*/,
                                     const fs::path& /*out_dir*/) const {
  // Every figure belongs to one signal: drawn per point by run_point.
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::SignalAnalysis);
