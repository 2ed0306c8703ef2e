#pragma once
// The grinding dynamics engine (MODELS.md G1, G5..G7 in the time domain): a model's structural
// dynamics integrated with the wheel and work surfaces stored by rotation angle. The regenerative
// term reads a surface "one revolution ago" by angle, so any speed law n(t) is exact (constant,
// modulated, scheduled, or a state of the model as in G5), not a constant-delay approximation.
// Two routes (docs/dynamics.md): the fixed-step engine (default; exact exponential propagation
// for models that declare a LinearForm, classical Runge-Kutta otherwise) and the adaptive
// SUNDIALS reference (ARKODE ERKStep or CVODE Adams) that its equivalence tests compare against.
//
// A model supplies physics only (TimeDomainModel): its state size, the contact law (penetration,
// force and removal per surface from the state and the surfaces one revolution ago) and the
// state derivatives given the contact force. The engine owns integration, surface memory,
// one-sided contact (events), output sampling, divergence and step-size checks.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace chatterlab {

// ------------------------------------------------------------------ speed laws

// Speed of a rotating body (wheel or workpiece) over time. angle_rad is the exact integral of the
// speed, so surfaces indexed by angle stay exact under any law. Speeds must stay > 0.
class SpeedLaw {
 public:
  virtual ~SpeedLaw() = default;
  virtual double rpm(double t_s) const = 0;
  // Rotation angle since t = 0 [rad]: integral of 2 pi rpm(t)/60.
  virtual double angle_rad(double t_s) const = 0;
  // Bounds of rpm over [0, t_end_s] (for sizing surface memory and the largest step).
  virtual double min_rpm(double t_end_s) const = 0;
  virtual double max_rpm(double t_end_s) const = 0;
};

// Periodic modulation of a mean speed: rpm(t) = mean (1 + amplitude_ratio w(2 pi f t)) with w a
// unit sine, triangle (same phase as the sine) or square wave (+1 on the first half period).
enum class SpeedModulation { constant, sinusoidal, triangular, square };

// Throws std::invalid_argument unless mean_rpm > 0, 0 <= amplitude_ratio < 1 (a spindle that
// would stop or reverse) and frequency_hz >= 0 (and > 0 unless constant or amplitude 0).
std::unique_ptr<SpeedLaw> make_modulated_speed(double mean_rpm, SpeedModulation shape,
                                               double amplitude_ratio, double frequency_hz);
// Piecewise-linear schedule through (times_s[i], rpm[i]) (times strictly increasing, starting at
// 0, every rpm > 0), held constant after the last point. std::invalid_argument otherwise.
std::unique_ptr<SpeedLaw> make_scheduled_speed(std::vector<double> times_s, std::vector<double> rpm);
SpeedModulation parse_speed_modulation(const std::string& name);  // std::invalid_argument

// Commanded infeed u(t) [m] and its rate (a variable feed, MODELS.md S1). Null in the settings:
// the constant rate infeed_rate_m_per_s.
class InfeedLaw {
 public:
  virtual ~InfeedLaw() = default;
  virtual double infeed_m(double t_s) const = 0;
  virtual double rate_m_per_s(double t_s) const = 0;
};

// ------------------------------------------------------------------ model interface

enum class Rotor { wheel = 0, work = 1 };
inline constexpr std::size_t rotor_count = 2;
const char* to_string(Rotor rotor);

// What the engine hands the model at time t.
struct ContactInput {
  double t_s = 0.0;
  std::span<const double> state;
  double infeed_m = 0.0;             // commanded infeed u(t) (G1 U0)
  double infeed_rate_m_per_s = 0.0;  // its rate du/dt
  // Per rotor (index by Rotor): speed [rpm] and the surface one revolution ago at the current
  // contact point [m of radius removed so far] (averaged over the contact arc when set); 0 for a
  // surface the model does not regenerate.
  double speed_rpm[rotor_count] = {0.0, 0.0};
  double angle_rad[rotor_count] = {0.0, 0.0};  // rotation angle since t = 0 (e.g. unbalance phase)
  double previous_surface_m[rotor_count] = {0.0, 0.0};
};

