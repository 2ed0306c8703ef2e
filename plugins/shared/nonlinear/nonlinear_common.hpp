#pragma once
// Numerical building blocks shared by the nonlinear (chaos) analyses of MODELS.md N: checks of
// the input series, the delay embedding (N1), k-d tree neighbour search with a Theiler window,
// the automatic Theiler window from a space-time separation plot, detection of linear/scaling
// regions, straight-line fits, block bootstrap and the result convention of analysis.hpp.
// docs/analysis/chaos.md describes the rules in words.
#include <algorithm>
#include <span>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::nonlinear {

// ---------------------------------------------------------------- plugin class
// Every nonlinear analysis plugin (N1-N4) is the same kind of class: its validated parameters
// and three functions of them. This template declares it once; a method is named by a tag type
// and defines the three members as explicit specialisations in its own .cpp:
//
//     struct LyapunovMethod;                                          // lyapunov.hpp
//     using LyapunovAnalysis = nonlinear::MethodAnalysis<LyapunovMethod>;
//
//     template <> PluginInfo LyapunovAnalysis::info() { ... }         // lyapunov.cpp
//     template <> Json LyapunovAnalysis::analyse(const SampledSeries&, const Json&) const { ... }
//     template <> void LyapunovAnalysis::plot(const Json&, const SampledSeries&, ...) const { ... }
//     CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovAnalysis);
template <class Method>
class MethodAnalysis final : public Analysis {
 public:
  static PluginInfo info();
  explicit MethodAnalysis(const ParamValues& params) : params_(params) {}
  Json analyse(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;

 private:
  ParamValues params_;
};

// ---------------------------------------------------------------- results
// A scalar estimate in the analysis.hpp convention: quality "good", "uncertain" or "failed".
Json estimate(double value, double ci_low, double ci_high, const std::string& quality,
              const std::string& reason);
// The "value" of an estimate stored in context[method][key], if present and finite.
std::optional<double> context_value(const Json& context, const std::string& method,
                                    const std::string& key);

// ---------------------------------------------------------------- input checks
// Vectors an analysis needs at least, beyond the embedding window (neighbour statistics).
inline constexpr std::size_t minimum_vectors = 100;
// Samples a series needs before any nonlinear analysis runs on it (a study rejects shorter ones
// as bad input): FNN and Cao examine embedding dimensions up to 10 with minimum_vectors vectors
// each, the D2 sweep goes to dimension 8 and needs 2000 pairs inside its scaling region, and
// the divergence curves follow minimum_vectors references for at least 30 samples in three
// dimensions. Below 300 samples these leave no statistics worth reporting; every automatic
// choice (delay, dimensions, horizon) is bounded so that a series of this length runs.
inline constexpr std::size_t minimum_series_samples = 300;
// Samples needed to embed in `dimension` with `delay` and still have minimum_vectors vectors.
std::size_t minimum_samples(int dimension, int delay);
// Throws InputError when a sample is not finite, naming its index.
void check_finite(std::span<const double> x, const std::string& what);
// Throws InputError when a sample is not finite (naming its index), the series is constant, or
// it is shorter than minimum_samples(dimension, delay) (naming the minimum). `what` names the
// series in the message (e.g. the input column).
void check_series(std::span<const double> x, int dimension, int delay, const std::string& what);

// ---------------------------------------------------------------- delay embedding (N1)
// X_i = (x_i, x_{i+delay}, ..., x_{i+(dimension-1) delay}), i < count: a view of the series,
// each coordinate read from x when it is needed (the series must outlive the embedding). A copy
// of the vectors would take dimension x 8 bytes per sample (80 for the FNN sweep's dimension 10,
// an order of magnitude more than the series); reading them from the series gives the same
// numbers in the same order of operations. `count` may be set below the maximum so that
// embeddings of several dimensions share the same vector indices.
class Embedding {
 public:
  // Dimensions a view serves at most (the parameters allow 30; FNN examines one more).
  static constexpr int max_dimension = 64;
  Embedding(std::span<const double> x, int dimension, int delay, std::size_t count = 0);
  std::size_t size() const { return count_; }
  int dimension() const { return dimension_; }
  int delay() const { return delay_; }
  // Coordinate k of vector i.
  double coordinate(std::size_t i, int k) const { return x_[i + std::size_t(k) * std::size_t(delay_)]; }
  // Vector i copied to out[0 .. dimension) (a k-d tree query needs contiguous coordinates).
  void copy_point(std::size_t i, double* out) const {
    for (int k = 0; k < dimension_; ++k) out[k] = coordinate(i, k);
  }
  // Euclidean and maximum-norm distances (inline: the Lyapunov loops spend most time here).
  double distance(std::size_t i, std::size_t j) const {
    double s = 0;
    for (int k = 0; k < dimension_; ++k) {
      const double d = coordinate(i, k) - coordinate(j, k);
      s += d * d;
    }
    return std::sqrt(s);
  }
  double max_distance(std::size_t i, std::size_t j) const {
    double s = 0;
    for (int k = 0; k < dimension_; ++k)
      s = std::max(s, std::abs(coordinate(i, k) - coordinate(j, k)));
    return s;
  }

