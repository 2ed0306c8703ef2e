#include "analysis/surrogates/surrogates.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "shared/nonlinear/correlation_sums.hpp"
#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/divergence.hpp"
#include "shared/nonlinear/kantz_scan.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "shared/nonlinear/ordered_sum.hpp"
#include "chatterlab/fft.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

std::vector<double> iaaft_surrogate(std::span<const double> x, std::uint64_t seed,
                                    int max_iterations) {
  const std::size_t n = x.size();
  std::vector<double> sorted(x.begin(), x.end());
  std::sort(sorted.begin(), sorted.end());
  RealFft fft(n);
  const auto spectrum = fft.forward(x);
  std::vector<double> amplitude(spectrum.size());
  for (std::size_t k = 0; k < spectrum.size(); ++k) amplitude[k] = std::abs(spectrum[k]);
  std::vector<double> s(x.begin(), x.end());
  std::mt19937_64 rng(seed);
  std::shuffle(s.begin(), s.end(), rng);
  std::vector<std::uint32_t> order(n), previous;
  // (value, index) pairs sorted directly: an index sort through a comparator that loads the
  // values was most of a surrogate's cost.
  std::vector<std::pair<double, std::uint32_t>> keyed(n);
  std::vector<std::complex<double>> z(spectrum.size());
  for (int it = 0; it < max_iterations; ++it) {
    fft.forward(s, z);
    for (std::size_t k = 0; k < z.size(); ++k) {
      const double a = std::abs(z[k]);
      z[k] = a > 0 ? z[k] * (amplitude[k] / a) : std::complex<double>(amplitude[k], 0.0);
    }
    fft.inverse(z, s);
    // Rank-order remap onto the original amplitudes.
    for (std::size_t i = 0; i < n; ++i) keyed[i] = {s[i], std::uint32_t(i)};
    std::sort(keyed.begin(), keyed.end());
    std::size_t changed = 0;
    for (std::size_t r = 0; r < n; ++r) {
      changed += previous.empty() || keyed[r].second != previous[r];
      order[r] = keyed[r].second;
      s[order[r]] = sorted[r];
    }
    // Converged when (almost) no rank moves any more: after that the spectrum changes by
    // amounts far below its sampling error.
    if (changed * 1000 <= n) break;
    previous = order;
  }
  return s;
}

std::vector<double> phase_randomised_surrogate(std::span<const double> x, std::uint64_t seed) {
  const std::size_t n = x.size();
  RealFft fft(n);
  auto spectrum = fft.forward(x);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2 * std::numbers::pi);
  for (std::size_t k = 1; k < spectrum.size(); ++k) {
    if (n % 2 == 0 && k == spectrum.size() - 1) continue;  // Nyquist term: real
    spectrum[k] = std::polar(std::abs(spectrum[k]), phase(rng));
  }
  return fft.inverse(spectrum);
}

double prediction_error(std::span<const double> x, int dimension, int delay,
                        std::size_t theiler, std::size_t neighbours, std::size_t references) {
  const std::size_t window = std::size_t(dimension - 1) * std::size_t(delay);
  // Vectors whose next sample exists.
  const std::size_t count = nonlinear::vector_count(x.size() - 1, dimension, delay);
  const nonlinear::Embedding e(x, dimension, delay, count);
  const nonlinear::NeighbourSearch search(e);
  references = std::min(references, count);
  // Summed in fixed blocks of references (ordered_sum.hpp): the same error whatever the
  // thread count.
  struct ErrorSums {
    double squared_error = 0, used = 0;
    ErrorSums& operator+=(const ErrorSums& o) {
      squared_error += o.squared_error;
      used += o.used;
      return *this;
    }
  };
  constexpr std::size_t reference_block = 64;
  const ErrorSums sums = nonlinear::ordered_block_sum<ErrorSums>(
      references, reference_block, [&](std::size_t r, ErrorSums& s) {
        const std::size_t i = std::size_t(double(r) * double(count) / double(references));
        const auto nn = search.nearest(i, neighbours, theiler, count);
        if (nn.empty()) return;
        double prediction = 0;
        for (const auto& m : nn) prediction += x[m.index + window + 1];
        prediction /= double(nn.size());
        const double err = x[i + window + 1] - prediction;
        s.squared_error += err * err;
        s.used += 1;
      });
  return std::sqrt(sums.squared_error / sums.used) / nonlinear::standard_deviation(x);
}

