#include "dynamics/engine_core.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace chatterlab::dynamics_detail {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::size_t kMaxSurfaceSamples = std::size_t{1} << 22;
}  // namespace

void validate_settings(const SimulationSettings& s) {
  auto positive = [](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0.0)) throw std::invalid_argument(fmt::format("{} must be > 0", what));
  };
  positive(s.duration_s, "duration_s");
  positive(s.sample_rate_hz, "sample_rate_hz");
  positive(s.relative_tolerance, "relative_tolerance");
  positive(s.samples_per_wave, "samples_per_wave");
  positive(s.max_steps_per_wave, "max_steps_per_wave");
  positive(s.divergence_limit_m, "divergence_limit_m");
  if (!(std::isfinite(s.fixed_steps_per_wave) && s.fixed_steps_per_wave >= 0.0))
    throw std::invalid_argument("fixed_steps_per_wave must be >= 0 (0: the propagator's default)");
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

EngineCore::EngineCore(const TimeDomainModel& model, const SimulationSettings& settings)
    : model_(model), settings_(settings), n_(model.state_size()) {
  validate_settings(settings);
  f_max_ = model.highest_frequency_hz();
  if (!(std::isfinite(f_max_) && f_max_ > 0.0))
    throw std::logic_error("TimeDomainModel::highest_frequency_hz must be > 0");
  for (std::size_t r = 0; r < rotor_count; ++r) setup_rotor(static_cast<Rotor>(r));
  result_.end_state.assign(n_, 0.0);
  snapshot_times_ = settings.snapshot_times_s;
  std::sort(snapshot_times_.begin(), snapshot_times_.end());
  sample_count_ = static_cast<std::size_t>(std::floor(settings.duration_s * settings.sample_rate_hz + 1e-9)) + 1;
  // Every output series is reserved once (growing ~12 series by doubling cost copies and page
  // faults comparable to the integration itself).
  for (std::vector<double>* series : {&result_.t_s, &result_.displacement_m, &result_.force_n, &result_.depth_of_cut_m,
                                      &result_.infeed_m, &result_.speed_rpm[0], &result_.speed_rpm[1],
                                      &result_.surface_at_contact_m[0], &result_.surface_at_contact_m[1],
                                      &result_.in_contact})
    if (settings.store_samples) series->reserve(sample_count_);
}

void EngineCore::setup_rotor(Rotor r) {
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
    if (min_rpm == max_rpm && min_rpm > 0.0) {
      rotor.constant_rpm = min_rpm;
      rotor.constant_rad_per_s = kTwoPi / 60.0 * min_rpm;
    }
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
  rotor.surface.emplace(samples, std::move(initial), rotor.arc_rad > 0.0);
  result_.surface_samples_per_rev[static_cast<std::size_t>(r)] = samples;
}

double EngineCore::rotor_angle(std::size_t r, double t, std::span<const double> x) const {
  const RotorState& rotor = rotors_[r];
  if (rotor.constant_rad_per_s > 0.0) return rotor.constant_rad_per_s * t;
  return rotor.law ? rotor.law->angle_rad(t) : x[*rotor.angle_state];
}

double EngineCore::rotor_rpm(std::size_t r, double t, std::span<const double> x) const {
  const RotorState& rotor = rotors_[r];
  if (rotor.constant_rpm > 0.0) return rotor.constant_rpm;
  return rotor.law ? rotor.law->rpm(t) : model_.speed_rpm_from_state(static_cast<Rotor>(r), x);
}

void EngineCore::evaluate_contact(double t, std::span<const double> x, ContactInput& in, ContactOutput& out,
                                  Settle settle, std::size_t known_rotor, double known_previous_m) const {
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
    in.previous_surface_m[r] = r == known_rotor ? known_previous_m
                               : rotor.surface     ? rotor.surface->mean(in.angle_rad[r] - kTwoPi, rotor.arc_rad)
                                                   : 0.0;
  }
  if (x.empty()) return;  // the linear forcing: no contact output
  model_.contact(in, out);
  if (!settings_.one_sided_contact || settle == Settle::none || settle == Settle::in_contact) return;
  if (settle == Settle::free || !(out.penetration_m > 0.0)) {
    out.normal_force_n = out.tangential_force_n = out.depth_of_cut_m = 0.0;
    for (double& removed : out.removed_m) removed = 0.0;
  }
}

void EngineCore::cell_input(double t_a, double t_b, ContactInput& in) const {
  const double t = 0.5 * (t_a + t_b);
  in.t_s = t;
  in.state = {};
  // Simpson's rule: exact for an infeed up to cubic in time over the cell (the same formula for
  // the constant rate, so that a law of constant rate reproduces it bit for bit).
  auto infeed = [&](double time) {
    return settings_.infeed ? settings_.infeed->infeed_m(time) : settings_.infeed_rate_m_per_s * time;
  };
  in.infeed_m = (infeed(t_a) + 4.0 * infeed(t) + infeed(t_b)) / 6.0;
  in.infeed_rate_m_per_s = settings_.infeed ? settings_.infeed->rate_m_per_s(t) : settings_.infeed_rate_m_per_s;
  for (std::size_t r = 0; r < rotor_count; ++r) {
    in.speed_rpm[r] = rotor_rpm(r, t, {});
    in.angle_rad[r] = rotor_angle(r, t, {});
    const RotorState& rotor = rotors_[r];
    if (!rotor.surface) in.previous_surface_m[r] = 0.0;
    else if (rotor.arc_rad > 0.0) in.previous_surface_m[r] = rotor.surface->mean(in.angle_rad[r] - kTwoPi, rotor.arc_rad);
    else in.previous_surface_m[r] = rotor.surface->average(rotor_angle(r, t_a, {}) - kTwoPi, rotor_angle(r, t_b, {}) - kTwoPi);
  }
}

