#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "shared/nonlinear/embedding_choice.hpp"
#include "shared/nonlinear/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t spectrum_blocks = 20;

// QR of the column-major dim x dim matrix a by Gram-Schmidt: a becomes Q, r_diagonal the
// |R_kk| (the stretching factors). Each column is orthogonalised twice against the ones before
// ("twice is enough", Giraud et al. 2005): one pass loses orthogonality in proportion to the
// condition number, which grows like exp((lambda_1 - lambda_d) x evolution steps).
void orthonormalise_columns(double* a, std::size_t dim, double* r_diagonal) {
  for (std::size_t k = 0; k < dim; ++k) {
    double* v = a + k * dim;
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t j = 0; j < k; ++j) {
        const double* u = a + j * dim;
        double projection = 0;
        for (std::size_t l = 0; l < dim; ++l) projection += u[l] * v[l];
        for (std::size_t l = 0; l < dim; ++l) v[l] -= projection * u[l];
      }
    double norm2 = 0;
    for (std::size_t l = 0; l < dim; ++l) norm2 += v[l] * v[l];
    const double norm = std::sqrt(norm2);
    r_diagonal[k] = norm;
    if (norm > 0)
      for (std::size_t l = 0; l < dim; ++l) v[l] /= norm;
  }
}
}  // namespace

SpectrumEstimate lyapunov_spectrum(std::span<const double> x, int dimension, int delay,
                                   std::size_t theiler, std::size_t evolution_steps,
                                   std::size_t neighbours, std::size_t references) {
  using nonlinear::Embedding;
  const Embedding e(x, dimension, delay);
  const nonlinear::NeighbourSearch search(e);
  const std::size_t n = e.size();
  const std::size_t m = std::max<std::size_t>(1, evolution_steps);
  if (n < m + neighbours + 10) throw PointFailure("series too short for the Lyapunov spectrum");
  const std::size_t limit = n - m;
  const std::size_t count = std::min(references, limit / m);
  const std::size_t dim = std::size_t(dimension), dd = dim * dim;
  const auto d = Eigen::Index(dim);
  // Local Jacobians (independent: computed in parallel), then the sequential QR chain. The
  // Jacobians are stored flat and every matrix below is allocated once (per thread): with a
  // heap matrix per fit and per chain step, malloc/free took ~6 % of the time and the chain
  // (serial) held back the OpenMP gain.
  std::vector<double> jacobians(count * dd);
  std::vector<char> ok(count, 0);
  using Matrix = Eigen::MatrixXd;
#pragma omp parallel
  {
    Matrix y, z, a(d, d);
    Eigen::ColPivHouseholderQR<Matrix> fit;
#pragma omp for schedule(dynamic, 64)
    for (std::size_t t = 0; t < count; ++t) {
      const std::size_t i = t * m;
      const auto nn = search.nearest(i, neighbours, theiler, limit);
      if (nn.size() < dim + 1) continue;
      y.resize(Eigen::Index(nn.size()), d);
      z.resize(Eigen::Index(nn.size()), d);
      for (std::size_t r = 0; r < nn.size(); ++r) {
        const std::size_t j = nn[r].index;
        for (int c = 0; c < dimension; ++c) {
          y(Eigen::Index(r), c) = e.coordinate(j, c) - e.coordinate(i, c);
          z(Eigen::Index(r), c) = e.coordinate(j + m, c) - e.coordinate(i + m, c);
        }
      }
      // Z = Y A^T in the least-squares sense (N3: A U = V with the covariance matrices).
      fit.compute(y);
      a.noalias() = fit.solve(z).transpose();
      Eigen::Map<Matrix>(jacobians.data() + t * dd, d, d) = a;
      ok[t] = a.allFinite() ? 1 : 0;
    }
  }
  SpectrumEstimate out;
  out.block_sums.assign(spectrum_blocks, std::vector<double>(dim, 0.0));
  out.block_steps.assign(spectrum_blocks, 0.0);
  // The chain is serial: Gram-Schmidt on preallocated d x d matrices (45 -> 10 ms for 100,000
  // steps against Eigen's dynamic-size Householder QR with its allocations, which was ~6 % of
  // the single-thread time and capped the OpenMP gain).
  Matrix q = Matrix::Identity(d, d), moved(d, d);
  std::vector<double> diagonal(dim);
  for (std::size_t t = 0; t < count; ++t) {
    if (!ok[t]) continue;
    moved.noalias() = Eigen::Map<const Matrix>(jacobians.data() + t * dd, d, d) * q;
    orthonormalise_columns(moved.data(), dim, diagonal.data());
    const std::size_t block = t * spectrum_blocks / count;
    bool finite = true;
    for (double rkk : diagonal) finite = finite && rkk > 0 && std::isfinite(rkk);
    if (!finite) continue;  // keep the previous frame
    q.swap(moved);
    for (std::size_t k = 0; k < dim; ++k) out.block_sums[block][k] += std::log(diagonal[k]);
    out.block_steps[block] += double(m);
  }
  std::vector<double> total(dim, 0.0);
  double steps = 0;
  for (std::size_t b = 0; b < spectrum_blocks; ++b) {
    for (std::size_t k = 0; k < total.size(); ++k) total[k] += out.block_sums[b][k];
    steps += out.block_steps[b];
  }
  for (double& v : total) v /= steps;
  std::sort(total.begin(), total.end(), std::greater<>());
  out.exponents = total;
  return out;
}

