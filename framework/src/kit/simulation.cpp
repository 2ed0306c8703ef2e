// Study kit: simulation settings (chatterlab/kit/simulation.hpp).
#include "chatterlab/kit/simulation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "chatterlab/errors.hpp"

namespace chatterlab::kit {

namespace {

std::string shape_name(SpeedLawShape shape) {
  switch (shape) {
    case SpeedLawShape::constant: return "constant";
    case SpeedLawShape::sinusoidal: return "sinusoidal";
    case SpeedLawShape::triangular: return "triangular";
    case SpeedLawShape::square: return "square";
    case SpeedLawShape::schedule: return "schedule";
  }
  return "?";
}

SpeedModulation modulation(SpeedLawShape shape) {
  switch (shape) {
    case SpeedLawShape::sinusoidal: return SpeedModulation::sinusoidal;
    case SpeedLawShape::triangular: return SpeedModulation::triangular;
    case SpeedLawShape::square: return SpeedModulation::square;
    default: return SpeedModulation::constant;
  }
}

ParamTable<SpeedLawSettings> make_speed_law_table(const std::string& rotor) {
  using S = SpeedLawSettings;
  ParamTable<S> t;
  std::vector<std::pair<std::string, SpeedLawShape>> shapes;
  for (SpeedLawShape s : {SpeedLawShape::constant, SpeedLawShape::sinusoidal, SpeedLawShape::triangular,
                          SpeedLawShape::square, SpeedLawShape::schedule})
    shapes.emplace_back(shape_name(s), s);
  t.add_choice(&S::shape, rotor + "_speed_modulation",
               "speed law of the " + rotor + " around the model's speed: constant, sinusoidal, triangular, square, "
               "or schedule (" + rotor + "_speed_schedule)",
               shapes);
  t.add(&S::amplitude_ratio, rotor + "_speed_amplitude_ratio", "1",
        "modulation amplitude over the mean speed (< 1: the spindle never stops or reverses)")
      .fraction(true);
  t.add(&S::frequency_hz, rotor + "_speed_frequency_hz", "Hz", "modulation frequency").non_negative();
  t.add(&S::schedule, rotor + "_speed_schedule", "s, rpm",
        "rows [t_s, rpm]: piecewise-linear speed from t = 0, held after the last row (with modulation = "
        "\"schedule\")");
  return t;
}

}  // namespace

// ------------------------------------------------------------------ parts

const ParamTable<SpeedLawSettings>& speed_law_table(Rotor rotor) {
  static const ParamTable<SpeedLawSettings> wheel = make_speed_law_table("wheel");
  static const ParamTable<SpeedLawSettings> work = make_speed_law_table("work");
  return rotor == Rotor::wheel ? wheel : work;
}

std::shared_ptr<const SpeedLaw> speed_law(const SpeedLawSettings& s, double nominal_rpm) {
  if (s.shape == SpeedLawShape::schedule) {
    std::vector<double> times, rpm;
    for (const std::vector<double>& row : s.schedule.value()) {
      times.push_back(row.at(0));
      rpm.push_back(row.at(1));
    }
    return make_scheduled_speed(std::move(times), std::move(rpm));
  }
  return make_modulated_speed(nominal_rpm, modulation(s.shape), s.amplitude_ratio, s.frequency_hz);
}

const ParamTable<DisturbanceSettings>& disturbance_table() {
  using S = DisturbanceSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::initial_displacement_m, "initial_displacement_m", "m", "initial structural displacement (disturbance)");
    t.add(&S::initial_velocity_m_per_s, "initial_velocity_m_per_s", "m/s", "initial structural velocity (an impulse)");
    t.add(&S::initial_waviness_m, "initial_waviness_m", "m", "random initial waviness of wheel and work (+/-, uniform)")
        .non_negative();
    t.add(&S::seed, "seed", "1", "seed of the random initial waviness").at_least(0);
    return t;
  }();
  return table;
}

const ParamTable<ContactSettings>& contact_table() {
  using S = ContactSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::infeed_rate_m_per_s, "infeed_rate_m_per_s", "m/s", "plunge infeed rate (G1 U0 = rate * t)").non_negative();
    t.add(&S::one_sided_contact, "one_sided_contact", "1",
          "the force cannot pull: the wheel leaves the work and re-enters (false: bilateral, linear contact; "
          "default: true with an infeed, false without one)");
    t.add(&S::wheel_contact_arc_deg, "wheel_contact_arc_deg", "deg",
          "geometric filtering (G4): wheel surface averaged over this arc (0: point contact)")
        .non_negative()
        .below(90.0);
    t.add(&S::work_contact_arc_deg, "work_contact_arc_deg", "deg",
          "geometric filtering (G4): work surface averaged over this arc (0: point contact)")
        .non_negative()
        .below(90.0);
    return t;
  }();
  return table;
}

