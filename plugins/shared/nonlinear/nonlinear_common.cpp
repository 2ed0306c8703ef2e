#include "shared/nonlinear/nonlinear_common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <numeric>
#include <random>

#include <malloc.h>

#include "chatterlab/errors.hpp"

namespace chatterlab::nonlinear {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
}

Json estimate(double value, double ci_low, double ci_high, const std::string& quality,
              const std::string& reason) {
  auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
  return Json{{"value", number(value)},
              {"ci_low", number(ci_low)},
              {"ci_high", number(ci_high)},
              {"quality", quality},
              {"reason", reason}};
}

std::optional<double> context_value(const Json& context, const std::string& method,
                                    const std::string& key) {
  if (!context.is_object() || !context.contains(method)) return std::nullopt;
  const Json& result = context[method];
  if (!result.is_object() || !result.contains(key)) return std::nullopt;
  const Json& entry = result[key];
  const Json& value = entry.is_object() && entry.contains("value") ? entry["value"] : entry;
  if (!value.is_number()) return std::nullopt;
  const double v = value.get<double>();
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

// ---------------------------------------------------------------- input checks
std::size_t minimum_samples(int dimension, int delay) {
  return std::size_t(std::max(dimension - 1, 0)) * std::size_t(std::max(delay, 1)) +
         minimum_vectors;
}

void check_finite(std::span<const double> x, const std::string& what) {
  for (std::size_t i = 0; i < x.size(); ++i)
    if (!std::isfinite(x[i]))
      throw InputError(fmt::format("{}: sample {} is {}: every sample must be a finite number",
                                   what, i + 1, x[i]));
}

void check_series(std::span<const double> x, int dimension, int delay, const std::string& what) {
  check_finite(x, what);
  const std::size_t needed = minimum_samples(dimension, delay);
  if (x.size() < needed)
    throw InputError(fmt::format(
        "{}: {} samples are too short for embedding dimension {} with delay {} samples: at least "
        "{} samples are needed ((dimension - 1) x delay + {} vectors)",
        what, x.size(), dimension, delay, needed, minimum_vectors));
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi > *lo))
    throw InputError(fmt::format(
        "{}: the signal is constant ({} in all {} samples): nothing to analyse", what, *lo,
        x.size()));
}

// ---------------------------------------------------------------- embedding
std::size_t vector_count(std::size_t n, int dimension, int delay) {
  const std::size_t window = std::size_t(dimension - 1) * std::size_t(delay);
  return n > window ? n - window : 0;
}

Embedding::Embedding(std::span<const double> x, int dimension, int delay, std::size_t count)
    : x_(x.data()), dimension_(dimension), delay_(delay) {
  if (dimension < 1 || dimension > max_dimension || delay < 1)
    throw PointFailure(fmt::format("delay embedding: dimension {} and delay {} samples: needs "
                                   "1 <= dimension <= {} and delay >= 1",
                                   dimension, delay, max_dimension));
  const std::size_t available = vector_count(x.size(), dimension, delay);
  count_ = count == 0 ? available : std::min(count, available);
}

// ---------------------------------------------------------------- neighbour search
namespace {
using Metric = nanoflann::L2_Simple_Adaptor<double, Embedding, double, std::uint32_t>;
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<Metric, Embedding, -1, std::uint32_t>;

bool admissible(std::size_t i, std::size_t j, std::size_t theiler, std::size_t limit) {
  const std::size_t gap = i > j ? i - j : j - i;
  return gap > theiler && j < limit;
}

// k nearest with the Theiler window applied while searching (so the tree prunes correctly).
class TheilerKnn {
 public:
  TheilerKnn(std::size_t k, std::size_t i, std::size_t theiler, std::size_t limit, double floor2)
      : k_(k), i_(i), theiler_(theiler), limit_(limit), floor2_(floor2) {}
  bool addPoint(double dist, std::uint32_t index) {
    if (dist <= floor2_ || !admissible(i_, index, theiler_, limit_)) return true;
    if (found_.size() < k_) {
      found_.push_back({index, dist});
      std::push_heap(found_.begin(), found_.end(), by_distance);
    } else if (dist < found_.front().distance) {
      std::pop_heap(found_.begin(), found_.end(), by_distance);
      found_.back() = {index, dist};
      std::push_heap(found_.begin(), found_.end(), by_distance);
    }
    return true;
  }
  double worstDist() const {
    return found_.size() < k_ ? std::numeric_limits<double>::max() : found_.front().distance;
  }
  bool full() const { return found_.size() == k_; }
  std::vector<Neighbour> sorted() {
    std::sort_heap(found_.begin(), found_.end(), by_distance);
    for (auto& n : found_) n.distance = std::sqrt(n.distance);
    return std::move(found_);
  }

