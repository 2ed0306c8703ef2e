#include "shared/nonlinear/embedding_choice.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "shared/nonlinear/ordered_sum.hpp"
#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace {

using nonlinear::Embedding;
using nonlinear::NeighbourSearch;

// Reference vectors used by FNN/Cao at most (evenly spread): fractions to 0.1 % (10 vectors).
constexpr std::size_t max_fnn_references = 10000;
// Reference vectors per block of the ordered FNN/Cao sums (a unit of parallel work).
constexpr std::size_t fnn_reference_block = 64;

// One dimension's false nearest neighbours (Kennel) and Cao's sums over the reference vectors.
struct FnnCaoSums {
  double false_neighbours = 0, valid = 0;  // references with a nearest neighbour
  double e_sum = 0, e_star_sum = 0, cao_count = 0;
  FnnCaoSums& operator+=(const FnnCaoSums& o) {
    false_neighbours += o.false_neighbours;
    valid += o.valid;
    e_sum += o.e_sum;
    e_star_sum += o.e_star_sum;
    cao_count += o.cao_count;
    return *this;
  }
};

std::vector<double> autocorrelation(std::span<const double> x, std::size_t max_lag) {
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / double(x.size());
  double var = 0;
  for (double v : x) var += (v - mean) * (v - mean);
  std::vector<double> acf(max_lag + 1);
  // Lags are independent (O(N) each, up to 1000 of them: threads share them out).
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t lag = 0; lag <= max_lag; ++lag) {
    double s = 0;
    for (std::size_t i = 0; i + lag < x.size(); ++i) s += (x[i] - mean) * (x[i + lag] - mean);
    acf[lag] = s / var;
  }
  return acf;
}

std::vector<double> mutual_information(std::span<const double> x, std::size_t max_lag,
                                       int bins) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double width = (*hi - *lo) / bins;
  // One byte per sample (bins <= 256: the parameter's limit).
  if (bins < 1 || bins > 256)
    throw PointFailure(fmt::format("mutual information: {} bins: needs 1..256", bins));
  std::vector<std::uint8_t> box(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    box[i] = std::uint8_t(std::min(bins - 1, int((x[i] - *lo) / width)));
  const std::size_t b = std::size_t(bins);
  std::vector<double> ami(max_lag + 1);
  // Lags are independent (O(N) each, up to 1000 of them: threads share them out). The joint
  // histogram is counted in integers; the marginals are its row and column sums (exact).
#pragma omp parallel
  {
    std::vector<std::uint64_t> joint(b * b);
    std::vector<double> pa(b), pb(b);
#pragma omp for schedule(dynamic, 4)
    for (std::size_t lag = 0; lag <= max_lag; ++lag) {
      std::fill(joint.begin(), joint.end(), 0);
      const std::size_t n = x.size() - lag;
      for (std::size_t i = 0; i < n; ++i) ++joint[std::size_t(box[i]) * b + box[i + lag]];
      std::fill(pa.begin(), pa.end(), 0.0);
      std::fill(pb.begin(), pb.end(), 0.0);
      for (std::size_t u = 0; u < b; ++u)
        for (std::size_t v = 0; v < b; ++v) {
          pa[u] += double(joint[u * b + v]);
          pb[v] += double(joint[u * b + v]);
        }
      double s = 0;
      for (std::size_t u = 0; u < b; ++u)
        for (std::size_t v = 0; v < b; ++v) {
          const double p = double(joint[u * b + v]);
          if (p > 0) s += p / double(n) * std::log(p * double(n) / (pa[u] * pb[v]));
        }
      ami[lag] = s;
    }
  }
  return ami;
}

}  // namespace

DelayChoice choose_delay(std::span<const double> x, std::size_t max_lag, int bins) {
  DelayChoice out;
  max_lag = std::max<std::size_t>(3, std::min(max_lag, x.size() / 4));
  out.mutual_information = mutual_information(x, max_lag, bins);
  out.autocorrelation = autocorrelation(x, max_lag);
  const auto& ami = out.mutual_information;
  // Histogram estimator bias for independent samples: (bins - 1)^2 / (2 N) nats.
  const double floor = double((bins - 1) * (bins - 1)) / (2.0 * double(x.size()));
  for (std::size_t lag = 1; lag + 2 <= max_lag; ++lag) {
    bool minimum = true;
    for (std::size_t j = lag >= 2 ? lag - 2 : 0; j <= lag + 2; ++j)
      if (j != lag && ami[j] < ami[lag]) minimum = false;
    // A genuine minimum, not the fluctuation of a curve that has already decayed to the bias
    // floor (maps such as Henon's decay in one or two steps: there the ACF rule applies).
    if (minimum && ami[lag] - floor < 0.5 * (ami[0] - floor) && ami[lag] > 2 * floor) {
      out.delay = int(lag);
      out.from_mutual_information = true;
      out.rule = fmt::format("first minimum of the average mutual information ({} bins)", bins);
      return out;
    }
  }
  const auto& acf = out.autocorrelation;
  for (std::size_t lag = 1; lag <= max_lag; ++lag)
    if (acf[lag] <= std::exp(-1.0)) {
      out.delay = int(lag);
      out.rule = fmt::format(
          "no usable minimum of the average mutual information up to lag {}: first lag where the "
          "autocorrelation falls below 1/e",
          max_lag);
      return out;
    }
  out.delay = int(max_lag);
  out.rule = fmt::format(
      "neither an AMI minimum nor an autocorrelation below 1/e up to lag {}: delay set to that "
      "lag (very slowly varying signal: consider downsampling)",
      max_lag);
  return out;
}

