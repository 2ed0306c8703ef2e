// The dynamics engine: CVODE (Adams, fixed-point iteration: the structural dynamics are not
// stiff) in one-step mode; after every step the regenerated surfaces are written at the angle
// grid points the contact passed, from CVODE's dense output, and the output samples are taken
// the same way. One SUNContext + integrator per call, so concurrent calls are independent.
// docs/dynamics.md explains the method and the settings.
#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "dynamics/surface_memory.hpp"

namespace chatterlab {

namespace {

using dynamics_detail::SurfaceMemory;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::size_t kMaxSurfaceSamples = std::size_t{1} << 22;

// RAII owners of the SUNDIALS objects.
struct Sundials {
  SUNContext context = nullptr;
  N_Vector y = nullptr, dky = nullptr, abstol = nullptr;
  SUNNonlinearSolver solver = nullptr;
  void* cvode = nullptr;
  Sundials() {
    if (SUNContext_Create(nullptr, &context) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~Sundials() {
    if (cvode) CVodeFree(&cvode);
    if (solver) SUNNonlinSolFree(solver);
    for (N_Vector v : {y, dky, abstol})
      if (v) N_VDestroy(v);
    SUNContext_Free(&context);
  }
  Sundials(const Sundials&) = delete;
  Sundials& operator=(const Sundials&) = delete;
};

void validate(const SimulationSettings& s) {
  auto positive = [](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0.0)) throw std::invalid_argument(fmt::format("{} must be > 0", what));
  };
  positive(s.duration_s, "duration_s");
  positive(s.sample_rate_hz, "sample_rate_hz");
  positive(s.relative_tolerance, "relative_tolerance");
  positive(s.samples_per_wave, "samples_per_wave");
  positive(s.max_steps_per_wave, "max_steps_per_wave");
  positive(s.divergence_limit_m, "divergence_limit_m");
  const double samples = s.duration_s * s.sample_rate_hz;
  if (s.store_samples && samples > max_output_samples)
    throw std::invalid_argument(fmt::format(
        "duration_s * sample_rate_hz = {:.4g} output samples exceeds the limit of {:.4g}: shorten "
        "the run or lower the sample rate",
        samples, max_output_samples));
  for (double arc : s.contact_arc_deg)
    if (!(std::isfinite(arc) && arc >= 0.0 && arc < 90.0))
      throw std::invalid_argument("contact arc must be in [0, 90) deg");
  for (double t : s.snapshot_times_s)
    if (!(std::isfinite(t) && t >= 0.0 && t <= s.duration_s))
      throw std::invalid_argument(fmt::format("snapshot time {} s is outside [0, duration_s]", t));
}

class Engine {
 public:
  Engine(const TimeDomainModel& model, const SimulationSettings& settings)
      : model_(model), settings_(settings), n_(model.state_size()), state_scratch_(n_) {
    validate(settings);
    f_max_ = model.highest_frequency_hz();
    if (!(std::isfinite(f_max_) && f_max_ > 0.0))
      throw std::logic_error("TimeDomainModel::highest_frequency_hz must be > 0");
    for (std::size_t r = 0; r < rotor_count; ++r) setup_rotor(static_cast<Rotor>(r));
    result_.end_state.assign(n_, 0.0);
  }

  SimulationResult run();

  // CVODE callbacks.
  static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* self) {
    auto& e = *static_cast<Engine*>(self);
    ++e.rhs_evaluations_;
    std::span<const double> x(N_VGetArrayPointer(y), e.n_);
    ContactInput in;
    ContactOutput out;
    e.evaluate_contact(t, x, in, out);
    e.model_.derivatives(in, out, std::span<double>(N_VGetArrayPointer(ydot), e.n_));
    return 0;
  }
  static int root(sunrealtype t, N_Vector y, sunrealtype* g, void* self) {
    auto& e = *static_cast<Engine*>(self);
    std::span<const double> x(N_VGetArrayPointer(y), e.n_);
    ContactInput in;
    ContactOutput out;
    e.evaluate_contact(t, x, in, out, false);
    g[0] = out.penetration_m;
    return 0;
  }
  static int error_weights(N_Vector y, N_Vector weights, void* self) {
    auto& e = *static_cast<Engine*>(self);
    const double* x = N_VGetArrayPointer(y);
    const double* atol = N_VGetArrayPointer(e.sun_.abstol);
    double* w = N_VGetArrayPointer(weights);
    for (std::size_t i = 0; i < e.n_; ++i) w[i] = 1.0 / (e.settings_.relative_tolerance * std::abs(x[i]) + atol[i]);
    return 0;
  }
  static void silent_error(int, const char*, const char*, char* message, void* self) {
    static_cast<Engine*>(self)->last_error_ = message;
  }

