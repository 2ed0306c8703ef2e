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

const std::vector<std::string> default_methods{"embedding", "correlation_dimension", "lyapunov"};

// Headline outputs: (results.csv column, method, key in that method's result).
struct Headline {
  const char* column;
  const char* method;
  const char* key;
};
const Headline headlines[] = {
    {"delay_samples", "embedding", "delay_samples"},
    {"embedding_dimension", "embedding", "embedding_dimension"},
    {"correlation_dimension", "correlation_dimension", "correlation_dimension"},
    {"lyapunov_max_per_s", "lyapunov", "lyapunov_max_per_s"},
};

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
                              "samples per second (required unless the file is WAV)");
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
      "dimension, Lyapunov exponents, surrogates (any registered analysis) with summary.json";
  info.models_md_ids = "N1-N4";
  // The [input] table; [analysis] holds `methods` (a list of analysis names, default
  // embedding, correlation_dimension, lyapunov) and one optional table per method.
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
  s.sample_interval = 1.0 / input.at("sample_rate_hz").get<double>();
  s.sample_unit = "s";
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
  if (input["sample_rate_hz"].is_null()) {
    if (!table.sample_rate_hz)
      throw InputError(fmt::format(
          "{}: missing key 'input.sample_rate_hz': {} is not a WAV file, so the sample rate "
          "must be given (samples per second; 1 for a map iterated once per sample)",
          where("input"), file.string()));
    input["sample_rate_hz"] = *table.sample_rate_hz;
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

  // ---- the signal itself: finite, not constant, long enough for every explicit embedding
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
  document["input"] = std::move(input);
  document["analysis"] = std::move(validated);
}

std::vector<std::string> SignalAnalysis::output_columns(const Json& /*document*/) const {
  std::vector<std::string> columns;
  for (const auto& h : headlines) columns.push_back(h.column);
  return columns;
}

Json SignalAnalysis::analyse(const Json& point_document, const fs::path& plot_dir) {
  const Json& input = point_document.at("input");
  const Json& analysis = point_document.at("analysis");
  const SampledSeries series = load_series(input);
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
  summary["input"] = input;
  summary["samples"] = series.values.size();
  for (const auto& h : headlines) {
    if (context.contains(h.method) && context[h.method].contains(h.key))
      summary[h.column] = context[h.method][h.key];
    else
      summary[h.column] = nonlinear::estimate(std::numeric_limits<double>::quiet_NaN(), 0, 0,
                                              "failed",
                                              fmt::format("method '{}' was not run", h.method));
  }
  // The largest exponent has two routes: the divergence methods (`lyapunov`) and the first
  // exponent of `lyapunov_spectrum`. The headline is the divergence estimate unless its quality
  // is worse than the spectrum's (e.g. Kantz and Rosenstein disagree on a short series).
  auto rank = [](const Json& e) {
    const std::string q = e.is_object() ? e.value("quality", "failed") : "failed";
    return q == "good" ? 2 : q == "uncertain" ? 1 : 0;
  };
  if (context.contains("lyapunov_spectrum") &&
      context["lyapunov_spectrum"].contains("lyapunov_max_per_s")) {
    Json alternative = context["lyapunov_spectrum"]["lyapunov_max_per_s"];
    if (rank(alternative) > rank(summary["lyapunov_max_per_s"])) {
      alternative["reason"] = fmt::format(
          "from lyapunov_spectrum (better quality than lyapunov: {}): {}",
          summary["lyapunov_max_per_s"].value("reason", ""), alternative.value("reason", ""));
      summary["lyapunov_max_per_s"] = alternative;
    }
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
  if (!plot_dir.empty()) {
    // Phase portrait x(t) vs x(t + tau): at most 20000 points.
    const Json& delay = summary["delay_samples"]["value"];
    const std::size_t tau = delay.is_number() ? std::size_t(delay.get<double>()) : 1;
    plot::Curves portrait;
    portrait.title = fmt::format("{}: phase portrait (delay {} samples)", series.name, tau);
    portrait.x_label = "x(t) [signal unit]";
    portrait.y_label = fmt::format("x(t + {:.4g} s) [signal unit]", double(tau) * series.sample_interval);
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

std::vector<Json> SignalAnalysis::run_point(const Json& point_document,
                                            const PointContext& context) const {
  const fs::path dir = context.artifact_dir;
  const Json summary = analyse(point_document, context.plots ? dir : fs::path());
  if (!dir.empty()) write_json_file(dir / "summary.json", summary);
  std::vector<Json> out;
  for (const auto& h : headlines) {
    const Json& e = summary[h.column];
    out.push_back(e.is_object() && e.contains("value") ? e["value"] : Json());
  }
  return out;
}

void SignalAnalysis::write_artifacts(const Study& /*study*/, const ResultTable& /*results*/,
                                     const fs::path& /*out_dir*/) const {
  // Every figure belongs to one signal: drawn per point by run_point.
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::SignalAnalysis);