 private:
  static bool by_distance(const Neighbour& a, const Neighbour& b) { return a.distance < b.distance; }
  std::size_t k_, i_, theiler_, limit_;
  double floor2_;
  std::vector<Neighbour> found_;  // max-heap on squared distance
};

class TheilerRadius {
 public:
  TheilerRadius(double radius_squared, std::size_t i, std::size_t theiler, std::size_t limit,
                double floor2, std::size_t max_count)
      : r2_(radius_squared), i_(i), theiler_(theiler), limit_(limit), floor2_(floor2),
        max_count_(max_count) {}
  bool addPoint(double dist, std::uint32_t index) {
    if (dist < r2_ && dist > floor2_ && admissible(i_, index, theiler_, limit_))
      found_.push_back({index, std::sqrt(dist)});
    return found_.size() < max_count_;  // false stops the search
  }
  double worstDist() const { return r2_; }
  bool full() const { return true; }
  std::vector<Neighbour> take() { return std::move(found_); }

 private:
  double r2_;
  std::size_t i_, theiler_, limit_;
  double floor2_;
  std::size_t max_count_;
  std::vector<Neighbour> found_;
};
}  // namespace

// Vectors per leaf of the k-d tree at most. nanoflann's nodes take 48 bytes in its pool (size_t
// leaf bounds, two child pointers, 16-byte words) and leaves of at most 16 vectors hold about 4.5
// on average: ~21 bytes of nodes per vector beside its 4-byte index, the largest array of a
// 10^7-sample analysis (250 MB). From 2^20 vectors on, leaves of up to 32 halve that (a query
// scans a few more vectors per leaf). Below, 16 as always: the leaf size decides which of
// several equally distant neighbours a query returns (quantised data have such ties), so
// shorter series keep their results.
namespace {
std::size_t leaf_vectors(std::size_t vectors) { return vectors >= (std::size_t(1) << 20) ? 32 : 16; }
}  // namespace

struct NeighbourSearch::Tree {
  explicit Tree(const Embedding& e)
      : index(std::size_t(e.dimension()), e,
              nanoflann::KDTreeSingleIndexAdaptorParams(leaf_vectors(e.size()))) {}
  KdTree index;
};

NeighbourSearch::NeighbourSearch(const Embedding& embedding)
    : embedding_(embedding), tree_(std::make_unique<Tree>(embedding)) {
  // Coincident vectors (an exactly periodic or quantised signal repeats itself) say nothing about
  // local stretching: neighbours closer than 1e-9 of the data range are skipped.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < embedding.size(); ++i) {
    lo = std::min(lo, embedding.coordinate(i, 0));
    hi = std::max(hi, embedding.coordinate(i, 0));
  }
  const double floor = 1e-9 * (hi - lo);
  floor2_ = floor * floor;
}
NeighbourSearch::~NeighbourSearch() {
  tree_.reset();
  // nanoflann allocates its nodes in 8 KB blocks from the heap, which stay resident when freed
  // (~150 MB after a tree of 10^7 vectors): return them, so that the next method's arrays do
  // not come on top of them.
  malloc_trim(0);
}

std::vector<Neighbour> NeighbourSearch::nearest(std::size_t i, std::size_t k,
                                                std::size_t theiler, std::size_t limit) const {
  TheilerKnn result(k, i, theiler, limit, floor2_);
  double query[Embedding::max_dimension];
  embedding_.copy_point(i, query);
  tree_->index.findNeighbors(result, query, nanoflann::SearchParams());
  return result.sorted();
}