double EngineCore::penetration(double t, std::span<const double> x) const {
  ContactInput in;
  ContactOutput out;
  evaluate_contact(t, x, in, out, Settle::none);
  return out.penetration_m;
}

double EngineCore::time_of_angle(std::size_t r, double target, double t_lo, double t_hi) {
  const RotorState& rotor = rotors_[r];
  if (rotor.constant_rad_per_s > 0.0) return std::clamp(target / rotor.constant_rad_per_s, t_lo, t_hi);
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

bool EngineCore::reads_settled(const ContactInput& in) const {
  for (std::size_t r = 0; r < rotor_count; ++r) {
    const RotorState& rotor = rotors_[r];
    if (rotor.surface && !rotor.surface->settled(in.angle_rad[r] - kTwoPi + 0.5 * rotor.arc_rad)) return false;
  }
  return true;
}

void EngineCore::write_surfaces(double t_start, double t_end) {
  before_surface_writes();
  for (std::size_t r = 0; r < rotor_count; ++r) {
    RotorState& rotor = rotors_[r];
    if (!rotor.surface) continue;
    SurfaceMemory& surface = *rotor.surface;
    // A speed law needs no state (no dense-output call per step and rotor).
    const double end_angle = rotor.law ? rotor_angle(r, t_end, {}) : rotor_angle(r, t_end, state_at(t_end));
    double t_lo = t_start;
    const auto n = static_cast<std::int64_t>(surface.samples_per_rev());
    while (static_cast<double>(surface.next_index()) * surface.spacing_rad() <= end_angle) {
      const std::int64_t k = surface.next_index();
      const double target = static_cast<double>(k) * surface.spacing_rad();
      const double t = k == 0 ? 0.0 : time_of_angle(r, target, t_lo, t_end);
      t_lo = t;
      ContactInput& in = contact_input_;
      ContactOutput out;
      // New surface = the surface one revolution ago (as the contact saw it) + this pass's
      // removal; without a contact arc that is exactly sample k - n (no interpolated read).
      if (rotor.arc_rad > 0.0) evaluate_contact(t, state_at(t), in, out);
      else evaluate_contact(t, state_at(t), in, out, Settle::by_penetration, r, surface.value(k - n));
      surface.push(in.previous_surface_m[r] + out.removed_m[r]);
    }
  }
}

bool EngineCore::record_sample(double t) {
  std::span<const double> x = state_at(t);
  ContactInput& in = contact_input_;
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

bool EngineCore::record_samples_until(double t, double slack) {
  while (next_sample_ < sample_count_ && static_cast<double>(next_sample_) / settings_.sample_rate_hz <= t + slack) {
    if (!record_sample(static_cast<double>(next_sample_) / settings_.sample_rate_hz)) {
      if (!result_.diverged) {
        result_.diverged = true;
        result_.status = fmt::format("diverged at t = {:.6g} s: outputs not finite", t);
      }
      return false;
    }
    ++next_sample_;
  }
  return true;
}

void EngineCore::take_snapshots_until(double t) {
  while (next_snapshot_ < snapshot_times_.size() && snapshot_times_[next_snapshot_] <= t) {
    take_snapshot(t);
    ++next_snapshot_;
  }
}

double EngineCore::next_snapshot_time() const {
  return next_snapshot_ < snapshot_times_.size() ? snapshot_times_[next_snapshot_]
                                                 : std::numeric_limits<double>::infinity();
}

void EngineCore::take_snapshot(double t) {
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

bool EngineCore::check_divergence(double t, std::span<const double> x) {
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

void EngineCore::contact_switch(double t, bool entering) {
  if (in_contact_ && !entering) lost_since_ = t;
  // (An interval of zero length is no loss of contact: a start exactly at zero penetration.)
  if (!in_contact_ && entering && t > lost_since_) {
    result_.contact_loss_intervals.emplace_back(lost_since_, t);
    result_.contact_loss_time_s += t - lost_since_;
  }
  in_contact_ = entering;
}

SimulationResult EngineCore::finish(double t_end, std::span<const double> x) {
  if (!in_contact_) {
    result_.contact_loss_intervals.emplace_back(lost_since_, t_end);
    result_.contact_loss_time_s += t_end - lost_since_;
  }
  result_.end_time_s = t_end;
  if (!result_.diverged) result_.status = "completed";
  std::copy(x.begin(), x.end(), result_.end_state.begin());
  result_.diagnostics = diagnostics_;
  for (std::string& d : model_.diagnostics()) result_.diagnostics.push_back(std::move(d));
  return std::move(result_);
}

}  // namespace chatterlab::dynamics_detail