double time_reversal_asymmetry(std::span<const double> x, int delay) {
  const auto tau = std::size_t(delay);
  double s2 = 0, s3 = 0;
  for (std::size_t i = 0; i + tau < x.size(); ++i) {
    const double d = x[i + tau] - x[i];
    s2 += d * d;
    s3 += d * d * d;
  }
  const double n = double(x.size() - tau);
  return (s3 / n) / std::pow(s2 / n, 1.5);
}

namespace {

// IAAFT iterations per surrogate: the relative mismatch of the Fourier amplitudes is 0.1 % after
// 30 and 0.06 % after 200 (Henon, Lorenz, AR(2), 8192 samples), far below the sampling error.
constexpr int iaaft_iterations = 30;
constexpr std::size_t divergence_references = 1000;  // Kantz curve of each series
constexpr std::size_t divergence_neighbour = 10;     // eps: median distance to this neighbour
const char* const kind_names[] = {"iaaft", "phase_randomised"};

// The statistics of one series, with the scales fixed by the data.
struct Scales {
  int dimension = 2, delay = 1;     // embedding of the statistics
  std::size_t theiler = 0;
  int correlation_dimension = 2;    // dimension of the correlation-sum statistic
  double log_r_low = 0, log_r_high = 0;  // ln r where the data's C = 1e-3 and 1e-2
  double eps = 0;                   // Kantz neighbourhood size (Euclidean)
  std::size_t steps = 0, stride = 1, half_rise_step = 0;
};

// Correlation sums up to r (absolute): every pair closer than r (a little beyond, for the last
// bin) when r is below 5 % of the range (few pairs at C = 1e-2, exact counts); else, where the
// pairs within r are many (high-dimensional, noise-like data), sampled references.
CorrelationSums sums_up_to(std::span<const double> x, const Scales& s, double log_r) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double cut = 1.2 * std::exp(log_r) / (*hi - *lo);
  return cut <= 0.05
             ? correlation_sums_within(x, s.correlation_dimension, s.delay, s.theiler, cut)
             : correlation_sums(x, s.correlation_dimension, s.delay, s.theiler, 500);
}

// Slope of ln C over [log_r_low, log_r_high] in the statistic's dimension (NaN if unresolved).
double dimension_statistic(std::span<const double> x, const Scales& s) {
  const auto sums = sums_up_to(x, s, s.log_r_high);
  const auto log_c = sums.log_correlation(s.correlation_dimension);
  const auto log_r = sums.log_radii();
  std::vector<double> rx, cy;
  for (std::size_t k = 0; k < log_c.size(); ++k)
    if (std::isfinite(log_c[k]) && log_r[k] >= s.log_r_low && log_r[k] <= s.log_r_high) {
      rx.push_back(log_r[k]);
      cy.push_back(log_c[k]);
    }
  return rx.size() >= 3 ? nonlinear::fit_line(rx, cy, 0, rx.size()).slope : std::nan("");
}

// Kantz's divergence at eps from k = 0 to the data's half-rise step.
std::vector<double> divergence_curve(std::span<const double> x, const Scales& s) {
  return kantz_scan(x, s.dimension, s.dimension, s.delay, s.theiler, s.steps,
                    divergence_references, {s.eps}, s.stride)
      .curve(0, s.dimension);
}
double divergence_statistic(std::span<const double> x, const Scales& s) {
  const auto y = divergence_curve(x, s);
  return y[s.half_rise_step] - y[0];
}

// Rank of the data among data + surrogates (1: below all) and whether that rejects the null.
struct RankTest {
  double data = 0;
  std::vector<std::vector<double>> surrogates;  // per kind
  std::vector<std::size_t> rank;                // per kind
  bool rejected(std::size_t kind) const { return rank[kind] == 1; }
};
void rank(RankTest& t) {
  t.rank.clear();
  for (const auto& values : t.surrogates)
    t.rank.push_back(1 + std::size_t(std::count_if(values.begin(), values.end(), [&](double v) {
                       return !(v > t.data);  // NaN counts against rejection
                     })));
}

}  // namespace