// What the model returns. In contact when penetration_m > 0 (one-sided contact: the engine then
// zeroes force and removal itself when penetration_m <= 0; bilateral contact uses the values as
// they are, i.e. a linear model).
struct ContactOutput {
  double penetration_m = 0.0;   // signed wheel-work interference; the contact event is its zero
  double normal_force_n = 0.0;  // force while in contact (linear in penetration for G1)
  double tangential_force_n = 0.0;
  double depth_of_cut_m = 0.0;  // work depth removed this pass (reported)
  // New removal added to each regenerated surface on this pass [m].
  double removed_m[rotor_count] = {0.0, 0.0};
};

// Initial disturbance of the structure (the simulation's [simulation] settings).
struct Disturbance {
  double displacement_m = 0.0;
  double velocity_m_per_s = 0.0;
};

// Optional structure of a model, used by the fixed-step engine (docs/dynamics.md): between
// contact events its state equation is linear with constant coefficients and driven by one scalar
// forcing f that never depends on the state:
//
//   in contact:      dx/dt = contact_matrix x + contact_input f(t)
//   out of contact:  dx/dt = free_matrix x + free_input f(t)        (one-sided contact only)
//
// f = TimeDomainModel::linear_forcing(in) may depend on t, the infeed, the speeds and angles and
// the surfaces one revolution ago (the engine evaluates it ahead of the state, at times whose
// surfaces are already written). G1: contact_matrix = A - k b c^T (the contact spring k =
// 1/(1/kc + 1/kg + 1/kw) folded into the modal matrix A), contact_input = k b, f = U0 - Wg(t - Tg)
// - Ww(t - Tw); free_matrix = A, free_input = 0. The engine then propagates the state exactly (a
// matrix exponential per step) and evaluates the model only where it needs the contact output;
// derivatives() must agree with the form (checked at the start of every run).
struct LinearForm {
  std::vector<double> contact_matrix, free_matrix;  // state_size x state_size, row-major
  std::vector<double> contact_input, free_input;    // state_size
};

class TimeDomainModel {
 public:
  virtual ~TimeDomainModel() = default;

  virtual std::size_t state_size() const = 0;
  // State at t = 0 for the disturbance (default: the structure at rest).
  virtual void initial_state(const Disturbance& disturbance, std::span<double> state) const = 0;
  // Typical magnitude of each state component for a displacement of displacement_m (sets
  // CVODE's absolute tolerances): displacements ~ d, velocities ~ d w, angles ~ 1, ...
  virtual void state_scales(double displacement_m, std::span<double> scales) const = 0;
  // Highest frequency the response can carry [Hz]: sizes surface resolution and the step limit.
  virtual double highest_frequency_hz() const = 0;

  // Surfaces stored and regenerated (G1: both, either switch may turn one off).
  virtual bool regenerates(Rotor rotor) const = 0;
  // Nominal (mean) speed [rpm] of each rotor; the simulation may replace it by a SpeedLaw.
  virtual double nominal_speed_rpm(Rotor rotor) const = 0;
  // G5: a rotor whose angle is a state of the model (index of the angle [rad] in the state
  // vector; its speed then comes from speed_rpm_from_state). Default: angles from speed laws.
  virtual std::optional<std::size_t> angle_state(Rotor /*rotor*/) const { return std::nullopt; }
  virtual double speed_rpm_from_state(Rotor /*rotor*/, std::span<const double> /*state*/) const {
    return 0.0;
  }

  virtual void contact(const ContactInput& in, ContactOutput& out) const = 0;
  // State derivatives with the contact output the engine settled (force zero out of contact).
  virtual void derivatives(const ContactInput& in, const ContactOutput& contact,
                           std::span<double> state_derivative) const = 0;
  // The reported structural displacement [m] (x of G1: the sum of modal displacements).
  virtual double displacement_m(std::span<const double> state) const = 0;
  // Model-specific diagnostics gathered during a run (e.g. G5: wheel speed near zero).
  virtual std::vector<std::string> diagnostics() const { return {}; }