  // nanoflann dataset adaptor
  std::size_t kdtree_get_point_count() const { return count_; }
  double kdtree_get_pt(std::size_t i, std::size_t k) const { return coordinate(i, int(k)); }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }

 private:
  const double* x_ = nullptr;
  std::size_t count_ = 0;
  int dimension_ = 1, delay_ = 1;
};

// Largest vector count for an embedding of `dimension` x `delay` of n samples (0 if none).
std::size_t vector_count(std::size_t n, int dimension, int delay);

struct Neighbour {
  std::uint32_t index;
  double distance;  // Euclidean
};

// k-d tree (nanoflann) over an Embedding. Every query excludes the temporal neighbours
// |i - j| <= theiler (Theiler window), indices j >= index_limit (so that the future of j needed
// by a Lyapunov estimate exists) and coincident vectors (closer than 1e-9 of the data range).
// Queries are const and thread-safe.
class NeighbourSearch {
 public:
  explicit NeighbourSearch(const Embedding& embedding);
  ~NeighbourSearch();
  NeighbourSearch(const NeighbourSearch&) = delete;
  NeighbourSearch& operator=(const NeighbourSearch&) = delete;

  // The k nearest admissible neighbours of vector i, nearest first (fewer if there are not k).
  std::vector<Neighbour> nearest(std::size_t i, std::size_t k, std::size_t theiler,
                                 std::size_t index_limit) const;
  // Admissible neighbours of vector i closer than `radius` (unsorted): all of them, or the
  // first `max_count` the tree search meets (it descends towards i first, so these lie near i).
  std::vector<Neighbour> within(std::size_t i, double radius, std::size_t theiler,
                                std::size_t index_limit,
                                std::size_t max_count = std::numeric_limits<std::size_t>::max()) const;

 private:
  struct Tree;
  const Embedding& embedding_;
  std::unique_ptr<Tree> tree_;
  double floor2_ = 0;
};

// ---------------------------------------------------------------- Theiler window
// Space-time separation plot (Provenzale et al. 1992): for each time separation dt the distance
// within which a fraction `fraction` of the vector pairs (i, i + dt) lie. Temporal correlation
// makes that contour grow with dt until it saturates; the Theiler window is the first dt where
// the contour reaches `saturation` x its median over the far half of the examined separations.
struct TheilerChoice {
  std::size_t window = 0;
  std::vector<double> separations, contour;  // the plot
  std::string rule;                          // how the window was chosen
};
TheilerChoice space_time_theiler(const Embedding& embedding, std::size_t max_separation,
                                 double fraction = 0.05, double saturation = 0.9);

// ---------------------------------------------------------------- straight lines and regions
struct LineFit {
  double slope = 0, intercept = 0, slope_stderr = 0;
  std::size_t points = 0;
};
LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y, std::size_t begin,
                 std::size_t end);  // least squares over [begin, end)

// Local slopes: least-squares slope of y over x within [i - half, i + half] (NaN where any point
// is not usable or the window leaves the curve).
std::vector<double> local_slopes(const std::vector<double>& x, const std::vector<double>& y,
                                 const std::vector<bool>& usable, std::size_t half);

// The longest run [begin, end) of usable points whose local slopes stay within
// `tolerance` (absolute) of the run's median slope, spanning at least `min_span` in x.
// found = false when no run qualifies. Ties go to the run starting at smaller x. With
// `furthest`, the qualifying run that reaches the largest x instead (the longest of those):
// a scaling region above small-scale artefacts (noise, the strands of a finite trajectory).
struct Region {
  bool found = false;
  std::size_t begin = 0, end = 0;
  double median_slope = 0;
};
Region find_plateau(const std::vector<double>& x, const std::vector<double>& slopes,
                    double tolerance, double min_span, bool furthest = false);

// ---------------------------------------------------------------- bootstrap
// Percentile interval (2.5 %, 97.5 %) of statistic(weights) over `replicates` resamplings of
// `blocks` blocks with replacement (weights[b] = how often block b was drawn). NaN statistics are
// skipped; returns {NaN, NaN} if fewer than half are finite. Fixed seed: reproducible.
struct Interval {
  double low, high;
};
Interval block_bootstrap(std::size_t blocks, std::size_t replicates, std::uint64_t seed,
                         const std::function<double(const std::vector<double>&)>& statistic);

// ---------------------------------------------------------------- helpers
double standard_deviation(std::span<const double> x);
// Parameter specs shared by the methods that embed a series.
ParamSpec delay_spec();              // delay_samples, optional (auto)
ParamSpec dimension_spec();          // embedding_dimension, optional (auto)
ParamSpec theiler_spec();            // theiler_window_samples, optional (auto)
ParamSpec seed_spec();               // seed
ParamSpec bootstrap_spec();          // bootstrap_replicates
// A real or integer parameter with limits [min, max]; a null `default_value` makes it optional
// (the method chooses automatically when it is absent).
ParamSpec numeric_spec(std::string key, ValueKind kind, std::string unit, std::string description,
                       Json default_value, double min,
                       double max = std::numeric_limits<double>::infinity(),
                       bool min_exclusive = false);
// An optional parameter's value when the study gave it.
std::optional<std::int64_t> given_integer(const ParamValues& params, const char* key);
std::optional<double> given_real(const ParamValues& params, const char* key);

}  // namespace chatterlab::nonlinear