const ParamTable<IntegratorSettings>& integrator_table() {
  using S = IntegratorSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::relative_tolerance, "relative_tolerance", "1",
          "relative tolerance of the adaptive integrators (explicit_runge_kutta, adams)")
        .positive()
        .at_most(1e-3);
    t.add_choice(&S::integrator, "integrator",
                 "time integrator (docs/dynamics.md): fixed_step (fixed steps; exact exponential propagation of "
                 "linear models, Runge-Kutta otherwise), explicit_runge_kutta (adaptive ARKODE Dormand-Prince "
                 "5(4), the reference) or adams (CVODE Adams)",
                 {{"fixed_step", TimeIntegrator::fixed_step},
                  {"explicit_runge_kutta", TimeIntegrator::explicit_runge_kutta},
                  {"adams", TimeIntegrator::adams}});
    t.add(&S::fixed_steps_per_wave, "fixed_steps_per_wave", "1",
          "fixed_step: steps per wave at the model's highest frequency (0: the default, 10 exponential (40 with "
          "one-sided contact) / 60 Runge-Kutta; with initial_waviness_m > 0 never more than 3/4 of the time "
          "between surface samples)")
        .non_negative();
    t.add(&S::divergence_limit_m, "divergence_limit_m", "m", "|displacement| beyond this stops the run as diverged")
        .positive();
    return t;
  }();
  return table;
}

const ParamTable<FitWindowSettings>& fit_window_table() {
  using S = FitWindowSettings;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::fit_start_s, "fit_start_s", "s", "start of the envelope-fit window (default: half-way to its end)")
        .non_negative();
    t.add(&S::fit_end_s, "fit_end_s", "s",
          "end of the envelope-fit window (default: where the contact first opens, else the end of the run)")
        .non_negative();
    t.add(&S::min_frequency_hz, "min_frequency_hz", "Hz",
          "spectral peaks below this are not the dominant (chatter) frequency: the infeed transient and "
          "work-revolution waviness live there")
        .non_negative();
    return t;
  }();
  return table;
}

namespace {

double default_fit_start(const FitWindowSettings& s, double end_s, double delay_s) {
  if (s.fit_start_s) return *s.fit_start_s;
  const double half = 0.5 * end_s;
  return half < delay_s && delay_s < end_s ? delay_s : half;
}

}  // namespace

FitWindow fit_window(const FitWindowSettings& s, double duration_s) {
  const double end = s.fit_end_s ? *s.fit_end_s : duration_s;
  return {default_fit_start(s, end, 0.0), end};
}

FitWindow fit_window(const FitWindowSettings& s, const SimulationResult& run, double delay_s) {
  double end = run.end_time_s;
  if (s.fit_end_s) {
    end = std::min(*s.fit_end_s, run.end_time_s);
  } else {
    for (const auto& [from, to] : run.contact_loss_intervals)
      if (from >= delay_s) {
        end = std::min(from, run.end_time_s);
        break;
      }
  }
  return {default_fit_start(s, end, delay_s), end};
}

double longest_delay_s(const TimeDomainModel& model) {
  double delay = 0.0;
  for (Rotor r : {Rotor::wheel, Rotor::work}) {
    // A rotor whose surface is not regenerated (G6's wheel, G7's work) feeds no delay back: its
    // revolution says nothing about when the regenerated surfaces take over the growth.
    if (!model.regenerates(r)) continue;
    const double rpm = model.nominal_speed_rpm(r);
    if (rpm > 0) delay = std::max(delay, 60.0 / rpm);
  }
  return delay;
}

// ------------------------------------------------------------------ the [simulation] table

const ParamTable<SimulationTable>& simulation_table() {
  using S = SimulationTable;
  static const ParamTable<S> table = [] {
    ParamTable<S> t;
    t.add(&S::duration_s, "duration_s", "s", "simulated time").positive().required();
    t.add(&S::sample_rate_hz, "sample_rate_hz", "Hz", "output sample rate").positive();
    t.add_fields(&S::disturbance, disturbance_table());
    t.add_fields(&S::contact, contact_table());
    t.add(&S::snapshot_times_s, "snapshot_times_s", "s",
          "times at which wheel and work surfaces are written (default: the end)")
        .non_negative();
    t.add_fields(&S::fit, fit_window_table());
    t.add_fields(&S::integration, integrator_table());
    t.add_fields(&S::wheel_speed, speed_law_table(Rotor::wheel));
    t.add_fields(&S::work_speed, speed_law_table(Rotor::work));
    return t;
  }();
  return table;
}

void check_speed_law(const SpeedLawSettings& s, Rotor rotor, double nominal_rpm, const std::string& path,
                     const SourceMap& sources) {
  const std::string prefix = std::string(to_string(rotor)) + "_speed_";
  auto where = [&](const std::string& key) { return sources.locate(path + "." + prefix + key).str(); };
  const std::string shape = shape_name(s.shape);
  if (s.shape == SpeedLawShape::schedule) {
    if (!s.schedule)
      throw InputError(fmt::format("{}: {}.{}modulation = \"schedule\" needs {}schedule (rows [t_s, rpm])",
                                   where("modulation"), path, prefix, prefix));
    for (const std::vector<double>& row : *s.schedule)
      if (row.size() != 2)
        throw InputError(fmt::format("{}: {}.{}schedule = {}: each row must be [t_s, rpm]", where("schedule"), path,
                                     prefix, Json(row).dump()));
  } else if (s.shape != SpeedLawShape::constant && s.amplitude_ratio > 0.0 && !(s.frequency_hz > 0.0)) {
    throw InputError(fmt::format("{}: {}.{}frequency_hz = 0: a {} modulation with amplitude_ratio > 0 needs a "
                                 "frequency > 0",
                                 where("frequency_hz"), path, prefix, shape));
  }
  if (s.shape == SpeedLawShape::constant) return;
  const std::string key = s.shape == SpeedLawShape::schedule ? "schedule" : "modulation";
  try {
    speed_law(s, nominal_rpm);
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: {}.{}{}: {}", where(key), path, prefix, key, e.what()));
  }
}