template <>
PluginInfo Surrogates::info() {
  using nonlinear::numeric_spec;
  ParamSpec kinds = param_spec("kinds", ValueKind::string, "",
                               "surrogate kinds: \"iaaft\", \"phase_randomised\" or \"both\"");
  kinds.choices = {"iaaft", "phase_randomised", "both"};
  kinds.default_value = "both";
  return plugin_info("surrogates", "N4",
                     {
                         nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
                         numeric_spec("surrogates", ValueKind::integer, "1",
                                      "surrogates of each kind (19: one-sided tests at significance 1/20)", 19, 4,
                                      999),
                         kinds,
                         numeric_spec("max_samples", ValueKind::integer, "samples",
                                      "the tests use at most this many samples from the start of the series (the "
                                      "IAAFT iterations cost a Fourier transform of the series each)",
                                      8192, 256),
                         numeric_spec("neighbours", ValueKind::integer, "1",
                                      "neighbours of the locally constant predictor", 5, 1),
                         numeric_spec("max_reference_points", ValueKind::integer, "1",
                                      "predictions per series at most (evenly spread)", 2000, 20),
                         nonlinear::seed_spec()},
                     {{"surrogates", 4}, {"max_reference_points", 100}},
                     "surrogate tests for determinism (IAAFT and phase-randomised): one-sided rank tests of "
                     "the prediction error, the divergence of neighbours (for the exponent) and the "
                     "correlation-sum slope (for the dimension); time-reversal asymmetry",
                     ThreadSafety::shareable);
}