 private:
  struct RotorState {
    std::shared_ptr<const SpeedLaw> law;       // null when the angle is a model state
    std::optional<std::size_t> angle_state;    // index of the angle in the state
    std::optional<SurfaceMemory> surface;      // when regenerated
    double arc_rad = 0.0;
  };

  void setup_rotor(Rotor r) {
    RotorState& rotor = rotors_[static_cast<std::size_t>(r)];
    rotor.angle_state = model_.angle_state(r);
    double min_rpm = model_.nominal_speed_rpm(r);
    double max_rpm = min_rpm;
    if (!rotor.angle_state) {
      rotor.law = settings_.speed[static_cast<std::size_t>(r)];
      if (!rotor.law)
        rotor.law = make_modulated_speed(model_.nominal_speed_rpm(r), SpeedModulation::constant, 0.0, 0.0);
      min_rpm = rotor.law->min_rpm(settings_.duration_s);
      max_rpm = rotor.law->max_rpm(settings_.duration_s);
    } else {
      min_rpm *= 0.5;  // a state speed varies; resolve a revolution at half the nominal speed
      max_rpm *= 2.0;
    }
    if (!(min_rpm > 0.0)) throw std::invalid_argument(fmt::format("{} speed must stay > 0 rpm", to_string(r)));
    max_rpm_ = std::max(max_rpm_, max_rpm);
    rotor.arc_rad = settings_.contact_arc_deg[static_cast<std::size_t>(r)] * kTwoPi / 360.0;
    if (!model_.regenerates(r)) return;
    // Samples per revolution: samples_per_wave at the highest frequency over the longest
    // revolution, so the cubic interpolation error stays ~1e-5 of the wave amplitude.
    double wanted = std::ceil(settings_.samples_per_wave * f_max_ * 60.0 / min_rpm);
    auto samples = static_cast<std::size_t>(std::clamp(wanted, 64.0, static_cast<double>(kMaxSurfaceSamples)));
    if (wanted > static_cast<double>(kMaxSurfaceSamples))
      diagnostics_.push_back(fmt::format(
          "{} surface: {} samples per revolution capped at {} (speed down to {:.3g} rpm)",
          to_string(r), wanted, kMaxSurfaceSamples, min_rpm));
    std::vector<double> initial;
    if (settings_.initial_waviness_m > 0.0) {
      std::mt19937_64 random(settings_.seed + static_cast<std::uint64_t>(r));
      std::uniform_real_distribution<double> uniform(-settings_.initial_waviness_m,
                                                     settings_.initial_waviness_m);
      initial.resize(samples);
      for (double& v : initial) v = uniform(random);
    }
    rotor.surface.emplace(samples, std::move(initial));
    result_.surface_samples_per_rev[static_cast<std::size_t>(r)] = samples;
  }

  double rotor_angle(std::size_t r, double t, std::span<const double> x) const {
    const RotorState& rotor = rotors_[r];
    return rotor.law ? rotor.law->angle_rad(t) : x[*rotor.angle_state];
  }
  double rotor_rpm(std::size_t r, double t, std::span<const double> x) const {
    const RotorState& rotor = rotors_[r];
    return rotor.law ? rotor.law->rpm(t) : model_.speed_rpm_from_state(static_cast<Rotor>(r), x);
  }

  // Builds the model's input at (t, x) and settles one-sided contact.
  void evaluate_contact(double t, std::span<const double> x, ContactInput& in, ContactOutput& out,
                        bool settle = true) const {
    in.t_s = t;
    in.state = x;
    if (settings_.infeed) {
      in.infeed_m = settings_.infeed->infeed_m(t);
      in.infeed_rate_m_per_s = settings_.infeed->rate_m_per_s(t);
    } else {
      in.infeed_m = settings_.infeed_rate_m_per_s * t;
      in.infeed_rate_m_per_s = settings_.infeed_rate_m_per_s;
    }
    for (std::size_t r = 0; r < rotor_count; ++r) {
      in.speed_rpm[r] = rotor_rpm(r, t, x);
      in.angle_rad[r] = rotor_angle(r, t, x);
      const RotorState& rotor = rotors_[r];
      in.previous_surface_m[r] = rotor.surface ? rotor.surface->mean(in.angle_rad[r] - kTwoPi, rotor.arc_rad) : 0.0;
    }
    model_.contact(in, out);
    if (settle && settings_.one_sided_contact && !(out.penetration_m > 0.0)) {
      out.normal_force_n = out.tangential_force_n = out.depth_of_cut_m = 0.0;
      for (double& removed : out.removed_m) removed = 0.0;
    }
  }

