#pragma once
// Floquet stability of linear delay-differential-algebraic systems with periodic coefficients and
// periodic delays (MODELS.md G7, S1-S3):
//
//   E x'(t) = A0(t) x(t) + sum_k A_k(t) x(t - tau_k(t)),   E = diag(1 differential, 0 algebraic),
//
// all T-periodic (a modulated spindle speed makes the revolution delay tau(t) periodic; an
// unbalance modulates the stiffness once per revolution). The monodromy operator over one period
// is discretised by semi-discretisation (Insperger & Stepan 2002, "Semi-discretization method for
// delayed systems", Int. J. Numer. Meth. Eng. 55; 2004, "Updated semi-discretization method for
// periodic delay-differential equations with discrete delay", IJNME 61; the book Semi-Discretization
// for Time-Delay Systems, Springer 2011): on each step of length h the undelayed part is
// integrated exactly (matrix exponential with coefficients frozen at the step's midpoint), the
// delayed values are a cubic Lagrange interpolant of the stored history along the exact delayed
// argument t - tau(t) (linearised over the step), and the algebraic variables are solved at each
// step end. The dominant eigenvalue mu of the discretised operator gives the Floquet growth rate
// ln|mu| / T; the step is halved until two levels agree within the tolerance (the convergence
// check). mu comes from Arnoldi's method on the step maps applied to vectors (matrix-free; the
// dense monodromy and its full spectrum only when Arnoldi does not converge, or on request).
// docs/derived_stability.md.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/dynamics.hpp"

namespace chatterlab {

class LinearisedModel;

class PeriodicDelaySystem {
 public:
  virtual ~PeriodicDelaySystem() = default;
  virtual std::size_t size() const = 0;
  virtual std::vector<bool> differential() const = 0;  // E's diagonal pattern (E = I there)
  virtual std::size_t delay_count() const = 0;
  virtual double period_s() const = 0;
  virtual double delay_s(std::size_t k, double t_s) const = 0;  // tau_k(t) > 0
  // tau_k at each of `times_s` (increasing): the discretisation asks for a whole period at once,
  // so that a system whose delays are solved (a revolution of a modulated rotor) can start each
  // solve from the previous ones.
  virtual void delays_s(std::size_t k, const std::vector<double>& times_s, std::vector<double>& out) const {
    out.resize(times_s.size());
    for (std::size_t i = 0; i < times_s.size(); ++i) out[i] = delay_s(k, times_s[i]);
  }
  virtual double max_delay_s() const = 0;                        // over all k and t
  virtual double min_delay_s() const = 0;
  // A0(t) (n x n) and A_k(t) (n x n each).
  virtual void coefficients(double t_s, Eigen::MatrixXd& a0, std::vector<Eigen::MatrixXd>& delayed) const = 0;
  // The highest frequency the dynamics carries [Hz]: the steps resolve it.
  virtual double frequency_scale_hz() const = 0;
  // Multipliers mu = 1 of a family of steady states (G1's cumulative removal), excluded like the
  // neutral root s = 0 of the characteristic route.
  virtual int family_multipliers() const { return 0; }
};

struct FloquetSettings {
  double steps_per_wave = 16.0;     // first level: h <= 1 / (steps_per_wave * frequency_scale_hz)
  double tolerance_per_s = 1e-3;    // accepted error estimate of the growth rate ...
  double relative_tolerance = 1e-3; // ... plus this fraction of |growth rate|
  std::size_t max_dimension = 3000; // of the discretised monodromy (a dense eigenvalue solve costs n^3)
  // The dominant multiplier from the full spectrum of the dense monodromy instead of Arnoldi's
  // method on the step maps (the reference the Krylov solve is tested against; slower).
  bool dense_spectrum = false;
};

struct FloquetResult {
  Complex multiplier;                 // dominant multiplier (Im >= 0), family multipliers excluded
  double growth_rate_per_s = 0.0;     // ln|mu| / T on the finest level
  double growth_rate_error_per_s = 0; // |sigma(h) - sigma(2h)| / 3 (error of sigma(h) for order >= 2)
  bool converged = false;             // error estimate <= tolerance
  int steps_per_period = 0;
  std::size_t dimension = 0;
  int family_multipliers_excluded = 0;
  std::string method;                 // what was computed, for the record
};

// The first (coarsest) level the convergence check starts from: steps per period and the
// monodromy's dimension (what a study checks against max_dimension before it runs).
struct FloquetLevel {
  int steps_per_period = 0;
  std::size_t dimension = 0;
};
FloquetLevel first_floquet_level(const PeriodicDelaySystem& system, const FloquetSettings& settings = {});

// Throws PointFailure when the system cannot be discretised within max_dimension or the
// eigenvalue solver fails; a result that did not converge is returned with converged = false.
FloquetResult floquet_growth_rate(const PeriodicDelaySystem& system, const FloquetSettings& settings = {});

// ------------------------------------------------------------------ models written once

// The speeds of a periodic process: null = constant at the model's nominal speed. Laws must be
// periodic with period_s (the modulation period, or a revolution when only an angle matters).
struct PeriodicProcess {
  std::shared_ptr<const SpeedLaw> speed[rotor_count];
  double period_s = 0.0;
};

// The periodic linearisation of a model written once (linearised_model.hpp): its Jacobian at
// each time with the speeds and angles of the process, and the delays one revolution of each
// regenerated rotor by angle. The model must stay referenced while the system is used.
std::unique_ptr<PeriodicDelaySystem> periodic_surface_system(const LinearisedModel& model,
                                                             const PeriodicProcess& process);

}  // namespace chatterlab