std::vector<Neighbour> NeighbourSearch::within(std::size_t i, double radius, std::size_t theiler,
                                               std::size_t limit, std::size_t max_count) const {
  TheilerRadius result(radius * radius, i, theiler, limit, floor2_, max_count);
  double query[Embedding::max_dimension];
  embedding_.copy_point(i, query);
  tree_->index.findNeighbors(result, query, nanoflann::SearchParams(32, 0, false));
  return result.take();
}

// ---------------------------------------------------------------- Theiler window
TheilerChoice space_time_theiler(const Embedding& e, std::size_t max_separation, double fraction,
                                 double saturation) {
  TheilerChoice out;
  const std::size_t n = e.size();
  max_separation = std::min(max_separation, n / 4);
  if (max_separation < 4) {
    out.rule = "series too short for a space-time separation plot: window 0";
    return out;
  }
  // At most ~400 pairs per separation, evenly spread over the series (deterministic).
  std::vector<double> d;
  for (std::size_t dt = 1; dt <= max_separation; ++dt) {
    const std::size_t pairs = n - dt;
    const std::size_t stride = std::max<std::size_t>(1, pairs / 400);
    d.clear();
    for (std::size_t i = 0; i < pairs; i += stride) d.push_back(e.distance(i, i + dt));
    const std::size_t q = std::min(d.size() - 1, std::size_t(fraction * double(d.size())));
    std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(q), d.end());
    out.separations.push_back(double(dt));
    out.contour.push_back(d[q]);
  }
  std::vector<double> far(out.contour.begin() + std::ptrdiff_t(out.contour.size() / 2),
                          out.contour.end());
  std::nth_element(far.begin(), far.begin() + std::ptrdiff_t(far.size() / 2), far.end());
  const double level = saturation * far[far.size() / 2];
  for (std::size_t k = 0; k < out.contour.size(); ++k)
    if (out.contour[k] >= level) {
      out.window = std::size_t(out.separations[k]);
      break;
    }
  out.rule = fmt::format(
      "space-time separation: first separation where the {:g} % contour reaches {:g} x its "
      "median over separations {}..{}",
      100 * fraction, saturation, max_separation / 2 + 1, max_separation);
  return out;
}

// ---------------------------------------------------------------- lines and regions
LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y, std::size_t begin,
                 std::size_t end) {
  LineFit f;
  f.points = end - begin;
  if (f.points < 2) return f;
  double mx = 0, my = 0;
  for (std::size_t i = begin; i < end; ++i) mx += x[i], my += y[i];
  mx /= double(f.points);
  my /= double(f.points);
  double sxx = 0, sxy = 0;
  for (std::size_t i = begin; i < end; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  if (f.points > 2) {
    double sse = 0;
    for (std::size_t i = begin; i < end; ++i) {
      const double r = y[i] - f.intercept - f.slope * x[i];
      sse += r * r;
    }
    f.slope_stderr = std::sqrt(sse / double(f.points - 2) / sxx);
  }
  return f;
}

std::vector<double> local_slopes(const std::vector<double>& x, const std::vector<double>& y,
                                 const std::vector<bool>& usable, std::size_t half) {
  std::vector<double> out(x.size(), nan);
  for (std::size_t i = half; i + half < x.size(); ++i) {
    bool ok = true;
    for (std::size_t j = i - half; j <= i + half && ok; ++j) ok = usable[j];
    if (ok) out[i] = fit_line(x, y, i - half, i + half + 1).slope;
  }
  return out;
}

Region find_plateau(const std::vector<double>& x, const std::vector<double>& slopes,
                    double tolerance, double min_span, bool furthest) {
  Region best;
  double best_span = 0;
  std::vector<double> run;
  for (std::size_t b = 0; b < slopes.size(); ++b) {
    if (!std::isfinite(slopes[b])) continue;
    // Grow [b, e) while every slope stays within tolerance of the running median.
    run.clear();
    std::size_t e = b;
    double median = slopes[b], lo = slopes[b], hi = slopes[b];
    while (e < slopes.size() && std::isfinite(slopes[e])) {
      run.push_back(slopes[e]);
      const double new_lo = std::min(lo, slopes[e]), new_hi = std::max(hi, slopes[e]);
      if (new_hi - new_lo > 2 * tolerance) break;  // no median can be within tolerance of both
      std::vector<double> sorted = run;
      std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(sorted.size() / 2),
                       sorted.end());
      const double m = sorted[sorted.size() / 2];
      if (new_hi - m > tolerance || m - new_lo > tolerance) break;
      median = m;
      lo = new_lo;
      hi = new_hi;
      ++e;
    }
    const double span = e > b ? x[e - 1] - x[b] : 0;
    if (span < min_span) continue;
    const bool better = furthest ? !best.found || e > best.end ||
                                       (e == best.end && span > best_span + 1e-12)
                                 : span > best_span + 1e-12;
    if (better) {
      best = {true, b, e, median};
      best_span = span;
    }
  }
  return best;
}