  // The linear form (above) in force at t_s, if the model has one; models whose parameters
  // change at known times (a feed plan's segments) return the form of the segment holding t_s and
  // announce the changes through next_linear_form_change_s. Default: none (the fixed-step engine
  // then integrates derivatives() by classical Runge-Kutta).
  virtual std::optional<LinearForm> linear_form(double /*t_s*/) const { return std::nullopt; }
  // Identifies equal forms (the engine keeps the propagators of each id it met); a model with one
  // form returns 0.
  virtual std::size_t linear_form_id(double /*t_s*/) const { return 0; }
  // First time > t_s at which the linear form changes (infinity: never).
  virtual double next_linear_form_change_s(double /*t_s*/) const;
  // The scalar forcing f of the linear form. `in.state` is empty: f must not depend on the state.
  virtual double linear_forcing(const ContactInput& /*in*/) const { return 0.0; }
};

// ------------------------------------------------------------------ simulation

// One output sample, as SimulationResult stores it (index arrays by Rotor).
struct OutputSample {
  double t_s = 0.0, displacement_m = 0.0, force_n = 0.0, depth_of_cut_m = 0.0, infeed_m = 0.0;
  double speed_rpm[rotor_count] = {0.0, 0.0};
  double surface_at_contact_m[rotor_count] = {0.0, 0.0};
  bool in_contact = true;
};

// Time integrator of the dynamics engine (docs/dynamics.md, settings). fixed_step: the fast
// engine (fixed steps tuned to the model's highest frequency; exact exponential propagation of a
// LinearForm, classical fourth-order Runge-Kutta otherwise). The adaptive SUNDIALS reference route:
// ARKODE ERKStep (explicit_runge_kutta, Dormand-Prince 5(4) with error control) or CVODE Adams
// (fixed-point iteration).
enum class TimeIntegrator { fixed_step, adams, explicit_runge_kutta };
const char* to_string(TimeIntegrator integrator);
TimeIntegrator parse_time_integrator(const std::string& name);  // std::invalid_argument

struct SimulationSettings {
  double duration_s = 1.0;
  double sample_rate_hz = 20000.0;  // output samples (t = i / rate)
  Disturbance disturbance{1e-6, 0.0};
  double initial_waviness_m = 0.0;  // random initial work and wheel surfaces (uniform +/-), seed
  std::uint64_t seed = 1;
  double infeed_rate_m_per_s = 0.0;  // u(t) = rate * t (the mean rate when `infeed` is set)
  std::shared_ptr<const InfeedLaw> infeed;  // a time-varying infeed; null: u = rate * t
  bool one_sided_contact = true;     // false: bilateral (linear) contact
  // Geometric filtering (G4 option): the previous surface is averaged over this arc [deg] around
  // the contact point; 0 = point contact.
  double contact_arc_deg[rotor_count] = {0.0, 0.0};
  // Speed laws per rotor; null: constant at the model's nominal speed.
  std::shared_ptr<const SpeedLaw> speed[rotor_count];
  std::vector<double> snapshot_times_s;  // surfaces recorded at these times (<= duration)
  TimeIntegrator integrator = TimeIntegrator::fixed_step;
  // Fixed-step engine: steps per wave at highest_frequency_hz (h <= 1/(this f_max); 0 = the
  // documented default: 10 exponential, 40 exponential with one-sided contact, 60 Runge-Kutta).
  // With random initial waviness the step is also at most 3/4 of the time between two surface
  // samples; it is shortened so that output samples fall on step ends where the interval allows.
  double fixed_steps_per_wave = 0.0;
  double relative_tolerance = 1e-6;  // SUNDIALS routes: growth rate to ~1e-5 relative (docs/dynamics.md)
  double samples_per_wave = 16.0;   // surface samples per wave at highest_frequency_hz
  double max_steps_per_wave = 4.0;  // SUNDIALS routes: largest step <= 1/(this * highest_frequency_hz)
  double divergence_limit_m = 1.0;  // |displacement| beyond this ends the run as "diverged"
  // Streaming (long runs, e.g. a 3000 s feed plan): on_sample, when set, is called with every
  // output sample in time order; with store_samples = false the series of SimulationResult stay
  // empty and the max_output_samples limit does not apply.
  std::function<void(const OutputSample&)> on_sample;
  bool store_samples = true;
};

