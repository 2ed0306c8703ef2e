#include "analysis/surrogates/surrogates.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "analysis/embedding/embedding.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/fft.hpp"
#include "chatterlab/plot.hpp"

namespace chatterlab {

std::vector<double> iaaft_surrogate(const std::vector<double>& x, std::uint64_t seed,
                                    int max_iterations) {
  const std::size_t n = x.size();
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  RealFft fft(n);
  const auto spectrum = fft.forward(x);
  std::vector<double> amplitude(spectrum.size());
  for (std::size_t k = 0; k < spectrum.size(); ++k) amplitude[k] = std::abs(spectrum[k]);
  std::vector<double> s = x;
  std::mt19937_64 rng(seed);
  std::shuffle(s.begin(), s.end(), rng);
  std::vector<std::size_t> order(n), previous;
  std::vector<std::complex<double>> z(spectrum.size());
  for (int it = 0; it < max_iterations; ++it) {
    fft.forward(s, z);
    for (std::size_t k = 0; k < z.size(); ++k) {
      const double a = std::abs(z[k]);
      z[k] = a > 0 ? z[k] * (amplitude[k] / a) : std::complex<double>(amplitude[k], 0.0);
    }
    fft.inverse(z, s);
    // Rank-order remap onto the original amplitudes.
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return s[a] < s[b]; });
    for (std::size_t r = 0; r < n; ++r) s[order[r]] = sorted[r];
    if (order == previous) break;
    previous = order;
  }
  return s;
}

double prediction_error(const std::vector<double>& x, int dimension, int delay,
                        std::size_t theiler, std::size_t neighbours, std::size_t references) {
  const std::size_t window = std::size_t(dimension - 1) * std::size_t(delay);
  // Vectors whose next sample exists.
  const std::size_t count = nonlinear::vector_count(x.size() - 1, dimension, delay);
  const nonlinear::Embedding e(x, dimension, delay, count);
  const nonlinear::NeighbourSearch search(e);
  references = std::min(references, count);
  double sse = 0, used = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : sse, used)
  for (std::size_t r = 0; r < references; ++r) {
    const std::size_t i = std::size_t(double(r) * double(count) / double(references));
    const auto nn = search.nearest(i, neighbours, theiler, count);
    if (nn.empty()) continue;
    double prediction = 0;
    for (const auto& m : nn) prediction += x[m.index + window + 1];
    prediction /= double(nn.size());
    const double err = x[i + window + 1] - prediction;
    sse += err * err;
    used += 1;
  }
  return std::sqrt(sse / used) / nonlinear::standard_deviation(x);
}

double time_reversal_asymmetry(const std::vector<double>& x, int delay) {
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

PluginInfo Surrogates::info() {
  PluginInfo info;
  info.name = "surrogates";
  info.description =
      "IAAFT surrogate test for determinism: nonlinear prediction error rank test (significance "
      "1/(surrogates+1)), time-reversal asymmetry";
  info.models_md_ids = "N4";
  using nonlinear::numeric_spec;
  info.params = {
      nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
      numeric_spec("surrogates", ValueKind::integer, "1",
                   "number of IAAFT surrogates (19: one-sided test at 5 %)", 19, 4, 999),
      numeric_spec("neighbours", ValueKind::integer, "1",
                   "neighbours of the locally constant predictor", 5, 1),
      numeric_spec("max_reference_points", ValueKind::integer, "1",
                   "predictions per series at most (evenly spread)", 4000, 20),
      nonlinear::seed_spec()};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"surrogates", 4}, {"max_reference_points", 100}};
  return info;
}

Json Surrogates::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const auto& x = series.values;
  const auto k = std::size_t(params_.integer("neighbours"));
  const auto refs = std::size_t(params_.integer("max_reference_points"));
  const auto count = std::size_t(params_.integer("surrogates"));
  const auto seed = std::uint64_t(params_.integer("seed"));
  auto error_of = [&](const std::vector<double>& s) {
    return prediction_error(s, embedding.dimension, embedding.delay, embedding.theiler, k, refs);
  };
  const double original = error_of(x);
  const double original_tr = time_reversal_asymmetry(x, embedding.delay);
  std::vector<double> errors(count), asymmetry(count);
  for (std::size_t s = 0; s < count; ++s) {
    const auto surrogate = iaaft_surrogate(x, seed + s);
    errors[s] = error_of(surrogate);
    asymmetry[s] = time_reversal_asymmetry(surrogate, embedding.delay);
  }
  const std::size_t below =
      std::size_t(std::count_if(errors.begin(), errors.end(), [&](double e) { return e <= original; }));
  const bool rejected = below == 0;
  const double significance = 1.0 / double(count + 1);
  const auto [lo, hi] = std::minmax_element(errors.begin(), errors.end());
  Json out;
  out["prediction_error"] = nonlinear::estimate(
      original, *lo, *hi, "good",
      rejected ? fmt::format("smaller than all {} surrogates (range shown as CI): determinism at "
                             "significance {:.3g}",
                             count, significance)
               : fmt::format("{} of {} surrogates predict as well: no evidence of determinism",
                             below, count));
  out["null_rejected"] = rejected;
  out["significance"] = significance;
  out["rank"] = below + 1;  // rank of the data among data + surrogates (1 = smallest error)
  out["surrogate_prediction_errors"] = errors;
  out["time_reversal_asymmetry"] = original_tr;
  out["surrogate_time_reversal_asymmetry"] = asymmetry;
  const std::size_t tr_extreme = std::size_t(std::count_if(
      asymmetry.begin(), asymmetry.end(), [&](double a) { return std::abs(a) >= std::abs(original_tr); }));
  out["time_reversal_rank"] = tr_extreme + 1;  // 1: more asymmetric than every surrogate
  out["delay_samples"] = embedding.delay;
  out["embedding_dimension"] = embedding.dimension;
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  return out;
}

void Surrogates::plot(const Json& result, const SampledSeries& series,
                      const std::filesystem::path& out_dir) const {
  plot::Curves c;
  c.title = fmt::format("{}: prediction error of the data and of IAAFT surrogates",
                        series.name.empty() ? std::string("series") : series.name);
  c.x_label = "surrogate number";
  c.y_label = "normalised one-step prediction error";
  plot::Series s{"surrogates", {}, result["surrogate_prediction_errors"].get<std::vector<double>>(),
                 "impulses"};
  for (std::size_t i = 0; i < s.y.size(); ++i) s.x.push_back(double(i + 1));
  c.series.push_back(s);
  c.reference_y = result["prediction_error"]["value"].get<double>();
  c.reference_label = "data";
  plot::render(c, out_dir, "surrogates");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::Surrogates);