namespace {
// Exponents within this fraction of |lambda_1| of zero have no reliable sign (the zero exponent
// of a flow); a genuine exponent reappears in one more embedding dimension within this fraction
// of max(|lambda_1|, |lambda_i|) (local fits underestimate strongly negative exponents, which
// therefore move more).
constexpr double zero_band = 0.2;
constexpr double dimension_tolerance = 0.2;
// An exponent within this fraction of max(|lambda_i|, |lambda_1|) of the sum of two others (or
// twice another) is a combination exponent: local linear fits of a map embedded in too many
// dimensions produce 2 lambda_1, lambda_1 + lambda_2, ... (Sauer, Tempkin and Yorke 1998).
constexpr double combination_tolerance = 0.06;
// The spectrum's largest exponent and the divergence estimate of `lyapunov` agree when they are
// within this fraction of each other (or the spectrum's value lies inside the other interval).
constexpr double divergence_agreement = 0.25;
}  // namespace

template <>
PluginInfo LyapunovSpectrum::info() {
  using nonlinear::numeric_spec;
  ParamSpec reversal = param_spec("time_reversal_check", ValueKind::boolean, "",
                                  "flag exponents that do not change sign for the reversed series");
  reversal.default_value = true;
  return plugin_info("lyapunov_spectrum", "N3",
                     {
                         nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
                         numeric_spec("evolution_steps", ValueKind::integer, "samples",
                                      "samples over which each local Jacobian maps displacements (multi-step "
                                      "evolution; absent: one delay)",
                                      Json(), 1),
                         numeric_spec("neighbours", ValueKind::integer, "1",
                                      "nearest neighbours per local fit (absent: max(20, 4 x dimension))", Json(), 2),
                         numeric_spec("max_reference_points", ValueKind::integer, "1",
                                      "local fits along the trajectory at most", 10000, 20),
                         reversal, nonlinear::bootstrap_spec(), nonlinear::seed_spec()},
                     {{"max_reference_points", 300}},
                     "Lyapunov spectrum from local Jacobian least-squares fits with QR re-orthonormalisation; "
                     "spurious exponents flagged by one more embedding dimension and by time reversal; "
                     "Kaplan-Yorke dimension and the sum of the exponents",
                     ThreadSafety::shareable);
}

