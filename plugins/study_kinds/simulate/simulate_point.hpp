#pragma once
// The `simulate` kind's work on one grid point after the engine has run: the growth-rate fit and
// spectrum, the part quality of the final work surface, and the point's files and figures.
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/fit_validity.hpp"
#include "chatterlab/spectrum.hpp"
#include "chatterlab/study_kind.hpp"
#include "study_kinds/simulate/simulate.hpp"

namespace chatterlab::simulate_point {

// The envelope fit over the fit window, its validity, and the spectrum of that window.
struct PointAnalysis {
  std::optional<EnvelopeFit> fit;
  std::optional<FitValidity> validity;  // with fit: can the fitted growth be trusted (issue 19)
  std::string fit_problem;
  std::optional<Spectrum> spectrum;
  std::vector<SpectralPeak> peaks;
  double max_displacement = 0.0;
};
// `longest_delay_s`: kit::longest_delay_s of the model (the default window and the validity need it).
PointAnalysis analyse(const SimulationResult& r, const kit::SimulationTable& sim, double longest_delay_s);

// The analysis that measures profile quality (Analysis::profile_quality()), the first by name of
// those registered; null when the build has none.
const Registry<Analysis>::Entry* profile_quality_analysis();

// The final work surface measured: its summary ("problem" when it could not be) and the numbers.
struct WorkSurfaceQuality {
  Json summary;
  Json wt_um, wz_um, ront_um;  // null when not measured
  std::optional<SampledSeries> profile_m;  // the measured profile, for the figures
  ProfileSpeeds speeds;                    // the speeds of the revolution that cut it
  std::unique_ptr<Analysis> analysis;      // the measuring instance
};
WorkSurfaceQuality measure_work_surface(const SimulationResult& r, const Json& surface_table,
                                        double infeed_rate_m_per_s);

// timeseries.csv (or .npy), surfaces_NN.csv, spectrum.csv, summary.json and (with context.plots) figures.
void write_point_files(const SimulationResult& r, const PointAnalysis& a, const WorkSurfaceQuality& quality,
                       const Json& document, const SimulateSettings& settings, const PointContext& context);

// A rotor's removal so far over one revolution, minus the infeed ramp: the angle cut last carries
// a revolution's more infeed (or wear) than the angle about to be cut, so the unrolled surface is
// a sawtooth of one step per revolution on which the chatter waves ride. The ramp is the line
// a + c u in u = (i - b) mod n, the samples counted from the step b; b is the one whose line fits
// best (all b share the sums of u, u^2 and y, so only sum(u y) depends on b, and it follows from
// prefix sums). A ramp whose rise c n is below twice the residual rms is none (the best of n
// breakpoints finds a sawtooth in any random waviness): then only the mean is removed and the
// rise is 0. The surface plots show the residual and name the rise.
struct Deramped {
  std::vector<double> values;
  double rise_per_revolution = 0.0;
};
Deramped without_infeed_ramp(std::span<const double> removal);

}  // namespace chatterlab::simulate_point