struct SurfaceSnapshot {
  double t_s = 0.0;
  std::vector<double> angle_deg;  // body-fixed angle, 0..360 (work and wheel on one grid)
  std::vector<double> surface_m[rotor_count];  // removal so far at each angle, per rotor
};

struct SimulationResult {
  // Output samples (uniform in time, t = i / sample_rate_hz, up to the end of the run).
  std::vector<double> t_s, displacement_m, force_n, depth_of_cut_m, infeed_m;
  std::vector<double> speed_rpm[rotor_count];
  std::vector<double> surface_at_contact_m[rotor_count];  // previous surface at the contact
  std::vector<double> in_contact;                         // 1 or 0
  std::vector<SurfaceSnapshot> snapshots;
  std::vector<std::pair<double, double>> contact_loss_intervals;  // [start, end] in s
  double contact_loss_time_s = 0.0;
  bool diverged = false;
  double end_time_s = 0.0;
  std::string status;  // "completed" or "diverged at t = ... s (...)"
  std::vector<double> end_state;
  std::vector<std::string> diagnostics;
  long steps = 0, rhs_evaluations = 0, contact_events = 0;
  std::size_t surface_samples_per_rev[rotor_count] = {0, 0};
  // How the run was integrated, e.g. "fixed step 1.6667e-04 s, exact exponential (linear form)"
  // or "ARKODE ERKStep (Dormand-Prince 5(4)), rtol 1e-06".
  std::string method;
  double fixed_step_s = 0.0;  // the fixed-step engine's step (0 for the SUNDIALS routes)
};

// Output samples of a run beyond which it is refused before it starts (memory of the series).
inline constexpr double max_output_samples = 5e7;

// Integrates the model. Throws std::invalid_argument for settings outside their limits (the
// study kind checks them first, with file and line) and PointFailure when the integrator fails
// (SUNDIALS: a set-up call refused, naming the routine and its flag; step-size collapse, too much
// work, naming the time and step size; any route: a right-hand side that is not finite). A
// divergent response is not an error: the run stops there and status/diverged say so, all
// outputs finite.
SimulationResult simulate(const TimeDomainModel& model, const SimulationSettings& settings);

// ------------------------------------------------------------------ growth-rate fit

struct EnvelopeFit {
  double growth_rate_per_s = 0.0;  // slope of ln(envelope) by least squares
  double intercept = 0.0;          // ln envelope at t = 0
  double start_s = 0.0, end_s = 0.0;
  double residual_rms = 0.0;  // rms of the ln-envelope residual (quality of the exponential)
  std::vector<double> t_s, envelope;  // one envelope sample per period of the dominant frequency
};

// Envelope of x(t) over [start_s, end_s] (uniform samples): a least-squares line is removed,
// the dominant frequency f of the window is found (Hann spectrum), and the envelope is half the
// peak-to-peak swing of each consecutive period 1/f (extremes refined by a parabola), placed at
// the mean time of its two extremes; ln(envelope) is fitted by least squares. Local in time, so
// a response growing by orders of magnitude is fitted without leakage bias. Throws
// std::invalid_argument for fewer than 64 samples or 8 periods in the window. Spectral peaks
// below min_frequency_hz are not candidates for the dominant frequency (the slow deflection of
// an infeed transient, work-revolution waviness).
EnvelopeFit fit_envelope(std::span<const double> t_s, std::span<const double> x, double start_s,
                         double end_s, double min_frequency_hz = 0.0);

}  // namespace chatterlab