namespace {

// A rate per sample, or per unit of the series.
struct RateText {
  double dt = 1;
  std::string unit;
  std::string operator()(double v) const {
    return unit == "sample" ? fmt::format("{:.4g} per sample", v)
                            : fmt::format("{:.4g} per {}", v / dt, unit);
  }
};

// The spectrum in the chosen embedding, in one more dimension (genuine exponents persist,
// spurious ones from fitting the local maps in more dimensions than the attractor needs move or
// appear; Parlitz 1992) and of the time-reversed series (empty when not computed).
struct Spectra {
  SpectrumEstimate forward;
  std::vector<double> higher, reversed;
};

// The settings of the local fits.
struct FitSettings {
  int dimension = 2, delay = 1;
  std::size_t theiler = 0, evolution_steps = 1, references = 0;
  std::optional<std::int64_t> neighbours;
  std::size_t neighbours_for(int d) const {
    return std::size_t(neighbours.value_or(std::max(20, 4 * d)));
  }
};

Spectra compute_spectra(std::span<const double> x, const FitSettings& s, bool reversal) {
  Spectra out;
  out.forward = lyapunov_spectrum(x, s.dimension, s.delay, s.theiler, s.evolution_steps,
                                  s.neighbours_for(s.dimension), s.references);
  if (x.size() >= nonlinear::minimum_samples(s.dimension + 1, s.delay) + s.evolution_steps + 20) {
    try {
      out.higher = lyapunov_spectrum(x, s.dimension + 1, s.delay, s.theiler, s.evolution_steps,
                                     s.neighbours_for(s.dimension + 1), s.references)
                       .exponents;
    } catch (const PointFailure&) {
      out.higher.clear();
    }
  }
  if (reversal) {
    const std::vector<double> reversed(x.rbegin(), x.rend());
    out.reversed = lyapunov_spectrum(reversed, s.dimension, s.delay, s.theiler,
                                     s.evolution_steps, s.neighbours_for(s.dimension),
                                     s.references)
                       .exponents;
  }
  return out;
}

// The 95 % block-bootstrap interval of exponent i: the i-th largest of the resampled block
// averages.
nonlinear::Interval exponent_interval(const SpectrumEstimate& forward, std::size_t i,
                                      std::size_t replicates, std::uint64_t seed) {
  const std::size_t dims = forward.exponents.size();
  return nonlinear::block_bootstrap(spectrum_blocks, replicates, seed,
                                    [&](const std::vector<double>& w) {
                                      std::vector<double> total(dims, 0.0);
                                      double steps = 0;
                                      for (std::size_t b = 0; b < spectrum_blocks; ++b) {
                                        for (std::size_t j = 0; j < dims; ++j)
                                          total[j] += w[b] * forward.block_sums[b][j];
                                        steps += w[b] * forward.block_steps[b];
                                      }
                                      for (double& v : total) v /= steps;
                                      std::sort(total.begin(), total.end(), std::greater<>());
                                      return total[i];
                                    });
}

// The checks of one exponent: which it fails (spurious) and which it passes.
struct Checks {
  std::vector<std::string> failed, passed;
};

// Only clearly positive exponents are checked in one more dimension: local fits estimate the
// contracting directions of a flow poorly, and differently in every dimension, and the zero
// exponent of a flow has no reliable sign (time reversal checks those).
void check_higher_dimension(double lambda, double lambda1, const Spectra& s, int dimension,
                            const RateText& rate, Checks& c) {
  if (s.higher.empty() || lambda < zero_band * lambda1) return;
  double closest = s.higher.front();
  for (double v : s.higher)
    if (std::abs(v - lambda) < std::abs(closest - lambda)) closest = v;
  const double tol = dimension_tolerance * std::max(lambda1, std::abs(lambda));
  (std::abs(closest - lambda) <= tol ? c.passed : c.failed)
      .push_back(fmt::format("in dimension {} the nearest exponent is {}", dimension + 1,
                             rate(closest)));
}

// True exponents change sign under time reversal: lambda_i ~ -lambda^rev_{d+1-i}; spurious
// ones keep their sign.
void check_time_reversal(std::size_t i, double lambda1, const Spectra& s, const RateText& rate,
                         Checks& c) {
  if (s.reversed.empty()) return;
  const double lambda = s.forward.exponents[i];
  const bool near_zero_here = std::abs(lambda) < zero_band * lambda1;
  const double partner = -s.reversed[s.forward.exponents.size() - 1 - i];
  const bool confirmed = (lambda > 0) == (partner > 0) ||
                         (near_zero_here && std::abs(partner) < zero_band * lambda1);
  (confirmed ? c.passed : c.failed)
      .push_back(fmt::format("the reversed series gives -lambda_rev = {}", rate(partner)));
}

// Combinations of two other exponents, neither of them near zero (a flow's zero exponent would
// make every exponent a "combination").
void check_combinations(std::size_t i, double lambda1, const std::vector<double>& exponents,
                        const RateText& rate, Checks& c) {
  const double lambda = exponents[i];
  const std::size_t dims = exponents.size();
  for (std::size_t j = 0; j < dims && c.failed.empty(); ++j)
    for (std::size_t l = j; l < dims; ++l) {
      const double a = exponents[j], b = exponents[l];
      if (j == i || l == i || std::abs(a) < zero_band * lambda1 ||
          std::abs(b) < zero_band * lambda1)
        continue;
      if (std::abs(lambda - (a + b)) <= combination_tolerance * std::max(std::abs(lambda), lambda1)) {
        c.failed.push_back(fmt::format("it equals the sum of {} and {} (a combination exponent)",
                                       rate(a), rate(b)));
        break;
      }
    }
}

// The `lyapunov` result in the context, when it ran.
const Json* lyapunov_result(const Json& context) {
  if (!context.is_object() || !context.contains("lyapunov") || !context["lyapunov"].is_object())
    return nullptr;
  return &context["lyapunov"];
}

// The divergence curves of `lyapunov` (when they show exponential divergence) bound the spectrum
// from above: no exponent can exceed the largest one.
double divergence_upper_bound(const Json& context) {
  const Json* l = lyapunov_result(context);
  if (!l || l->value("divergence", "") != "exponential") return nan;
  const Json& e = (*l)["lyapunov_max_per_sample"];
  return e["ci_high"].is_number() ? e["ci_high"].get<double>() : nan;
}

// Exponent i with its interval (per sample and per unit), its checks and the spurious flag.
Json exponent_json(std::size_t i, const Spectra& s, const nonlinear::Interval& ci,
                   const Checks& c, const RateText& rate) {
  const double lambda = s.forward.exponents[i];
  const bool spurious = !c.failed.empty();
  const std::string reason =
      spurious ? fmt::format("spurious: {}", fmt::join(c.failed, "; "))
               : (c.passed.empty() ? std::string("local Jacobian fits")
                                   : fmt::format("confirmed: {}", fmt::join(c.passed, "; ")));
  Json e = nonlinear::estimate(lambda, ci.low, ci.high, spurious ? "uncertain" : "good", reason);
  e["value_per_" + rate.unit] = lambda / rate.dt;
  e["ci_low_per_" + rate.unit] = std::isfinite(ci.low) ? Json(ci.low / rate.dt) : Json();
  e["ci_high_per_" + rate.unit] = std::isfinite(ci.high) ? Json(ci.high / rate.dt) : Json();
  e["spurious"] = spurious;
  return e;
}

// Every exponent with its interval, its checks and the spurious flag; the genuine ones are
// appended to `genuine` (largest first). An exponent above the upper end of the divergence
// estimate (`divergence_high`, NaN when none) is spurious: none can exceed the largest.
Json classify_exponents(const Spectra& spectra, int dimension, double divergence_high,
                        std::size_t replicates, std::uint64_t seed, const RateText& rate,
                        std::vector<double>& genuine) {
  const auto& forward = spectra.forward.exponents;
  const double lambda1 = std::max(std::abs(forward[0]), 1e-12);
  Json exponents = Json::array();
  for (std::size_t i = 0; i < forward.size(); ++i) {
    const auto ci = exponent_interval(spectra.forward, i, replicates, seed + i);
    Checks checks;
    check_higher_dimension(forward[i], lambda1, spectra, dimension, rate, checks);
    check_time_reversal(i, lambda1, spectra, rate, checks);
    check_combinations(i, lambda1, forward, rate, checks);
    if (std::isfinite(divergence_high) && forward[i] > divergence_high + zero_band * lambda1)
      checks.failed.push_back(fmt::format("it exceeds the largest exponent of the divergence "
                                          "curves (at most {})",
                                          rate(divergence_high)));
    if (checks.failed.empty()) genuine.push_back(forward[i]);
    exponents.push_back(exponent_json(i, spectra, ci, checks, rate));
  }
  return exponents;
}

// Kaplan-Yorke dimension (defined here only with a positive genuine exponent: chaos) and the
// sum of the genuine exponents.
struct GenuineSpectrum {
  std::vector<double> exponents;
  double sum = 0, kaplan_yorke = nan;
  bool dissipative = false;
};

GenuineSpectrum genuine_spectrum(std::vector<double> genuine, double lambda1) {
  GenuineSpectrum g;
  g.exponents = std::move(genuine);
  for (double v : g.exponents) g.sum += v;
  double partial = 0;
  if (!g.exponents.empty() && g.exponents.front() > zero_band * lambda1)
    for (std::size_t j = 0; j < g.exponents.size(); ++j) {
      if (partial + g.exponents[j] < 0) {
        g.kaplan_yorke = double(j) + partial / std::abs(g.exponents[j]);
        break;
      }
      partial += g.exponents[j];
    }
  g.dissipative = !g.exponents.empty() && g.sum < 0;
  return g;
}

// Cross-checks with the other methods' results in the study: D2 <= D1 <= D_KY (Kaplan-Yorke
// conjecture: a D2 well above D_KY contradicts the spectrum), and the divergence estimate.
// Returns the text of the checks; adds doubts.
std::string cross_checks(const Json& context, const GenuineSpectrum& g, double largest,
                         const RateText& rate, std::vector<std::string>& doubts) {
  std::string checks;
  const auto d2 = nonlinear::context_value(context, "correlation_dimension", "correlation_dimension");
  if (d2 && std::isfinite(g.kaplan_yorke)) {
    const bool consistent = *d2 <= g.kaplan_yorke + 0.2;
    checks += fmt::format("; Kaplan-Yorke dimension {:.3g} {} D2 = {:.3g}", g.kaplan_yorke,
                          consistent ? "is consistent with (D2 <= D_KY)" : "is below", *d2);
    if (!consistent)
      doubts.push_back(fmt::format("D2 = {:.3g} exceeds the Kaplan-Yorke dimension {:.3g}", *d2,
                                   g.kaplan_yorke));
  }
  const Json* l = lyapunov_result(context);
  if (!l) return checks;
  const std::string divergence = l->value("divergence", "");
  const Json& e = (*l)["lyapunov_max_per_sample"];
  if (divergence == "exponential" && e["value"].is_number()) {
    const double v = e["value"].get<double>();
    const bool inside = largest >= e["ci_low"].get<double>() && largest <= e["ci_high"].get<double>();
    const bool agrees = inside || std::abs(largest - v) <= divergence_agreement * std::abs(v);
    checks += fmt::format("; the divergence estimate is {}{}", rate(v), agrees ? " (agrees)" : "");
    if (!agrees) doubts.push_back(fmt::format("the divergence curves give {}", rate(v)));
    // Agreement with a doubtful estimate confirms nothing: what makes the divergence estimate
    // uncertain (noise, a short series) biases the local fits as much.
    if (e.value("quality", "") != "good")
      doubts.push_back("the divergence estimate it is checked against is not good");
  } else if (divergence == "none" || divergence == "undetermined") {
    doubts.push_back(divergence == "none"
                         ? "the divergence curves show no exponential divergence"
                         : "the divergence curves show no common exponential divergence");
  }
  return checks;
}

}  // namespace