  // State at t inside the last step (dense output), or the initial state before any step.
  std::span<const double> state_at(double t) {
    if (!stepped_) return {N_VGetArrayPointer(sun_.y), n_};
    if (CVodeGetDky(sun_.cvode, t, 0, sun_.dky) != CV_SUCCESS)
      throw std::logic_error("CVodeGetDky outside the last step");
    return {N_VGetArrayPointer(sun_.dky), n_};
  }

  // Time in [t_lo, t_hi] at which rotor r reaches angle `target` (angles increase): Newton on
  // angle(t) with the speed as derivative, kept inside a shrinking bracket.
  double time_of_angle(std::size_t r, double target, double t_lo, double t_hi) {
    const RotorState& rotor = rotors_[r];
    // A speed law needs no state: angle and speed are functions of time alone.
    auto angle = [&](double t) { return rotor.law ? rotor.law->angle_rad(t) : rotor_angle(r, t, state_at(t)); };
    auto rate = [&](double t) {
      return kTwoPi / 60.0 * (rotor.law ? rotor.law->rpm(t) : rotor_rpm(r, t, state_at(t)));
    };
    double a_lo = angle(t_lo), a_hi = angle(t_hi);
    if (a_hi <= a_lo) return t_hi;
    double t = t_lo + (target - a_lo) / (a_hi - a_lo) * (t_hi - t_lo);
    for (int it = 0; it < 30; ++it) {
      t = std::clamp(t, t_lo, t_hi);
      const double residual = angle(t) - target;
      if (residual > 0) t_hi = t; else t_lo = t;
      if (std::abs(residual) <= 1e-13 * std::max(1.0, std::abs(target)) || t_hi - t_lo < 1e-15 * std::max(1.0, t))
        return t;
      const double speed = rate(t);
      const double next = speed > 0 ? t - residual / speed : 0.5 * (t_lo + t_hi);
      t = (next > t_lo && next < t_hi) ? next : 0.5 * (t_lo + t_hi);
    }
    return t;
  }

  // Writes every surface grid point the contact passed up to time t_end.
  void write_surfaces(double t_start, double t_end) {
    for (std::size_t r = 0; r < rotor_count; ++r) {
      RotorState& rotor = rotors_[r];
      if (!rotor.surface) continue;
      SurfaceMemory& surface = *rotor.surface;
      // A speed law needs no state (no dense-output call per step and rotor).
      const double end_angle = rotor.law ? rotor.law->angle_rad(t_end) : rotor_angle(r, t_end, state_at(t_end));
      double t_lo = t_start;
      const auto n = static_cast<std::int64_t>(surface.samples_per_rev());
      while (static_cast<double>(surface.next_index()) * surface.spacing_rad() <= end_angle) {
        const std::int64_t k = surface.next_index();
        const double target = static_cast<double>(k) * surface.spacing_rad();
        const double t = k == 0 ? 0.0 : time_of_angle(r, target, t_lo, t_end);
        t_lo = t;
        ContactInput in;
        ContactOutput out;
        evaluate_contact(t, state_at(t), in, out);
        // New surface = the surface one revolution ago (as the contact saw it) + this pass's
        // removal; without a contact arc that is exactly sample k - n.
        const double previous = rotor.arc_rad > 0.0 ? in.previous_surface_m[r] : surface.value(k - n);
        surface.push(previous + out.removed_m[r]);
      }
    }
  }