void check_simulation(SimulationTable& t, const TimeDomainModel& model, const std::string& path,
                      const SourceMap& sources) {
  auto where = [&](const std::string& key) { return sources.locate(path + "." + key).str(); };
  const double samples = t.duration_s * t.sample_rate_hz;
  if (samples > max_output_samples)
    throw InputError(fmt::format(
        "{}: {}.duration_s = {}: duration_s * sample_rate_hz = {:.4g} output samples exceeds the limit of {:.4g} "
        "(shorten duration_s or lower sample_rate_hz = {})",
        where("duration_s"), path, t.duration_s, samples, max_output_samples, t.sample_rate_hz));
  if (samples < 64)
    throw InputError(fmt::format("{}: {}.duration_s = {}: only {:.0f} output samples; at least 64 are needed for "
                                 "the spectrum and the growth fit",
                                 where("duration_s"), path, t.duration_s, samples));
  if (!t.snapshot_times_s) t.snapshot_times_s = std::vector<double>{t.duration_s};
  for (double time : *t.snapshot_times_s)
    if (time > t.duration_s)
      throw InputError(fmt::format("{}: {}.snapshot_times_s = {}: a time is beyond duration_s = {}",
                                   where("snapshot_times_s"), path, Json(time).dump(), t.duration_s));
  const FitWindow fit = fit_window(t.fit, t.duration_s);
  if (!(fit.start_s < fit.end_s) || fit.end_s > t.duration_s)
    throw InputError(fmt::format("{}: {}.fit_start_s/fit_end_s = {}/{}: the envelope-fit window must satisfy "
                                 "fit_start_s < fit_end_s <= duration_s = {}",
                                 where(t.fit.fit_end_s && !t.fit.fit_start_s ? "fit_end_s" : "fit_start_s"), path,
                                 fit.start_s, fit.end_s, t.duration_s));
  check_speed_law(t.wheel_speed, Rotor::wheel, model.nominal_speed_rpm(Rotor::wheel), path, sources);
  check_speed_law(t.work_speed, Rotor::work, model.nominal_speed_rpm(Rotor::work), path, sources);
}

// ------------------------------------------------------------------ to the engine

void apply(const DisturbanceSettings& s, SimulationSettings& engine) {
  engine.disturbance.displacement_m = s.initial_displacement_m;
  engine.disturbance.velocity_m_per_s = s.initial_velocity_m_per_s;
  engine.initial_waviness_m = s.initial_waviness_m;
  engine.seed = s.seed;
}

bool one_sided(const ContactSettings& s) { return s.one_sided_contact.value_or(s.infeed_rate_m_per_s > 0.0); }

void apply(const ContactSettings& s, SimulationSettings& engine) {
  engine.infeed_rate_m_per_s = s.infeed_rate_m_per_s;
  engine.one_sided_contact = one_sided(s);
  engine.contact_arc_deg[static_cast<std::size_t>(Rotor::wheel)] = s.wheel_contact_arc_deg;
  engine.contact_arc_deg[static_cast<std::size_t>(Rotor::work)] = s.work_contact_arc_deg;
}

void apply(const IntegratorSettings& s, SimulationSettings& engine) {
  engine.relative_tolerance = s.relative_tolerance;
  engine.integrator = s.integrator;
  engine.fixed_steps_per_wave = s.fixed_steps_per_wave;
  engine.divergence_limit_m = s.divergence_limit_m;
}

void apply_speed_laws(const SpeedLawSettings& wheel, const SpeedLawSettings& work, const TimeDomainModel& model,
                      SimulationSettings& engine) {
  for (Rotor r : {Rotor::wheel, Rotor::work})
    if (!model.angle_state(r))
      engine.speed[static_cast<std::size_t>(r)] = speed_law(r == Rotor::wheel ? wheel : work, model.nominal_speed_rpm(r));
}

SimulationSettings simulation_settings(const SimulationTable& t, const TimeDomainModel& model) {
  SimulationSettings s;
  s.duration_s = t.duration_s;
  s.sample_rate_hz = t.sample_rate_hz;
  apply(t.disturbance, s);
  apply(t.contact, s);
  s.snapshot_times_s = t.snapshot_times_s.value_or(std::vector<double>{t.duration_s});
  apply(t.integration, s);
  apply_speed_laws(t.wheel_speed, t.work_speed, model, s);
  return s;
}

}  // namespace chatterlab::kit