DimensionChoice choose_dimension(std::span<const double> x, int delay, int max_dimension,
                                 std::size_t theiler, double distance_ratio,
                                 double fnn_threshold) {
  DimensionChoice out;
  const double sigma = nonlinear::standard_deviation(x);
  constexpr double attractor_ratio = 2.0;  // Kennel's A_tol
  std::vector<double> e(std::size_t(max_dimension) + 2), e_star(std::size_t(max_dimension) + 2);
  for (int d = 1; d <= max_dimension + 1; ++d) {
    // Vectors whose (d+1)-th coordinate exists.
    const std::size_t count = nonlinear::vector_count(x.size(), d + 1, delay);
    if (count < nonlinear::minimum_vectors) break;
    const Embedding embedding(x, d, delay, count);
    const NeighbourSearch search(embedding);
    const std::size_t stride = std::max<std::size_t>(1, count / max_fnn_references);
    const std::size_t extra = std::size_t(d) * std::size_t(delay);
    // Reference vectors i = r * stride, summed in fixed blocks of r (ordered_sum.hpp): the
    // same E1, E2 and FNN fraction whatever the thread count.
    const std::size_t reference_count = (count + stride - 1) / stride;
    const FnnCaoSums sums = nonlinear::ordered_block_sum<FnnCaoSums>(
        reference_count, fnn_reference_block, [&](std::size_t r, FnnCaoSums& s) {
          const std::size_t i = r * stride;
          const auto nn = search.nearest(i, 1, theiler, count);
          if (nn.empty() || !(nn[0].distance > 0)) return;
          const std::size_t j = nn[0].index;
          const double distance = nn[0].distance;
          const double gain = std::abs(x[i + extra] - x[j + extra]);
          s.valid += 1;
          if (gain / distance > distance_ratio ||
              std::sqrt(distance * distance + gain * gain) / sigma > attractor_ratio)
            s.false_neighbours += 1;
          const double rmax = embedding.max_distance(i, j);
          if (rmax > 0) {
            s.e_sum += std::max(rmax, gain) / rmax;
            s.e_star_sum += gain;
            s.cao_count += 1;
          }
        });
    if (sums.valid == 0 || sums.cao_count == 0) break;
    e[std::size_t(d)] = sums.e_sum / sums.cao_count;
    e_star[std::size_t(d)] = sums.e_star_sum / sums.cao_count;
    if (d <= max_dimension) out.fnn_fraction.push_back(sums.false_neighbours / sums.valid);
  }
  for (std::size_t d = 1; d < out.fnn_fraction.size() + 1 && d + 1 < e.size(); ++d) {
    if (e[d + 1] == 0) break;
    out.cao_e1.push_back(e[d + 1] / e[d]);
    out.cao_e2.push_back(e_star[d + 1] / e_star[d]);
  }
  for (std::size_t k = 0; k < out.fnn_fraction.size(); ++k)
    if (out.fnn_fraction[k] <= fnn_threshold) {
      out.fnn_dimension = int(k) + 1;
      break;
    }
  // Cao: E1(d) -> 1 once d embeds the attractor; the dimension is the first d after which E1
  // stops changing (within 0.1 of 1 here, and of the next value).
  for (std::size_t k = 0; k + 1 < out.cao_e1.size(); ++k)
    if (out.cao_e1[k] >= 0.9 && std::abs(out.cao_e1[k + 1] - out.cao_e1[k]) < 0.1) {
      out.cao_dimension = int(k) + 1;
      break;
    }
  for (double e2 : out.cao_e2)
    out.e2_max_deviation = std::max(out.e2_max_deviation, std::abs(1.0 - e2));
  out.deterministic = out.e2_max_deviation > 0.1;
  return out;
}