// ---------------------------------------------------------------- bootstrap
Interval block_bootstrap(std::size_t blocks, std::size_t replicates, std::uint64_t seed,
                         const std::function<double(const std::vector<double>&)>& statistic) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, blocks - 1);
  std::vector<double> values, weights(blocks);
  for (std::size_t r = 0; r < replicates; ++r) {
    std::fill(weights.begin(), weights.end(), 0.0);
    for (std::size_t b = 0; b < blocks; ++b) weights[pick(rng)] += 1;
    const double v = statistic(weights);
    if (std::isfinite(v)) values.push_back(v);
  }
  if (values.size() * 2 < replicates || values.empty()) return {nan, nan};
  std::sort(values.begin(), values.end());
  auto at = [&](double p) {
    const double pos = p * double(values.size() - 1);
    const std::size_t lo = std::size_t(pos);
    const std::size_t hi = std::min(lo + 1, values.size() - 1);
    return values[lo] + (pos - double(lo)) * (values[hi] - values[lo]);
  };
  return {at(0.025), at(0.975)};
}

// ---------------------------------------------------------------- helpers
double standard_deviation(std::span<const double> x) {
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / double(x.size());
  double s = 0;
  for (double v : x) s += (v - mean) * (v - mean);
  return std::sqrt(s / double(x.size()));
}

ParamSpec delay_spec() {
  return numeric_spec("delay_samples", ValueKind::integer, "samples",
                      "embedding delay (N1); absent: from an earlier `embedding` result or chosen "
                      "automatically by average mutual information",
                      Json(), 1, 100000);
}

ParamSpec dimension_spec() {
  return numeric_spec("embedding_dimension", ValueKind::integer, "1",
                      "embedding dimension (N1); absent: from an earlier `embedding` result or "
                      "chosen automatically by false nearest neighbours",
                      Json(), 1, 30);
}

ParamSpec theiler_spec() {
  return numeric_spec("theiler_window_samples", ValueKind::integer, "samples",
                      "neighbours closer in time than this are excluded; absent: from a "
                      "space-time separation plot",
                      Json(), 0, 1000000);
}

ParamSpec seed_spec() {
  return numeric_spec("seed", ValueKind::integer, "1",
                      "random seed (bootstrap, surrogates): fixed, so runs repeat exactly",
                      20240611, 0);
}

ParamSpec bootstrap_spec() {
  return numeric_spec("bootstrap_replicates", ValueKind::integer, "1",
                      "bootstrap resamplings (of blocks of reference points) for the 95 % "
                      "confidence interval",
                      200, 20, 100000);
}

ParamSpec numeric_spec(std::string key, ValueKind kind, std::string unit, std::string description,
                       Json default_value, double min, double max, bool min_exclusive) {
  ParamSpec s = param_spec(std::move(key), kind, std::move(unit), std::move(description));
  s.optional = default_value.is_null();
  s.default_value = std::move(default_value);
  s.min = min;
  s.max = max;
  s.min_exclusive = min_exclusive;
  return s;
}

std::optional<std::int64_t> given_integer(const ParamValues& params, const char* key) {
  const Json& p = params.json();
  if (p.contains(key) && p[key].is_number_integer()) return p[key].get<std::int64_t>();
  return std::nullopt;
}

std::optional<double> given_real(const ParamValues& params, const char* key) {
  const Json& p = params.json();
  if (p.contains(key) && p[key].is_number()) return p[key].get<double>();
  return std::nullopt;
}

}  // namespace chatterlab::nonlinear
