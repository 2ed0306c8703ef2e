#pragma once
// Modal parameters from a measured FRF (docs/analysis/frf.md): what turns a tap test into the modes
// of MODELS.md G1 (H(s) = sum_i (1/k_i)/(s^2/w_i^2 + 2 zeta_i s/w_i + 1)).
//
//   1. Poles: least-squares complex-frequency (LSCF) common-denominator fits of increasing order
//      (z-domain basis Omega = e^{-j w dt}, dt = 1/(2 f_max), reduced normal equations), each
//      order's poles from the denominator's companion matrix;
//   2. stabilisation diagram: a pole is "stable" when the next lower order has one within the
//      frequency and damping tolerances ("stable in frequency" within the frequency tolerance
//      only); the poles stable at least in frequency are clustered by frequency and a cluster
//      present in enough orders is a physical mode (automatic selection);
//   3. modal compliances 1/k_i and residual terms (upper: a constant compliance of the modes above
//      the band; lower: -1/(M w^2) of those below) by linear least squares with the poles fixed
//      (LSFD), then every parameter refined together by Levenberg-Marquardt on the complex misfit;
//   4. standard uncertainties from that last fit: s^2 (J^T W J)^{-1}, s^2 the residual variance.
//
// Real (proportionally damped) modes, as G1 uses them; the relative misfit says how well that
// describes the measurement.
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/frf.hpp"
#include "chatterlab/param_table.hpp"

namespace chatterlab {

enum class FitWeighting { relative, uniform };

struct ModalFitSettings {
  std::optional<double> min_frequency_hz;  // fit band; default: the measured band
  std::optional<double> max_frequency_hz;
  int max_order = 48;              // highest LSCF order (poles in z; a mode takes two)
  double frequency_tolerance = 0.01;  // stabilisation: |delta f|/f between consecutive orders
  double damping_tolerance = 0.05;    // |delta zeta|/zeta
  double max_damping_ratio = 0.2;     // poles more damped than this are not modes
  double min_stable_fraction = 0.3;   // a mode is stable in at least this fraction of the orders
  std::optional<int> modes;           // keep this many modes (most persistent); default: all selected
  // Weights of the compliance fit and the refinement (the pole fit is unweighted):
  // relative: each line weighted by 1/|H| (errors proportional to the response, as a hammer test's
  // are away from anti-resonances); uniform: every line alike.
  FitWeighting weighting = FitWeighting::relative;
};
const ParamTable<ModalFitSettings>& modal_fit_settings_table();

struct FittedMode {
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  double stiffness_n_per_m = 0.0;  // modal stiffness k: static compliance 1/k (negative: a mode seen in antiphase)
  // Standard uncertainties (one standard deviation).
  double frequency_sd_hz = 0.0;
  double damping_ratio_sd = 0.0;
  double stiffness_sd_n_per_m = 0.0;
  int stable_orders = 0;  // orders in which the diagram found this mode's pole stable (at least in frequency)
};

struct StabilisationPole {
  enum class Status { new_pole, frequency_stable, stable };
  int order = 0;
  double frequency_hz = 0.0;
  double damping_ratio = 0.0;
  Status status = Status::new_pole;
};

struct ModalFit {
  std::vector<FittedMode> modes;  // ascending frequency
  double upper_residual_m_per_n = 0.0;   // compliance of the modes above the band
  double lower_residual_kg = 0.0;        // M of -1/(M w^2) for the modes below the band (0: none)
  double min_frequency_hz = 0.0, max_frequency_hz = 0.0;  // fit band
  std::vector<StabilisationPole> stabilisation;  // every physical-looking pole of every order
  std::vector<int> orders;                       // the orders fitted
  double relative_misfit = 0.0;  // sqrt(sum |H_fit - H|^2 / sum |H|^2) over the band
  int lines = 0;                 // measured lines in the band
  int refinement_iterations = 0;

  // The synthesised receptance [m/N] at frequency_hz: modes plus residual terms.
  Complex receptance(double frequency_hz) const;
  // The modes alone (what a G1 model uses).
  Complex modal_receptance(double frequency_hz) const;
};

// Throws InputError when the band holds too few lines or no mode is found (the message says what
// the stabilisation diagram saw and which setting to change).
ModalFit fit_modes(const MeasuredFrf& frf, const ModalFitSettings& settings);

// Receptance of real modes at frequency_hz (G1's H(j w)).
Complex modes_receptance(const std::vector<FittedMode>& modes, double frequency_hz);

// A model capability (Model::measured_machine()): the model's machine compliance comes from a
// measured FRF. Kinds show the measurement and the fit next to their results (kit::plot_modal_fit).
class MeasuredMachine {
 public:
  virtual ~MeasuredMachine() = default;
  virtual const MeasuredFrf& measured_frf() const = 0;
  // The fit the model uses, or null when it uses the measured FRF directly.
  virtual const ModalFit* modal_fit() const = 0;
};

}  // namespace chatterlab