namespace {

// Surrogate kinds (indices into kind_names) of the `kinds` parameter.
std::vector<std::size_t> surrogate_kinds(const std::string& kinds) {
  std::vector<std::size_t> out;
  if (kinds != "phase_randomised") out.push_back(0);
  if (kinds != "iaaft") out.push_back(1);
  return out;
}

// The correlation-sum statistic's scales: the data's radii where C = 1e-3 and 1e-2 (sampled
// references, all radii), in the saturation dimension of `correlation_dimension` (else m), as
// far as the series holds vectors.
void set_dimension_scales(std::span<const double> x, const Json& context, Scales& s) {
  const auto saturation =
      nonlinear::context_value(context, "correlation_dimension", "saturation_dimension");
  s.correlation_dimension =
      std::max(2, saturation && *saturation > 0 ? int(*saturation) : s.dimension);
  while (s.correlation_dimension > 1 &&
         x.size() < nonlinear::minimum_samples(s.correlation_dimension, s.delay))
    --s.correlation_dimension;
  const auto sums = correlation_sums(x, s.correlation_dimension, s.delay, s.theiler, 1000);
  const auto log_c = sums.log_correlation(s.correlation_dimension);
  const auto log_r = sums.log_radii();
  s.log_r_low = s.log_r_high = std::nan("");
  for (std::size_t b = 0; b < log_c.size(); ++b) {
    if (!std::isfinite(s.log_r_low) && log_c[b] >= std::log(1e-3)) s.log_r_low = log_r[b];
    if (!std::isfinite(s.log_r_high) && log_c[b] >= std::log(1e-2)) s.log_r_high = log_r[b];
  }
}

// The divergence statistic's scales: eps = the median distance to the divergence_neighbour-th
// neighbour (300 references), the horizon and curve stride.
void set_divergence_scales(std::span<const double> x, Scales& s) {
  const nonlinear::Embedding e(x, s.dimension, s.delay);
  const nonlinear::NeighbourSearch search(e);
  std::vector<double> d;
  for (std::size_t r = 0; r < 300; ++r) {
    const auto nn = search.nearest(r * e.size() / 300, divergence_neighbour, s.theiler, e.size());
    if (nn.size() == divergence_neighbour) d.push_back(nn.back().distance);
  }
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  s.eps = d.empty() ? 0.0 : d[d.size() / 2];
  const std::size_t window = std::size_t(s.dimension - 1) * std::size_t(s.delay);
  const std::size_t horizon =
      std::min<std::size_t>(std::max(30, 100 * s.delay), (x.size() - window) / 4);
  s.stride = curve_stride(s.delay, horizon, 64);
  s.steps = horizon / s.stride + 1;
}

// The data's half-rise step of its divergence curve and the statistic there; false when the
// curve does not rise (no statistic).
bool set_half_rise(std::span<const double> x, Scales& s, double& statistic) {
  if (!(s.eps > 0)) return false;
  const auto y = divergence_curve(x, s);
  const double top = *std::max_element(y.begin(), y.end());
  s.half_rise_step = 0;
  for (std::size_t q = 1; q < y.size() && s.half_rise_step == 0; ++q)
    if (std::isfinite(y[q]) && y[q] >= y[0] + 0.5 * (top - y[0])) s.half_rise_step = q;
  if (!std::isfinite(y[0]) || s.half_rise_step == 0) return false;
  statistic = y[s.half_rise_step] - y[0];
  return true;
}

// The three rank tests with their statistics on the data and on every surrogate.
struct Tests {
  std::vector<std::size_t> kinds;
  std::size_t count = 0;  // surrogates per kind
  RankTest prediction, divergence, dimension;
  bool divergence_ok = false, dimension_ok = false;
  double asymmetry_data = 0;
  std::vector<double> asymmetry;  // of the IAAFT surrogates
  bool all_reject(const RankTest& t, bool ok) const {
    if (!ok) return false;
    for (std::size_t q = 0; q < kinds.size(); ++q)
      if (!t.rejected(q)) return false;
    return true;
  }
};

// Every statistic of the data and of `count` surrogates of each kind.
template <class PredictionError>
void run_tests(std::span<const double> x, const Scales& s, std::uint64_t seed,
               const PredictionError& error_of, Tests& t) {
  t.prediction.data = error_of(x);
  if (t.dimension_ok) t.dimension.data = dimension_statistic(x, s);
  t.asymmetry_data = time_reversal_asymmetry(x, s.delay);
  for (RankTest* r : {&t.prediction, &t.divergence, &t.dimension})
    r->surrogates.assign(t.kinds.size(), {});
  for (std::size_t q = 0; q < t.kinds.size(); ++q)
    for (std::size_t n = 0; n < t.count; ++n) {
      const std::uint64_t surrogate_seed = seed + 1000 * t.kinds[q] + n;
      const auto v = t.kinds[q] == 0 ? iaaft_surrogate(x, surrogate_seed, iaaft_iterations)
                                     : phase_randomised_surrogate(x, surrogate_seed);
      t.prediction.surrogates[q].push_back(error_of(v));
      t.divergence.surrogates[q].push_back(t.divergence_ok ? divergence_statistic(v, s)
                                                           : std::nan(""));
      t.dimension.surrogates[q].push_back(t.dimension_ok ? dimension_statistic(v, s)
                                                         : std::nan(""));
      if (t.kinds[q] == 0) t.asymmetry.push_back(time_reversal_asymmetry(v, s.delay));
    }
  for (RankTest* r : {&t.prediction, &t.divergence, &t.dimension}) rank(*r);
}

Json test_json(const Tests& tests, const RankTest& t, bool ok, const char* what) {
  Json j;
  j["data"] = ok && std::isfinite(t.data) ? Json(t.data) : Json();
  j["computed"] = ok;
  j["what"] = what;
  for (std::size_t q = 0; q < tests.kinds.size(); ++q) {
    Json values = Json::array();
    for (double v : t.surrogates[q]) values.push_back(std::isfinite(v) ? Json(v) : Json());
    j[kind_names[tests.kinds[q]]] =
        Json{{"surrogates", values}, {"rank", t.rank[q]}, {"rejected", ok && t.rejected(q)}};
  }
  j["rejected"] = tests.all_reject(t, ok);
  return j;
}

// "prediction error: rejected (iaaft rank 1 of 20, ...); ..." for the reason.
std::string verdicts_text(const Tests& t) {
  std::vector<std::string> verdicts;
  for (const auto& [name, test, ok] :
       {std::tuple{"prediction error", &t.prediction, true},
        std::tuple{"divergence (exponent)", &t.divergence, t.divergence_ok},
        std::tuple{"correlation-sum slope (dimension)", &t.dimension, t.dimension_ok}}) {
    std::vector<std::string> per_kind;
    for (std::size_t q = 0; q < t.kinds.size(); ++q)
      per_kind.push_back(fmt::format("{} rank {} of {}", kind_names[t.kinds[q]], test->rank[q],
                                     t.count + 1));
    verdicts.push_back(fmt::format("{}: {} ({})", name,
                                   !ok                       ? "not computed"
                                   : t.all_reject(*test, ok) ? "rejected"
                                                             : "not rejected",
                                   fmt::join(per_kind, ", ")));
  }
  return fmt::format("{}", fmt::join(verdicts, "; "));
}

Json tests_json(const Tests& t, std::size_t samples_used) {
  Json out;
  out["statistics"] = {
      {"prediction_error", test_json(t, t.prediction, true,
                                     "normalised one-step prediction error (locally constant)")},
      {"divergence", test_json(t, t.divergence, t.divergence_ok,
                               "growth of ln distance of neighbours within eps up to the data's "
                               "half-rise time (Kantz)")},
      {"dimension", test_json(t, t.dimension, t.dimension_ok,
                              "slope of ln C(r) where the data's C is 1e-3..1e-2")}};
  out["kinds"] = Json::array();
  for (std::size_t q : t.kinds) out["kinds"].push_back(kind_names[q]);
  out["samples_used"] = samples_used;
  const double significance = 1.0 / double(t.count + 1);
  out["significance"] = significance;
  out["rejected_for_prediction"] = t.all_reject(t.prediction, true);
  out["rejected_for_exponent"] = t.all_reject(t.divergence, t.divergence_ok);
  out["rejected_for_dimension"] = t.all_reject(t.dimension, t.dimension_ok);
  // Compatibility with the single-test summary: the prediction error under the first kind.
  const auto& first = t.prediction.surrogates[0];
  const auto [lo, hi] = std::minmax_element(first.begin(), first.end());
  out["prediction_error"] = nonlinear::estimate(
      t.prediction.data, *lo, *hi, "good",
      fmt::format("surrogate range shown as interval; linear stochastic null at significance "
                  "{:.3g} per test (one-sided, data below every surrogate): {}",
                  significance, verdicts_text(t)));
  out["null_rejected"] = t.prediction.rejected(0);
  out["rank"] = t.prediction.rank[0];
  out["time_reversal_asymmetry"] = t.asymmetry_data;
  out["surrogate_time_reversal_asymmetry"] = t.asymmetry;
  const std::size_t tr_extreme =
      std::size_t(std::count_if(t.asymmetry.begin(), t.asymmetry.end(), [&](double a) {
        return std::abs(a) >= std::abs(t.asymmetry_data);
      }));
  out["time_reversal_rank"] = tr_extreme + 1;  // 1: more asymmetric than every surrogate
  return out;
}

}  // namespace