std::size_t embedding_default_max_lag(std::size_t n) { return std::min<std::size_t>(1000, n / 10); }
std::size_t theiler_range(int delay) { return std::size_t(std::max(100, 20 * delay)); }

EmbeddingChoice choose_embedding(std::span<const double> x, std::size_t max_lag, int bins, int max_dimension,
                  double ratio, double threshold, const Json& fixed_delay) {
  EmbeddingChoice c;
  if (fixed_delay.is_number_integer()) {
    c.delay.delay = fixed_delay.get<int>();
    c.delay.rule = "given (delay_samples)";
    c.delay.mutual_information = mutual_information(x, std::min(max_lag, x.size() / 4), bins);
  } else {
    c.delay = choose_delay(x, max_lag, bins);
  }
  // Provisional Theiler window for the neighbour searches of FNN and Cao: 2-D embedding.
  const Embedding plane(x, 2, c.delay.delay);
  const std::size_t provisional =
      nonlinear::space_time_theiler(plane, theiler_range(c.delay.delay)).window;
  c.dimension = choose_dimension(x, c.delay.delay, max_dimension, provisional, ratio, threshold);
  // Neither criterion settled: the largest dimension examined (FNN stops where the series no
  // longer holds minimum_vectors vectors, so a short series never gets an infeasible dimension).
  const int examined = std::max(1, int(c.dimension.fnn_fraction.size()));
  c.chosen_dimension = c.dimension.fnn_dimension > 0   ? c.dimension.fnn_dimension
                       : c.dimension.cao_dimension > 0 ? c.dimension.cao_dimension
                                                       : std::min(max_dimension, examined);
  const Embedding chosen(x, c.chosen_dimension, c.delay.delay);
  c.theiler = nonlinear::space_time_theiler(chosen, theiler_range(c.delay.delay));
  return c;
}


void add_embedding_fields(Json& result, const EmbeddingParameters& embedding) {
  result["delay_samples"] = embedding.delay;
  result["embedding_dimension"] = embedding.dimension;
  result["theiler_window_samples"] = embedding.theiler;
  result["embedding_source"] = embedding.source;
}

EmbeddingParameters resolve_embedding(const ParamValues& params, const SampledSeries& series,
                                      const Json& context) {
  // The automatic choices histogram the samples before any other check: a NaN would index
  // outside the bins (found by the conformance suite's NaN check).
  nonlinear::check_finite(series.values, series.name);
  EmbeddingParameters out;
  const Json& p = params.json();
  auto given = [&](const char* key) { return p.contains(key) && p[key].is_number_integer(); };
  auto from_context = [&](const char* key) {
    return nonlinear::context_value(context, "embedding", key);
  };
  std::vector<std::string> sources;
  std::optional<EmbeddingChoice> automatic;
  auto automatic_choice = [&]() -> const EmbeddingChoice& {
    if (!automatic)
      automatic = choose_embedding(series.values, embedding_default_max_lag(series.values.size()), embedding_default_bins,
                             embedding_default_max_dimension, embedding_default_distance_ratio,
                             embedding_default_fnn_threshold,
                             given("delay_samples") ? p["delay_samples"] : Json());
    return *automatic;
  };
  if (given("delay_samples")) {
    out.delay = p["delay_samples"].get<int>();
    sources.push_back("delay given");
  } else if (auto v = from_context("delay_samples")) {
    out.delay = int(*v);
    sources.push_back("delay from `embedding`");
  } else {
    out.delay = automatic_choice().delay.delay;
    sources.push_back("delay chosen automatically");
  }
  if (given("embedding_dimension")) {
    out.dimension = p["embedding_dimension"].get<int>();
    sources.push_back("dimension given");
  } else if (auto v = from_context("embedding_dimension")) {
    out.dimension = int(*v);
    sources.push_back("dimension from `embedding`");
  } else {
    out.dimension = automatic_choice().chosen_dimension;
    sources.push_back("dimension chosen automatically");
  }
  if (given("theiler_window_samples")) {
    out.theiler = p["theiler_window_samples"].get<std::size_t>();
    sources.push_back("Theiler window given");
  } else if (auto v = from_context("theiler_window_samples");
             v && !given("delay_samples") && !given("embedding_dimension")) {
    out.theiler = std::size_t(*v);
    sources.push_back("Theiler window from `embedding`");
  } else {
    const Embedding e(series.values, out.dimension, out.delay);
    out.theiler = nonlinear::space_time_theiler(e, theiler_range(out.delay)).window;
    sources.push_back("Theiler window from a space-time separation plot");
  }
  nonlinear::check_series(series.values, out.dimension, out.delay,
                          series.name.empty() ? std::string("series") : series.name);
  out.source = fmt::format("{}", fmt::join(sources, ", "));
  return out;
}

}  // namespace chatterlab