  bool record_sample(double t) {
    std::span<const double> x = state_at(t);
    ContactInput in;
    ContactOutput out;
    evaluate_contact(t, x, in, out);
    const double displacement = model_.displacement_m(x);
    const bool contact = !settings_.one_sided_contact || out.penetration_m > 0.0;
    const double values[] = {displacement, out.normal_force_n, out.depth_of_cut_m,
                             in.speed_rpm[0], in.speed_rpm[1], in.previous_surface_m[0],
                             in.previous_surface_m[1]};
    for (double v : values)
      if (!std::isfinite(v)) return false;
    if (settings_.on_sample) {
      OutputSample sample;
      sample.t_s = t;
      sample.displacement_m = displacement;
      sample.force_n = out.normal_force_n;
      sample.depth_of_cut_m = out.depth_of_cut_m;
      sample.infeed_m = in.infeed_m;
      for (std::size_t r = 0; r < rotor_count; ++r) {
        sample.speed_rpm[r] = in.speed_rpm[r];
        sample.surface_at_contact_m[r] = in.previous_surface_m[r];
      }
      sample.in_contact = contact;
      settings_.on_sample(sample);
    }
    if (!settings_.store_samples) return true;
    result_.t_s.push_back(t);
    result_.displacement_m.push_back(displacement);
    result_.force_n.push_back(out.normal_force_n);
    result_.depth_of_cut_m.push_back(out.depth_of_cut_m);
    result_.infeed_m.push_back(in.infeed_m);
    for (std::size_t r = 0; r < rotor_count; ++r) {
      result_.speed_rpm[r].push_back(in.speed_rpm[r]);
      result_.surface_at_contact_m[r].push_back(in.previous_surface_m[r]);
    }
    result_.in_contact.push_back(contact ? 1.0 : 0.0);
    return true;
  }

  void take_snapshot(double t) {
    SurfaceSnapshot snap;
    snap.t_s = t;
    std::size_t grid = 0;
    for (const RotorState& rotor : rotors_)
      if (rotor.surface) grid = std::max(grid, rotor.surface->samples_per_rev());
    grid = std::clamp<std::size_t>(grid, 360, 1 << 16);
    for (std::size_t i = 0; i < grid; ++i) snap.angle_deg.push_back(360.0 * static_cast<double>(i) / static_cast<double>(grid));
    for (std::size_t r = 0; r < rotor_count; ++r) {
      const RotorState& rotor = rotors_[r];
      snap.surface_m[r].assign(grid, 0.0);
      if (!rotor.surface) continue;
      // Body-angle profile of the last revolution, resampled (periodic linear) onto the grid.
      std::vector<double> profile = rotor.surface->last_revolution();
      const double m = static_cast<double>(profile.size());
      for (std::size_t i = 0; i < grid; ++i) {
        double pos = m * static_cast<double>(i) / static_cast<double>(grid);
        auto j = static_cast<std::size_t>(pos);
        double u = pos - static_cast<double>(j);
        snap.surface_m[r][i] = (1 - u) * profile[j % profile.size()] + u * profile[(j + 1) % profile.size()];
      }
    }
    result_.snapshots.push_back(std::move(snap));
  }

  // True if the run must stop: state not finite or displacement beyond the limit.
  bool check_divergence(double t) {
    std::span<const double> x(N_VGetArrayPointer(sun_.y), n_);
    bool finite = std::all_of(x.begin(), x.end(), [](double v) { return std::isfinite(v); });
    double displacement = finite ? model_.displacement_m(x) : std::nan("");
    if (finite && std::isfinite(displacement) && std::abs(displacement) <= settings_.divergence_limit_m)
      return false;
    result_.diverged = true;
    std::string state;
    for (std::size_t i = 0; i < n_ && i < 12; ++i) state += fmt::format("{}{:.4g}", i ? ", " : "", x[i]);
    result_.status = finite ? fmt::format("diverged at t = {:.6g} s: |displacement| = {:.4g} m exceeds "
                                          "divergence_limit_m = {:.4g} m (state: {})",
                                          t, std::abs(displacement), settings_.divergence_limit_m, state)
                            : fmt::format("diverged at t = {:.6g} s: state not finite (state: {})", t, state);
    return true;
  }

  void fail(int flag, double t) {
    double h = 0.0, t_current = t;
    CVodeGetCurrentStep(sun_.cvode, &h);
    CVodeGetCurrentTime(sun_.cvode, &t_current);
    const char* name = CVodeGetReturnFlagName(flag);
    std::string what = fmt::format("integrator failed at t = {:.6g} s (step size h = {:.3g} s", t_current, h);
    if (flag == CV_TOO_CLOSE || flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE)
      what += ", step-size collapse";
    what += fmt::format("; CVODE {}{}{})", name, last_error_.empty() ? "" : ": ", last_error_);
    free(const_cast<char*>(name));  // CVodeGetReturnFlagName allocates
    throw PointFailure(what);
  }