template <>
Json LyapunovSpectrum::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  FitSettings fit;
  fit.dimension = embedding.dimension;
  fit.delay = embedding.delay;
  fit.theiler = embedding.theiler;
  fit.evolution_steps = std::size_t(
      nonlinear::given_integer(params_, "evolution_steps").value_or(embedding.delay));
  fit.neighbours = nonlinear::given_integer(params_, "neighbours");
  fit.references = std::size_t(params_.integer("max_reference_points"));
  const Spectra spectra =
      compute_spectra(series.values, fit, params_.boolean("time_reversal_check"));
  const RateText rate{series.sample_interval, series.sample_unit};
  const auto& forward = spectra.forward.exponents;
  const std::size_t dims = forward.size();
  const double lambda1 = std::max(std::abs(forward[0]), 1e-12);
  std::vector<double> genuine;
  const Json exponents = classify_exponents(
      spectra, fit.dimension, divergence_upper_bound(context),
      std::size_t(params_.integer("bootstrap_replicates")),
      std::uint64_t(params_.integer("seed")), rate, genuine);
  const GenuineSpectrum g = genuine_spectrum(std::move(genuine), lambda1);
  // The spectrum's largest exponent: the first genuine one (else the first).
  std::size_t head = 0;
  while (head < dims && exponents[head]["spurious"].get<bool>()) ++head;
  if (head == dims) head = 0;
  std::vector<std::string> doubts;
  if (g.exponents.empty())
    doubts.push_back("every exponent is spurious");
  else if (head > 0)
    doubts.push_back(fmt::format("the {} largest exponents are spurious", head));
  if (!g.dissipative)
    doubts.push_back(fmt::format("the genuine exponents sum to {} (not negative: not the "
                                 "spectrum of a dissipative attractor)",
                                 rate(g.sum)));
  const std::string checks = cross_checks(context, g, forward[head], rate, doubts);
  const std::string quality = doubts.empty() ? "good" : "uncertain";
  std::string reason = fmt::format("largest genuine exponent of the local-Jacobian spectrum ({} "
                                   "of {} exponents genuine; their sum {}){}",
                                   g.exponents.size(), dims, rate(g.sum), checks);
  if (!doubts.empty()) reason += fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
  const Json& first = exponents[head];
  auto largest = [&](double f) {
    auto scaled = [&](const char* key) {
      return first[key].is_number() ? first[key].get<double>() * f : nan;
    };
    return nonlinear::estimate(scaled("value"), scaled("ci_low"), scaled("ci_high"), quality,
                               reason);
  };
  Json out;
  out["exponents_per_sample"] = exponents;
  out["reversed_exponents_per_sample"] = spectra.reversed;
  out["higher_dimension_exponents_per_sample"] = spectra.higher;
  out["lyapunov_max_per_sample"] = largest(1.0);
  if (rate.unit != "sample") out["lyapunov_max_per_" + rate.unit] = largest(1.0 / rate.dt);
  out["genuine_exponents"] = g.exponents.size();
  out["sum_per_sample"] = g.sum;  // of the genuine exponents: < 0 for a dissipative system
  out["dissipative"] = g.dissipative;
  out["kaplan_yorke_dimension"] = std::isfinite(g.kaplan_yorke) ? Json(g.kaplan_yorke) : Json();
  out["evolution_steps"] = fit.evolution_steps;
  out["neighbours"] = fit.neighbours_for(fit.dimension);
  add_embedding_fields(out, embedding);
  return out;
}