template <>
Json Surrogates::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto max_samples = std::size_t(params_.integer("max_samples"));
  const std::span<const double> x = series.values.first(std::min(max_samples, series.values.size()));
  // Scales of the statistics, fixed by the data.
  Scales s;
  s.dimension = embedding.dimension;
  s.delay = embedding.delay;
  s.theiler = embedding.theiler;
  set_dimension_scales(x, context, s);
  set_divergence_scales(x, s);
  Tests tests;
  tests.kinds = surrogate_kinds(params_.string("kinds"));
  tests.count = std::size_t(params_.integer("surrogates"));
  tests.divergence_ok = set_half_rise(x, s, tests.divergence.data);
  tests.dimension_ok = std::isfinite(s.log_r_low) && std::isfinite(s.log_r_high) &&
                       s.log_r_high > s.log_r_low;
  const auto k = std::size_t(params_.integer("neighbours"));
  const auto refs = std::size_t(params_.integer("max_reference_points"));
  auto error_of = [&](std::span<const double> v) {
    return prediction_error(v, s.dimension, s.delay, s.theiler, k, refs);
  };
  run_tests(x, s, std::uint64_t(params_.integer("seed")), error_of, tests);
  Json out = tests_json(tests, x.size());
  add_embedding_fields(out, embedding);
  return out;
}

template <>
void Surrogates::plot(const Json& result, const SampledSeries& series,
                      const std::filesystem::path& out_dir) const {
  const std::string title = series.name.empty() ? std::string("series") : series.name;
  const struct {
    const char* key;
    const char* stem;
    const char* what;
    const char* label;
  } panels[] = {
      {"prediction_error", "surrogates", "prediction error",
       "normalised one-step prediction error"},
      {"divergence", "surrogates_divergence", "divergence (test for the exponent)",
       "growth of < ln distance > to the half-rise time"},
      {"dimension", "surrogates_dimension", "correlation-sum slope (test for the dimension)",
       "slope of ln C(r) where C = 1e-3..1e-2"}};
  for (const auto& p : panels) {
    const Json& t = result["statistics"][p.key];
    if (!t["computed"].get<bool>() || !t["data"].is_number()) continue;
    plot::Curves c;
    c.title = fmt::format("{}: {}, data and surrogates", title, p.what);
    c.x_label = "surrogate number";
    c.integer_x = true;
    c.y_label = p.label;
    for (const Json& kind : result["kinds"]) {
      const std::string name = kind.get<std::string>();
      plot::Series s{name == "iaaft" ? "IAAFT surrogates" : "phase-randomised surrogates",
                     {}, {}, "impulses"};
      const Json& values = t[name]["surrogates"];
      for (std::size_t i = 0; i < values.size(); ++i)
        if (values[i].is_number()) {
          s.x.push_back(double(i + 1) + (name == "iaaft" ? 0.0 : 0.3));
          s.y.push_back(values[i].get<double>());
        }
      c.series.push_back(s);
    }
    c.reference_y = t["data"].get<double>();
    c.reference_label = "data";
    plot::render(c, out_dir, p.stem);
  }
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::Surrogates);
