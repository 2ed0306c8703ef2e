// The fixed-step route of the dynamics engine (fixed_step_engine.hpp). Per step [t_k, t_k + h]:
// propagate the state (exactly for a LinearForm: x <- E x + W f with the forcing at four step
// times; classical Runge-Kutta otherwise), evaluate the contact at the step end, and if the
// penetration changed sign locate the event inside the step, end the piece there and propagate
// the rest of the step on the other side. Each piece then writes the surface grid points it
// passed and the output samples inside it from a cubic Hermite interpolant of (x, dx/dt) at its
// ends; samples that fall on step ends (the step divides the sample interval whenever it can)
// are the propagated states themselves. No allocation per step.
#include "dynamics/fixed_step_engine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "dynamics/engine_core.hpp"
#include "dynamics/linear_propagator.hpp"

namespace chatterlab {

double TimeDomainModel::next_linear_form_change_s(double /*t_s*/) const {
  return std::numeric_limits<double>::infinity();
}

namespace dynamics_detail {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Pieces per step beyond which contact switches are no longer split out (a contact chattering
// faster than the step): the side then follows the penetration's sign at the piece end.
constexpr int kMaxPiecesPerStep = 16;
// Largest step in units of the time between two surface samples (docs/dynamics.md: with random
// initial waviness the growth rate of studies/simulate_g8_chatter.toml is 1.7 % off at 1.26 and
// within 0.35 % from 0.8 down, against the reference route).
constexpr double kStepsPerSurfaceSample = 0.75;

// A point of the trajectory: time, state, and its first and (exponential propagation: exact,
// for a quintic Hermite dense output) second derivative on the side in force.
struct Point {
  double t = 0.0;
  std::vector<double> x, f, g;
  bool has_second = false;
};

class FixedStepEngine final : public EngineCore {
 public:
  FixedStepEngine(const TimeDomainModel& model, const SimulationSettings& settings);
  SimulationResult run();

 private:
  std::span<const double> state_at(double t) override;

  // Propagation of the current step [t_k, t_next]: x(t_b) from x(t_a) on the side; f_a is dx/dt
  // at t_a (Runge-Kutta's first stage).
  void advance(double t_a, double t_b, bool side, const double* x, const double* f_a, double* out);
  // t - t_k, exactly h at the step's end (t_next - t_k differs from h by rounding).
  double local(double t) const { return t == t_next_ ? h_ : t - t_k_; }
  // dx/dt at (t, x) on the side (t inside the current step); throws PointFailure if not finite.
  void derivative(double t, bool side, const double* x, double* dx);
  // p.f (and p.g = d2x/dt2 with a linear form) at p.t, p.x on the side.
  void slopes(bool side, Point& p);
  // The linear forcing's average over the time cell [t_a, t_b] (the model's, from the surfaces
  // one revolution ago) and, for the consistency check, its value at t.
  double forcing(double t_a, double t_b);
  // Runge-Kutta right-hand side on a fixed contact side.
  bool rhs(double t, const double* x, bool side, double* dx);
  // Locates the contact switch inside the piece [a, b] (times, a = piece_a_.t) whose end b has the
  // penetration of the other side; sets `event` (time, state, derivative on the old side).
  void locate_event(bool side, Point& event);
  // Switches to the linear form in force at t (or to Runge-Kutta if the model has none).
  void select_form(double t);
  void check_linear_form(double t, const LinearForm& form);
  void set_step(double h);
  [[noreturn]] void fail(double t, const std::string& cause) const;

  bool has_form_ = false;  // the model declares a linear form: the forcing nodes are kept
  double h_ = 0.0;         // the step
  double t_k_ = 0.0;       // start of the current step
  double t_next_ = 0.0;    // its end
  bool first_step_ = true;
  // Linear forms met so far, by the model's id; current_ is the one in force (null: Runge-Kutta).
  std::map<std::size_t, LinearPropagator> propagators_;
  const LinearPropagator* current_ = nullptr;
  double next_form_change_ = kInfinity;
  std::vector<double> scales_;
  // Forcing averages over the current step's four cells ([t_k - h, t_k] .. [t_k + 2h, t_k + 3h];
  // first step [t_k, t_k + h] ..), and the step's forcing cubic through them.
  double nodes_[4] = {0.0, 0.0, 0.0, 0.0};
  ForcingCubic cubic_;
  // Dense output: the piece [piece_a_.t, piece_b_.t] of the current step.
  Point piece_a_, piece_b_;
  std::vector<double> dense_;
  // Runge-Kutta stages and scratch.
  std::vector<double> k2_, k3_, k4_, stage_, scratch_, scratch2_;
  std::string form_problem_;
};

FixedStepEngine::FixedStepEngine(const TimeDomainModel& model, const SimulationSettings& settings)
    : EngineCore(model, settings), scales_(n_), dense_(n_), k2_(n_), k3_(n_), k4_(n_), stage_(n_),
      scratch_(n_), scratch2_(n_) {
  for (Point* p : {&piece_a_, &piece_b_}) {
    p->x.assign(n_, 0.0);
    p->f.assign(n_, 0.0);
    p->g.assign(n_, 0.0);
  }
  model_.state_scales(1.0, scales_);
  for (double& s : scales_) s = std::isfinite(s) && s > 0.0 ? s : 1.0;
}

void FixedStepEngine::set_step(double h) { h_ = h; }

void FixedStepEngine::fail(double t, const std::string& cause) const {
  throw PointFailure(fmt::format("fixed-step integration failed at t = {:.6g} s (step h = {:.4g} s): {}", t, h_, cause));
}

double FixedStepEngine::forcing(double t_a, double t_b) {
  ContactInput& in = contact_input_;
  if (t_b > t_a) {
    cell_input(t_a, t_b, in);
  } else {
    ContactOutput unused;
    evaluate_contact(t_a, {}, in, unused);
  }
  ++result_.rhs_evaluations;
  const double f = model_.linear_forcing(in);
  if (!std::isfinite(f)) fail(t_a, fmt::format("linear forcing not finite at t = {:.6g} s", in.t_s));
  return f;
}

bool FixedStepEngine::rhs(double t, const double* x, bool side, double* dx) {
  ++result_.rhs_evaluations;
  ContactInput& in = contact_input_;
  ContactOutput out;
  evaluate_contact(t, {x, n_}, in, out, side ? Settle::in_contact : Settle::free);
  model_.derivatives(in, out, {dx, n_});
  for (std::size_t i = 0; i < n_; ++i)
    if (!std::isfinite(dx[i])) {
      fail(t, fmt::format("right-hand side not finite at t = {:.6g} s", t));
      return false;
    }
  return true;
}

void FixedStepEngine::derivative(double t, bool side, const double* x, double* dx) {
  if (current_) {
    current_->derivative(side, x, cubic_.value(local(t)), dx);
    return;
  }
  rhs(t, x, side, dx);
}

void FixedStepEngine::slopes(bool side, Point& p) {
  derivative(p.t, side, p.x.data(), p.f.data());
  p.has_second = current_ != nullptr;
  if (!p.has_second) return;
  // d2x/dt2 = A dx/dt + b df/dt.
  current_->derivative(side, p.f.data(), cubic_.rate(local(p.t)), p.g.data());
}

void FixedStepEngine::advance(double t_a, double t_b, bool side, const double* x, const double* f_a, double* out) {
  const double a = local(t_a), b = local(t_b);
  if (current_) {
    const ForcingNodes nodes = first_step_ ? ForcingNodes::first_step : ForcingNodes::centred;
    if (a == 0.0 && b == h_) current_->step(side, nodes, x, nodes_, out);
    else current_->piece(side, cubic_, a, b, x, out);
    return;
  }
  // Classical Runge-Kutta over [t_a, t_b].
  const double t = t_a, dt = b - a;
  if (dt == 0.0) {
    std::copy_n(x, n_, out);
    return;
  }
  auto stage = [&](const double* k, double factor, double* into) {
    for (std::size_t i = 0; i < n_; ++i) stage_[i] = x[i] + factor * k[i];
    return rhs(t + factor, stage_.data(), side, into);
  };
  stage(f_a, 0.5 * dt, k2_.data());  // rhs() reports a value that is not finite
  stage(k2_.data(), 0.5 * dt, k3_.data());
  stage(k3_.data(), dt, k4_.data());
  const double sixth = dt / 6.0;
  for (std::size_t i = 0; i < n_; ++i) out[i] = x[i] + sixth * (f_a[i] + 2.0 * (k2_[i] + k3_[i]) + k4_[i]);
}

std::span<const double> FixedStepEngine::state_at(double t) {
  const double ta = piece_a_.t, tb = piece_b_.t, d = tb - ta;
  const double snap = 1e-9 * h_;  // step ends coincide with sample times up to rounding
  if (std::abs(t - tb) <= snap) return piece_b_.x;
  if (std::abs(t - ta) <= snap || d <= 0.0) return piece_a_.x;
  const double u = (t - ta) / d, v = 1.0 - u;
  if (piece_a_.has_second && piece_b_.has_second) {
    // Quintic Hermite from x, dx/dt and d2x/dt2 at the ends (error ~(h w)^6 / 46080 of the
    // amplitude, 1e-7 at h w = 0.4: outputs as accurate as the exact step ends).
    const double u2 = u * u, u3 = u2 * u, v3 = v * v * v;
    const double h0 = v3 * (1.0 + 3.0 * u + 6.0 * u2), h3 = u3 * (10.0 - 15.0 * u + 6.0 * u2);
    const double h1 = d * u * v3 * (1.0 + 3.0 * u), h4 = -d * u3 * v * (4.0 - 3.0 * u);
    const double h2 = 0.5 * d * d * u2 * v3, h5 = 0.5 * d * d * u3 * v * v;
    for (std::size_t i = 0; i < n_; ++i)
      dense_[i] = h0 * piece_a_.x[i] + h1 * piece_a_.f[i] + h2 * piece_a_.g[i] + h3 * piece_b_.x[i] +
                  h4 * piece_b_.f[i] + h5 * piece_b_.g[i];
    return dense_;
  }
  // Cubic Hermite from x and dx/dt at the piece's ends (Runge-Kutta: its own order).
  const double h00 = (1.0 + 2.0 * u) * v * v, h01 = u * u * (3.0 - 2.0 * u);
  const double h10 = d * u * v * v, h11 = -d * u * u * v;
  for (std::size_t i = 0; i < n_; ++i)
    dense_[i] = h00 * piece_a_.x[i] + h01 * piece_b_.x[i] + h10 * piece_a_.f[i] + h11 * piece_b_.f[i];
  return dense_;
}

void FixedStepEngine::check_linear_form(double t, const LinearForm& form) {
  // derivatives() and the form must describe the same model: compare them at a few states on
  // both sides of the contact (a random state and its negative), scaled like the response.
  std::mt19937_64 random(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> x(n_), dx(n_);
  const double f = forcing(t, t);
  for (int trial = 0; trial < 4; ++trial) {
    if (trial % 2 == 0)
      for (std::size_t i = 0; i < n_; ++i) x[i] = 1e-6 * scales_[i] * uniform(random);
    else
      for (double& v : x) v = -v;
    ContactInput& in = contact_input_;
    ContactOutput out;
    evaluate_contact(t, x, in, out);
    model_.derivatives(in, out, dx);
    const bool side = !settings_.one_sided_contact || out.penetration_m > 0.0;
    const std::vector<double>& a = side ? form.contact_matrix : form.free_matrix;
    const std::vector<double>& b = side ? form.contact_input : form.free_input;
    for (std::size_t i = 0; i < n_; ++i) {
      double value = b[i] * f, size = std::abs(b[i] * f);
      for (std::size_t j = 0; j < n_; ++j) {
        value += a[i * n_ + j] * x[j];
        size += std::abs(a[i * n_ + j] * x[j]);
      }
      if (!(std::abs(value - dx[i]) <= 1e-9 * size + 1e-300))
        throw std::logic_error(fmt::format(
            "the model's linear_form disagrees with its derivatives at t = {:.6g} s ({} side, state "
            "component {}: {:.6g} from the form, {:.6g} from derivatives())",
            t, side ? "contact" : "free", i, value, dx[i]));
    }
  }
}

void FixedStepEngine::select_form(double t) {
  next_form_change_ = model_.next_linear_form_change_s(t);
  current_ = nullptr;
  if (!has_form_ || !form_problem_.empty()) return;
  std::optional<LinearForm> form = model_.linear_form(t);
  if (!form) return;
  const std::size_t id = model_.linear_form_id(t);
  auto it = propagators_.find(id);
  if (it == propagators_.end()) {
    check_linear_form(t, *form);
    it = propagators_.try_emplace(id, *form, n_, h_, scales_).first;
  }
  if (!it->second.ok()) {
    form_problem_ = it->second.problem();
    diagnostics_.push_back(fmt::format("fixed-step engine: {}; the run continues by Runge-Kutta from t = {:.6g} s",
                                       form_problem_, t));
    return;
  }
  current_ = &it->second;
}

void FixedStepEngine::locate_event(bool side, Point& event) {
  const double ta = piece_a_.t, tb = piece_b_.t;
  const double tolerance = 100.0 * std::numeric_limits<double>::epsilon() * (std::abs(tb) + h_);
  // 1. The root of the penetration along the piece's Hermite interpolant (Illinois).
  double lo = ta, hi = tb;
  double g_lo = penetration(ta, piece_a_.x), g_hi = penetration(tb, piece_b_.x);
  double t = hi;
  if (g_lo == 0.0 || (g_lo > 0.0) == (g_hi > 0.0)) {
    t = ta;  // no bracket: the switch is at the piece start (it began at zero penetration)
  } else {
    int kept = 0;
    for (int it = 0; it < 100 && hi - lo > tolerance; ++it) {
      t = std::clamp(hi - g_hi * (hi - lo) / (g_hi - g_lo), lo, hi);
      if (t <= lo || t >= hi) t = 0.5 * (lo + hi);
      const double g = penetration(t, state_at(t));
      if (g == 0.0) break;
      if ((g > 0.0) == (g_hi > 0.0)) {
        hi = t;
        g_hi = g;
        if (kept == -1) g_lo *= 0.5;  // Illinois: the same end kept twice
        kept = -1;
      } else {
        lo = t;
        g_lo = g;
        if (kept == 1) g_hi *= 0.5;
        kept = 1;
      }
    }
  }
  // 2. The state there by accurate propagation from the piece start, then Newton on the
  // penetration along the trajectory (its rate by a difference along dx/dt) to the root, the
  // state carried by a second-order Taylor step.
  std::vector<double>& x = event.x;
  std::vector<double>& f = event.f;
  for (int it = 0; it < 4; ++it) {
    advance(ta, t, side, piece_a_.x.data(), piece_a_.f.data(), x.data());
    derivative(t, side, x.data(), f.data());
    const double g = penetration(t, x);
    const double epsilon = 1e-6 * h_;
    for (std::size_t i = 0; i < n_; ++i) scratch_[i] = x[i] + epsilon * f[i];
    const double rate = (penetration(t + epsilon, scratch_) - g) / epsilon;
    if (!(std::isfinite(rate) && rate != 0.0)) break;
    const double dt = std::clamp(t - g / rate, ta, tb) - t;
    if (std::abs(dt) <= tolerance || it == 3) {
      // Second-order Taylor step from t to t + dt: x + dt f + dt^2/2 f'.
      derivative(t + epsilon, side, scratch_.data(), scratch2_.data());
      for (std::size_t i = 0; i < n_; ++i) x[i] += dt * f[i] + 0.5 * dt * dt * (scratch2_[i] - f[i]) / epsilon;
      t += dt;
      break;
    }
    t += dt;
  }
  event.t = t;
  slopes(side, event);
}

SimulationResult FixedStepEngine::run() {
  const double t_end = settings_.duration_s;
  // The step: steps_per_wave at the highest frequency; with random initial waviness (white noise
  // at the surface sample scale, docs/dynamics.md) at most 3/4 of the time between two samples of
  // a regenerated surface (at the rotor's nominal or largest scheduled speed), so that each step's
  // forcing cell resolves the rough surface; at most an eighth of the
  // shortest revolution (the forcing cells up to three steps ahead must read written surface).
  // Then shortened (by at most 20 %) so that sample times fall on step ends: a whole number of
  // steps per sample interval, or of sample intervals per step.
  has_form_ = [&] {
    for (const RotorState& rotor : rotors_)
      if (rotor.angle_state) return false;  // a model whose angles are states has no state-free forcing
    return model_.linear_form(0.0).has_value();
  }();
  const double per_wave = settings_.fixed_steps_per_wave > 0.0 ? settings_.fixed_steps_per_wave
                          : !has_form_                          ? kDefaultRungeKuttaStepsPerWave
                          : settings_.one_sided_contact         ? kDefaultOneSidedStepsPerWave
                                                                : kDefaultExponentialStepsPerWave;
  double h_max = std::min(1.0 / (per_wave * f_max_), 0.125 * 60.0 / max_rpm_);
  for (std::size_t r = 0; r < rotor_count && settings_.initial_waviness_m > 0.0; ++r) {
    const RotorState& rotor = rotors_[r];
    if (!rotor.surface) continue;
    const double rpm = rotor.law ? rotor.law->max_rpm(settings_.duration_s) : model_.nominal_speed_rpm(static_cast<Rotor>(r));
    h_max = std::min(h_max, kStepsPerSurfaceSample * 60.0 / (rpm * static_cast<double>(rotor.surface->samples_per_rev())));
  }
  const double interval = 1.0 / settings_.sample_rate_hz;
  const double aligned = interval >= h_max ? interval / std::ceil(interval / h_max - 1e-9)
                                           : interval * std::floor(h_max / interval + 1e-9);
  set_step(aligned >= 0.8 * h_max ? aligned : h_max);
  result_.fixed_step_s = h_;

  Point now;  // the state at the current step boundary
  now.x.assign(n_, 0.0);
  now.f.assign(n_, 0.0);
  now.g.assign(n_, 0.0);
  model_.initial_state(settings_.disturbance, now.x);
  in_contact_ = !settings_.one_sided_contact || penetration(0.0, now.x) > 0.0;
  select_form(0.0);
  if (has_form_) {
    for (int j = 0; j < 4; ++j) nodes_[j] = forcing(static_cast<double>(j) * h_, static_cast<double>(j + 1) * h_);
    cubic_ = LinearPropagator::cubic(ForcingNodes::first_step, nodes_, h_);
  }
  slopes(in_contact_, now);
  piece_a_ = piece_b_ = now;

  write_surfaces(0.0, 0.0);
  const double slack = 1e-9 * h_;
  bool stop = !record_samples_until(0.0, slack);
  if (stop) check_divergence(0.0, now.x);
  take_snapshots_until(0.0);
  Point event = now;
  bool switches_unresolved = false;
  for (long k = 0; !stop && now.t < t_end - slack; ++k) {
    t_k_ = static_cast<double>(k) * h_;
    const double t_next = std::min(static_cast<double>(k + 1) * h_, t_end);
    t_next_ = t_next == static_cast<double>(k + 1) * h_ ? t_next : -1.0;  // a shortened last step: no snap
    if (k > 0 && has_form_) {
      first_step_ = false;
      if (k > 1) {  // (step 1's centred cells are the first step's)
        std::copy(nodes_ + 1, nodes_ + 4, nodes_);
        nodes_[3] = forcing(static_cast<double>(k + 2) * h_, static_cast<double>(k + 3) * h_);
      }
      // The slopes at t_k under this step's forcing cubic (its value at t_k differs a little from
      // the previous step's): the dense output interpolates this step's exact solution.
      const ForcingCubic previous = cubic_;
      cubic_ = LinearPropagator::cubic(ForcingNodes::centred, nodes_, h_);
      if (current_)
        current_->reforce(in_contact_, cubic_.value(0.0) - previous.value(h_), cubic_.rate(0.0) - previous.rate(h_),
                          now.f.data(), now.g.data());
    }
    // Pieces of the step: split at linear-form changes and at contact events. (The points change
    // hands by swapping: no copies of the state per step.)
    std::swap(piece_a_, now);
    for (int piece = 0;; ++piece) {
      // A piece ends at the step end, at a change of the linear form, or at a snapshot time (the
      // surfaces are then written exactly up to it).
      const double ta = piece_a_.t;
      const bool form_change = next_form_change_ <= t_next && next_form_change_ > ta;
      double tb = form_change ? next_form_change_ : t_next;
      if (const double snapshot = next_snapshot_time(); snapshot > ta && snapshot < tb) tb = snapshot;
      advance(ta, tb, in_contact_, piece_a_.x.data(), piece_a_.f.data(), piece_b_.x.data());
      piece_b_.t = tb;
      slopes(in_contact_, piece_b_);
      bool switched = false;
      if (settings_.one_sided_contact && (penetration(tb, piece_b_.x) > 0.0) != in_contact_) {
        if (piece < kMaxPiecesPerStep) {
          locate_event(in_contact_, event);
          std::swap(piece_b_, event);
          ++result_.contact_events;
        } else {
          switches_unresolved = true;
        }
        switched = true;
      }
      write_surfaces(piece_a_.t, piece_b_.t);
      if (!record_samples_until(piece_b_.t, slack)) {
        check_divergence(piece_b_.t, piece_b_.x);
        std::swap(now, piece_b_);  // the run ends where the failing output was asked
        stop = true;
        break;
      }
      take_snapshots_until(piece_b_.t);
      const bool at_change = form_change && !switched && piece_b_.t == next_form_change_;
      if (switched) contact_switch(piece_b_.t, !in_contact_);
      if (at_change) select_form(tb);
      if (switched || at_change) slopes(in_contact_, piece_b_);
      std::swap(piece_a_, piece_b_);
      if (piece_a_.t >= t_next) break;
    }
    if (stop) break;
    std::swap(now, piece_a_);
    ++result_.steps;
    take_snapshots_until(now.t);
    if (check_divergence(now.t, now.x)) break;
  }
  if (switches_unresolved)
    diagnostics_.push_back(fmt::format(
        "fixed-step engine: more than {} contact switches within one step of {:.4g} s; the later ones were "
        "taken at step ends (shorten the step: fixed_steps_per_wave)", kMaxPiecesPerStep, h_));
  result_.method = current_ || !propagators_.empty()
                       ? fmt::format("fixed step {:.5g} s, exact exponential propagation of the linear form", h_)
                       : fmt::format("fixed step {:.5g} s, classical Runge-Kutta (4th order)", h_);
  return finish(now.t, now.x);
}

}  // namespace

SimulationResult simulate_fixed_step(const TimeDomainModel& model, const SimulationSettings& settings) {
  FixedStepEngine engine(model, settings);
  return engine.run();
}

}  // namespace dynamics_detail
}  // namespace chatterlab