template <>
void LyapunovSpectrum::plot(const Json& result, const SampledSeries& series,
                            const std::filesystem::path& out_dir) const {
  plot::Curves c;
  c.title = fmt::format("{}: Lyapunov spectrum (forward, -reversed, one dimension more)",
                        series.name.empty() ? std::string("series") : series.name);
  c.x_label = "exponent index i";
  c.y_label = fmt::format("lambda_i [1/{}]", series.sample_unit);
  plot::Series forward{"lambda_i (dimension m)", {}, {}, "linespoints"},
      spurious{"spurious", {}, {}, "points"},
      reversed{"-lambda_rev (reversed series)", {}, {}, "points"},
      higher{"lambda_i (dimension m + 1)", {}, {}, "points"};
  const auto& e = result["exponents_per_sample"];
  const auto rev = result["reversed_exponents_per_sample"].get<std::vector<double>>();
  const auto up = result["higher_dimension_exponents_per_sample"].get<std::vector<double>>();
  const double dt = series.sample_interval;
  for (std::size_t i = 0; i < e.size(); ++i) {
    const double v = e[i]["value"].get<double>() / dt;
    forward.x.push_back(double(i + 1));
    forward.y.push_back(v);
    if (e[i]["spurious"].get<bool>()) {
      spurious.x.push_back(double(i + 1));
      spurious.y.push_back(v);
    }
    if (!rev.empty()) {
      reversed.x.push_back(double(i + 1));
      reversed.y.push_back(-rev[e.size() - 1 - i] / dt);
    }
  }
  for (std::size_t i = 0; i < up.size(); ++i) {
    higher.x.push_back(double(i + 1));
    higher.y.push_back(up[i] / dt);
  }
  c.series.push_back(forward);
  if (!spurious.x.empty()) c.series.push_back(spurious);
  if (!reversed.x.empty()) c.series.push_back(reversed);
  if (!higher.x.empty()) c.series.push_back(higher);
  c.reference_y = 0.0;
  c.integer_x = true;
  plot::render(c, out_dir, "lyapunov_spectrum");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::LyapunovSpectrum);