  const TimeDomainModel& model_;
  const SimulationSettings& settings_;
  std::size_t n_;
  std::vector<double> state_scratch_;
  RotorState rotors_[rotor_count];
  double f_max_ = 0.0, max_rpm_ = 0.0;
  Sundials sun_;
  bool stepped_ = false;
  long rhs_evaluations_ = 0;
  std::string last_error_;
  std::vector<std::string> diagnostics_;
  SimulationResult result_;
};

SimulationResult Engine::run() {
  const double t_end = settings_.duration_s;
  sun_.y = N_VNew_Serial(static_cast<sunindextype>(n_), sun_.context);
  sun_.dky = N_VNew_Serial(static_cast<sunindextype>(n_), sun_.context);
  sun_.abstol = N_VNew_Serial(static_cast<sunindextype>(n_), sun_.context);
  std::span<double> y(N_VGetArrayPointer(sun_.y), n_);
  model_.initial_state(settings_.disturbance, y);

  // Absolute tolerances: the relative tolerance times the state scale of a displacement of the
  // disturbance (or the infeed of a wheel revolution, whichever is larger), so that a decaying
  // response stays resolved far below its start.
  double reference = std::max({std::abs(settings_.disturbance.displacement_m),
                               settings_.infeed_rate_m_per_s * 60.0 / max_rpm_,
                               settings_.initial_waviness_m, 1e-12});
  std::span<double> scales(N_VGetArrayPointer(sun_.abstol), n_);
  model_.state_scales(reference, scales);
  for (double& s : scales) s = 1e-3 * settings_.relative_tolerance * std::max(s, 1e-300);
  const std::vector<double> tolerance_floor(scales.begin(), scales.end());
  // Absolute tolerances follow the amplitude: each component of an oscillation passes through
  // zero twice a period, where only the absolute tolerance bounds its error weight; a fixed one
  // set for the start is far too strict once the response has decayed or grown by orders of
  // magnitude (the step size then collapses to resolve noise). Every window the tolerance is
  // reset to 0.1 rtol times the component's largest magnitude over the last two windows.
  const double tolerance_window_s = std::max(4.0 / f_max_, 0.02);
  std::vector<double> window_max(n_, 0.0), previous_window_max(n_, 0.0);
  double window_end = tolerance_window_s;
  auto adapt_tolerances = [&](double t_now) {
    std::span<const double> x(N_VGetArrayPointer(sun_.y), n_);
    for (std::size_t i = 0; i < n_; ++i) window_max[i] = std::max(window_max[i], std::abs(x[i]));
    if (t_now < window_end) return;
    std::span<double> atol(N_VGetArrayPointer(sun_.abstol), n_);
    for (std::size_t i = 0; i < n_; ++i) {
      atol[i] = std::max(tolerance_floor[i],
                         0.1 * settings_.relative_tolerance * std::max(window_max[i], previous_window_max[i]));
      previous_window_max[i] = window_max[i];
      window_max[i] = 0.0;
    }
    window_end = t_now + tolerance_window_s;
  };

  sun_.cvode = CVodeCreate(CV_ADAMS, sun_.context);
  if (!sun_.cvode) throw std::runtime_error("CVodeCreate failed");
  CVodeSetErrHandlerFn(sun_.cvode, &Engine::silent_error, this);
  if (CVodeInit(sun_.cvode, &Engine::rhs, 0.0, sun_.y) != CV_SUCCESS) throw std::runtime_error("CVodeInit failed");
  CVodeSetUserData(sun_.cvode, this);
  // Error weights 1/(rtol |y_i| + atol_i) from a weight function reading sun_.abstol, so the
  // absolute tolerances can follow the amplitude during the run (adapt_tolerances below).
  CVodeWFtolerances(sun_.cvode, &Engine::error_weights);
  sun_.solver = SUNNonlinSol_FixedPoint(sun_.y, 0, sun_.context);
  CVodeSetNonlinearSolver(sun_.cvode, sun_.solver);
  // Largest step: a fraction of the shortest wave (dense output and contact events stay local)
  // and well below a revolution (a read one revolution back must find written surface).
  const double max_step = std::min(1.0 / (settings_.max_steps_per_wave * f_max_), 0.25 * 60.0 / max_rpm_);
  CVodeSetMaxStep(sun_.cvode, max_step);
  CVodeSetMaxNumSteps(sun_.cvode, 100000);
  CVodeSetStopTime(sun_.cvode, t_end);
  if (settings_.one_sided_contact) CVodeRootInit(sun_.cvode, 1, &Engine::root);

  std::vector<double> snapshots = settings_.snapshot_times_s;
  std::sort(snapshots.begin(), snapshots.end());
  std::size_t next_snapshot = 0;
  const auto sample_count = static_cast<std::size_t>(std::floor(t_end * settings_.sample_rate_hz + 1e-9)) + 1;
  std::size_t next_sample = 0;
  if (settings_.store_samples) result_.t_s.reserve(sample_count);

  // Contact bookkeeping (one-sided): intervals out of contact.
  auto penetration_now = [&](double t, std::span<const double> x) {
    ContactInput in;
    ContactOutput out;
    evaluate_contact(t, x, in, out, false);
    return out.penetration_m;
  };
  bool in_contact = !settings_.one_sided_contact || penetration_now(0.0, y) > 0.0;
  double lost_since = 0.0;

  write_surfaces(0.0, 0.0);
  double t = 0.0;
  bool stop = false;
  while (!stop) {
    // Output samples and snapshots up to t (inclusive), then one step.
    while (next_sample < sample_count &&
           static_cast<double>(next_sample) / settings_.sample_rate_hz <= t) {
      if (!record_sample(static_cast<double>(next_sample) / settings_.sample_rate_hz)) {
        check_divergence(t);
        if (!result_.diverged) {
          result_.diverged = true;
          result_.status = fmt::format("diverged at t = {:.6g} s: outputs not finite", t);
        }
        stop = true;
        break;
      }
      ++next_sample;
    }
    while (next_snapshot < snapshots.size() && snapshots[next_snapshot] <= t) {
      take_snapshot(t);
      ++next_snapshot;
    }
    if (stop || t >= t_end) break;

    double t_new = t;
    int flag = CVode(sun_.cvode, t_end, sun_.y, &t_new, CV_ONE_STEP);
    if (flag < 0) fail(flag, t);
    stepped_ = true;
    write_surfaces(t, t_new);
    if (flag == CV_ROOT_RETURN) {
      int direction = 0;
      CVodeGetRootInfo(sun_.cvode, &direction);
      ++result_.contact_events;
      const bool entering = direction > 0;
      if (in_contact && !entering) lost_since = t_new;
      if (!in_contact && entering) {
        result_.contact_loss_intervals.emplace_back(lost_since, t_new);
        result_.contact_loss_time_s += t_new - lost_since;
      }
      in_contact = entering;
    } else if (settings_.one_sided_contact &&
               (penetration_now(t_new, {N_VGetArrayPointer(sun_.y), n_}) > 0.0) != in_contact) {
      // A switch the event function cannot see: starting exactly at zero penetration (no
      // sign change to detect), e.g. the first touch of an infeed from rest.
      if (in_contact) {
        lost_since = t_new;
      } else {
        result_.contact_loss_intervals.emplace_back(lost_since, t_new);
        result_.contact_loss_time_s += t_new - lost_since;
      }
      in_contact = !in_contact;
    }
    // Samples inside this step come from the dense output before a restart discards it.
    while (next_sample < sample_count &&
           static_cast<double>(next_sample) / settings_.sample_rate_hz <= t_new) {
      if (!record_sample(static_cast<double>(next_sample) / settings_.sample_rate_hz)) break;
      ++next_sample;
    }
    t = t_new;
    if (check_divergence(t)) break;
    adapt_tolerances(t);
    if (flag == CV_ROOT_RETURN) {
      // The force law has a kink at the contact switch: restart the multistep method there.
      CVodeReInit(sun_.cvode, t, sun_.y);
      stepped_ = false;
    }
  }
  if (!in_contact) {
    result_.contact_loss_intervals.emplace_back(lost_since, t);
    result_.contact_loss_time_s += t - lost_since;
  }
  result_.end_time_s = t;
  if (!result_.diverged) result_.status = "completed";
  std::copy(y.begin(), y.end(), result_.end_state.begin());
  long steps = 0;
  CVodeGetNumSteps(sun_.cvode, &steps);
  result_.steps = steps;
  result_.rhs_evaluations = rhs_evaluations_;
  result_.diagnostics = diagnostics_;
  for (std::string& d : model_.diagnostics()) result_.diagnostics.push_back(std::move(d));
  return std::move(result_);
}

}  // namespace

SimulationResult simulate(const TimeDomainModel& model, const SimulationSettings& settings) {
  Engine engine(model, settings);
  return engine.run();
}

}  // namespace chatterlab
