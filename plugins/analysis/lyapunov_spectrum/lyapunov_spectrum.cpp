#include "analysis/lyapunov_spectrum/lyapunov_spectrum.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/embedding/embedding.hpp"
#include "analysis/nonlinear_common/nonlinear_common.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plot.hpp"

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

SpectrumEstimate lyapunov_spectrum(const std::vector<double>& x, int dimension, int delay,
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
      const double* b = e.point(i);
      const double* b1 = e.point(i + m);
      for (std::size_t r = 0; r < nn.size(); ++r) {
        const double* a0 = e.point(nn[r].index);
        const double* a1 = e.point(nn[r].index + m);
        for (Eigen::Index c = 0; c < d; ++c) {
          y(Eigen::Index(r), c) = a0[c] - b[c];
          z(Eigen::Index(r), c) = a1[c] - b1[c];
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

PluginInfo LyapunovSpectrum::info() {
  PluginInfo info;
  info.name = "lyapunov_spectrum";
  info.description =
      "Lyapunov spectrum from local Jacobian least-squares fits with QR re-orthonormalisation; "
      "spurious exponents flagged by one more embedding dimension and by time reversal; "
      "Kaplan-Yorke dimension and the sum of the exponents";
  info.models_md_ids = "N3";
  using nonlinear::numeric_spec;
  ParamSpec reversal = param_spec("time_reversal_check", ValueKind::boolean, "",
                                  "flag exponents that do not change sign for the reversed series");
  reversal.default_value = true;
  info.params = {
      nonlinear::delay_spec(), nonlinear::dimension_spec(), nonlinear::theiler_spec(),
      numeric_spec("evolution_steps", ValueKind::integer, "samples",
                   "samples over which each local Jacobian maps displacements (multi-step "
                   "evolution; absent: one delay)",
                   Json(), 1),
      numeric_spec("neighbours", ValueKind::integer, "1",
                   "nearest neighbours per local fit (absent: max(20, 4 x dimension))", Json(), 2),
      numeric_spec("max_reference_points", ValueKind::integer, "1",
                   "local fits along the trajectory at most", 10000, 20),
      reversal, nonlinear::bootstrap_spec(), nonlinear::seed_spec()};
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"max_reference_points", 300}};
  return info;
}

Json LyapunovSpectrum::analyse(const SampledSeries& series, const Json& context) const {
  const auto embedding = resolve_embedding(params_, series, context);
  const std::size_t m = std::size_t(
      nonlinear::given_integer(params_, "evolution_steps").value_or(embedding.delay));
  const auto neighbours_given = nonlinear::given_integer(params_, "neighbours");
  auto neighbours_for = [&](int dimension) {
    return std::size_t(neighbours_given.value_or(std::max(20, 4 * dimension)));
  };
  const std::size_t k = neighbours_for(embedding.dimension);
  const auto refs = std::size_t(params_.integer("max_reference_points"));
  const int dim = embedding.dimension;
  const auto forward = lyapunov_spectrum(series.values, dim, embedding.delay, embedding.theiler,
                                         m, k, refs);
  // One more dimension: genuine exponents persist, spurious ones (from fitting the local maps in
  // more dimensions than the attractor needs) move or appear (Parlitz 1992).
  std::vector<double> higher;
  if (series.values.size() >= nonlinear::minimum_samples(dim + 1, embedding.delay) + m + 20) {
    try {
      higher = lyapunov_spectrum(series.values, dim + 1, embedding.delay, embedding.theiler, m,
                                 neighbours_for(dim + 1), refs)
                   .exponents;
    } catch (const PointFailure&) {
      higher.clear();
    }
  }
  std::vector<double> reversed_exponents;
  if (params_.boolean("time_reversal_check")) {
    std::vector<double> reversed(series.values.rbegin(), series.values.rend());
    reversed_exponents = lyapunov_spectrum(reversed, dim, embedding.delay, embedding.theiler, m,
                                           k, refs)
                             .exponents;
  }
  const double dt = series.sample_interval;
  const std::string unit = series.sample_unit;
  const std::size_t dims = forward.exponents.size();
  const double lambda1 = std::max(std::abs(forward.exponents[0]), 1e-12);
  auto rate = [&](double v) {
    return unit == "sample" ? fmt::format("{:.4g} per sample", v)
                            : fmt::format("{:.4g} per {}", v / dt, unit);
  };
  // The divergence curves of `lyapunov` (when they show exponential divergence) bound the
  // spectrum from above: no exponent can exceed the largest one.
  double divergence_high = nan;
  if (context.is_object() && context.contains("lyapunov") && context["lyapunov"].is_object() &&
      context["lyapunov"].value("divergence", "") == "exponential") {
    const Json& e = context["lyapunov"]["lyapunov_max_per_sample"];
    if (e["ci_high"].is_number()) divergence_high = e["ci_high"].get<double>();
  }
  Json exponents = Json::array();
  std::vector<double> genuine;
  for (std::size_t i = 0; i < dims; ++i) {
    const auto ci = nonlinear::block_bootstrap(
        spectrum_blocks, std::size_t(params_.integer("bootstrap_replicates")),
        std::uint64_t(params_.integer("seed")) + i, [&](const std::vector<double>& w) {
          // Exponent i as the i-th largest of the resampled block averages.
          std::vector<double> total(dims, 0.0);
          double steps = 0;
          for (std::size_t b = 0; b < spectrum_blocks; ++b) {
            for (std::size_t j = 0; j < dims; ++j) total[j] += w[b] * forward.block_sums[b][j];
            steps += w[b] * forward.block_steps[b];
          }
          for (double& v : total) v /= steps;
          std::sort(total.begin(), total.end(), std::greater<>());
          return total[i];
        });
    const double lambda = forward.exponents[i];
    const bool near_zero_here = std::abs(lambda) < zero_band * lambda1;
    std::vector<std::string> failed, passed;
    // Only clearly positive exponents are checked in one more dimension: local fits estimate the
    // contracting directions of a flow poorly, and differently in every dimension, and the zero
    // exponent of a flow has no reliable sign (time reversal checks those).
    if (!higher.empty() && lambda >= zero_band * lambda1) {
      double closest = higher.front();
      for (double v : higher)
        if (std::abs(v - lambda) < std::abs(closest - lambda)) closest = v;
      const double tol = dimension_tolerance * std::max(lambda1, std::abs(lambda));
      (std::abs(closest - lambda) <= tol ? passed : failed)
          .push_back(fmt::format("in dimension {} the nearest exponent is {}", dim + 1,
                                 rate(closest)));
    }
    if (!reversed_exponents.empty()) {
      // True exponents change sign under time reversal: lambda_i ~ -lambda^rev_{d+1-i};
      // spurious ones keep their sign.
      const double partner = -reversed_exponents[dims - 1 - i];
      const bool confirmed = (lambda > 0) == (partner > 0) ||
                             (near_zero_here && std::abs(partner) < zero_band * lambda1);
      (confirmed ? passed : failed)
          .push_back(fmt::format("the reversed series gives -lambda_rev = {}", rate(partner)));
    }
    // Combinations of two other exponents, neither of them near zero (a flow's zero exponent
    // would make every exponent a "combination").
    for (std::size_t j = 0; j < dims && failed.empty(); ++j)
      for (std::size_t l = j; l < dims; ++l) {
        const double a = forward.exponents[j], b = forward.exponents[l];
        if (j == i || l == i || std::abs(a) < zero_band * lambda1 ||
            std::abs(b) < zero_band * lambda1)
          continue;
        if (std::abs(lambda - (a + b)) <=
            combination_tolerance * std::max(std::abs(lambda), lambda1)) {
          failed.push_back(fmt::format("it equals the sum of {} and {} (a combination exponent)",
                                       rate(a), rate(b)));
          break;
        }
      }
    if (std::isfinite(divergence_high) && lambda > divergence_high + zero_band * lambda1)
      failed.push_back(fmt::format("it exceeds the largest exponent of the divergence curves (at "
                                   "most {})",
                                   rate(divergence_high)));
    const bool spurious = !failed.empty();
    if (!spurious) genuine.push_back(lambda);
    const std::string reason =
        spurious ? fmt::format("spurious: {}", fmt::join(failed, "; "))
                 : (passed.empty() ? std::string("local Jacobian fits")
                                   : fmt::format("confirmed: {}", fmt::join(passed, "; ")));
    Json e = nonlinear::estimate(lambda, ci.low, ci.high, spurious ? "uncertain" : "good", reason);
    e["value_per_" + unit] = lambda / dt;
    e["ci_low_per_" + unit] = std::isfinite(ci.low) ? Json(ci.low / dt) : Json();
    e["ci_high_per_" + unit] = std::isfinite(ci.high) ? Json(ci.high / dt) : Json();
    e["spurious"] = spurious;
    exponents.push_back(e);
  }

  // Kaplan-Yorke dimension (defined here only with a positive genuine exponent: chaos) and the
  // sum of the genuine exponents.
  double sum = 0, partial = 0, kaplan_yorke = nan;
  for (double v : genuine) sum += v;
  if (!genuine.empty() && genuine.front() > zero_band * lambda1)
    for (std::size_t j = 0; j < genuine.size(); ++j) {
      if (partial + genuine[j] < 0) {
        kaplan_yorke = double(j) + partial / std::abs(genuine[j]);
        break;
      }
      partial += genuine[j];
    }
  const bool dissipative = !genuine.empty() && sum < 0;
  // The spectrum's largest exponent: the first genuine one (else the first).
  std::size_t head = 0;
  while (head < dims && exponents[head]["spurious"].get<bool>()) ++head;
  if (head == dims) head = 0;
  std::vector<std::string> doubts;
  if (genuine.empty())
    doubts.push_back("every exponent is spurious");
  else if (head > 0)
    doubts.push_back(fmt::format("the {} largest exponents are spurious", head));
  if (!dissipative)
    doubts.push_back(fmt::format("the genuine exponents sum to {} (not negative: not the "
                                 "spectrum of a dissipative attractor)",
                                 rate(sum)));
  // Cross-checks with the other methods' results in the study.
  std::string checks;
  if (const auto d2 = nonlinear::context_value(context, "correlation_dimension",
                                               "correlation_dimension")) {
    if (std::isfinite(kaplan_yorke)) {
      // D2 <= D1 <= D_KY (Kaplan-Yorke conjecture): a D2 well above D_KY contradicts the
      // spectrum.
      const bool consistent = *d2 <= kaplan_yorke + 0.2;
      checks += fmt::format("; Kaplan-Yorke dimension {:.3g} {} D2 = {:.3g}", kaplan_yorke,
                            consistent ? "is consistent with (D2 <= D_KY)" : "is below", *d2);
      if (!consistent)
        doubts.push_back(fmt::format("D2 = {:.3g} exceeds the Kaplan-Yorke dimension {:.3g}", *d2,
                                     kaplan_yorke));
    }
  }
  if (context.is_object() && context.contains("lyapunov") && context["lyapunov"].is_object()) {
    const Json& l = context["lyapunov"];
    const std::string divergence = l.value("divergence", "");
    const Json& e = l["lyapunov_max_per_sample"];
    if (divergence == "exponential" && e["value"].is_number()) {
      const double v = e["value"].get<double>();
      const double mine = forward.exponents[head];
      const bool inside = mine >= e["ci_low"].get<double>() && mine <= e["ci_high"].get<double>();
      const bool agrees = inside || std::abs(mine - v) <= divergence_agreement * std::abs(v);
      checks += fmt::format("; the divergence estimate is {}{}", rate(v),
                            agrees ? " (agrees)" : "");
      if (!agrees)
        doubts.push_back(fmt::format("the divergence curves give {}", rate(v)));
    } else if (divergence == "none" || divergence == "undetermined") {
      doubts.push_back(divergence == "none"
                           ? "the divergence curves show no exponential divergence"
                           : "the divergence curves show no common exponential divergence");
    }
  }
  const Json& first = exponents[head];
  const std::string quality = doubts.empty() ? "good" : "uncertain";
  std::string reason = fmt::format("largest genuine exponent of the local-Jacobian spectrum ({} "
                                   "of {} exponents genuine; their sum {}){}",
                                   genuine.size(), dims, rate(sum), checks);
  if (!doubts.empty()) reason += fmt::format("; uncertain: {}", fmt::join(doubts, "; "));
  Json out;
  out["exponents_per_sample"] = exponents;
  out["reversed_exponents_per_sample"] = reversed_exponents;
  out["higher_dimension_exponents_per_sample"] = higher;
  auto largest = [&](double f) {
    return nonlinear::estimate(first["value"].get<double>() * f,
                               first["ci_low"].is_number() ? first["ci_low"].get<double>() * f : nan,
                               first["ci_high"].is_number() ? first["ci_high"].get<double>() * f : nan,
                               quality, reason);
  };
  out["lyapunov_max_per_sample"] = largest(1.0);
  if (unit != "sample") out["lyapunov_max_per_" + unit] = largest(1.0 / dt);
  out["genuine_exponents"] = genuine.size();
  out["sum_per_sample"] = sum;  // of the genuine exponents: < 0 for a dissipative system
  out["dissipative"] = dissipative;
  out["kaplan_yorke_dimension"] = std::isfinite(kaplan_yorke) ? Json(kaplan_yorke) : Json();
  out["evolution_steps"] = m;
  out["neighbours"] = k;
  out["delay_samples"] = embedding.delay;
  out["embedding_dimension"] = embedding.dimension;
  out["theiler_window_samples"] = embedding.theiler;
  out["embedding_source"] = embedding.source;
  return out;
}

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
