#pragma once
// Study kit: the settings of a time-domain simulation (chatterlab/dynamics.hpp), declared once
// as ParamTables and turned into the engine's SimulationSettings. The parts are separate so that
// a kind with its own table (suppression_map's [suppression_map], feed_risk's [feed_risk]) embeds
// the ones it needs with ParamTable::add_fields, overriding defaults through its own struct's
// member initialisers; the `simulate` kind's [simulation] table is SimulationTable, all of them.
//
//     struct MySettings { double revolutions = 40; kit::IntegratorSettings integration{1e-4}; };
//     t.add_fields(&MySettings::integration, kit::integrator_table());
//     ...  SimulationSettings s;  kit::apply(settings.integration, s);
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab::kit {

// ------------------------------------------------------------------ parts

// One rotor's speed law around the model's nominal speed; keys <rotor>_speed_modulation,
// <rotor>_speed_amplitude_ratio, <rotor>_speed_frequency_hz, <rotor>_speed_schedule.
enum class SpeedLawShape { constant, sinusoidal, triangular, square, schedule };
struct SpeedLawSettings {
  SpeedLawShape shape = SpeedLawShape::constant;
  double amplitude_ratio = 0.0;  // of the mean speed, < 1
  double frequency_hz = 0.0;
  std::optional<std::vector<std::vector<double>>> schedule;  // rows [t_s, rpm] (shape schedule)
};
const ParamTable<SpeedLawSettings>& speed_law_table(Rotor rotor);
// The law (constant at nominal_rpm for shape constant). Throws std::invalid_argument for a law
// the engine refuses (a schedule's times not increasing, a speed that reaches 0, ...).
std::shared_ptr<const SpeedLaw> speed_law(const SpeedLawSettings& settings, double nominal_rpm);

// The disturbance that starts the run.
struct DisturbanceSettings {
  double initial_displacement_m = 1e-6;
  double initial_velocity_m_per_s = 0.0;
  double initial_waviness_m = 0.0;  // random initial wheel and work surfaces (uniform +/-)
  std::uint64_t seed = 1;
};
const ParamTable<DisturbanceSettings>& disturbance_table();

// The wheel-work contact: infeed, one-sided or bilateral force, geometric filtering arcs (G4).
struct ContactSettings {
  double infeed_rate_m_per_s = 0.0;
  std::optional<bool> one_sided_contact;  // absent: one-sided exactly when there is an infeed
  double wheel_contact_arc_deg = 0.0, work_contact_arc_deg = 0.0;
};
const ParamTable<ContactSettings>& contact_table();
// Whether the contact is one-sided. Without an infeed the mean depth of cut is zero, so a
// one-sided contact opens at the first vibration and never carries the linear growth (issue 19);
// the bilateral contact is then the linearisation the roots describe.
bool one_sided(const ContactSettings& settings);

// The integrator and the end of a run that runs away (docs/dynamics.md: the fixed-step engine is
// the default route, the adaptive SUNDIALS integrators the reference).
struct IntegratorSettings {
  double relative_tolerance = 1e-6;  // adaptive routes only
  TimeIntegrator integrator = TimeIntegrator::fixed_step;
  double divergence_limit_m = 0.01;
  double fixed_steps_per_wave = 0.0;  // fixed_step only; 0: the engine's documented default
};
const ParamTable<IntegratorSettings>& integrator_table();

// The window of the growth-rate fit (fit_envelope) and its spectral floor.
struct FitWindowSettings {
  std::optional<double> fit_start_s;  // default: half the duration
  std::optional<double> fit_end_s;    // default: the end
  double min_frequency_hz = 10.0;
};
const ParamTable<FitWindowSettings>& fit_window_table();
struct FitWindow {
  double start_s = 0.0, end_s = 0.0;
};
// The window as given, for checks before a run (a default end is the end of the run).
FitWindow fit_window(const FitWindowSettings& settings, double duration_s);
// The window of a finished run. The default is the later half of the linear regime: it ends where
// the contact first opens after the longest regenerative delay (after that the amplitude is
// limited by lift-off, not by the roots; lift-offs while the infeed builds the first cut do not
// count) or at the end of the run, and starts half-way there but not before that delay (only then
// are the regenerated surfaces under the contact). Explicit fit_start_s / fit_end_s are taken as
// given (the end clipped to the run); assess_fit (chatterlab/fit_validity.hpp) judges either.
FitWindow fit_window(const FitWindowSettings& settings, const SimulationResult& run, double longest_delay_s);
// The longest regenerative delay of a model: one revolution, at nominal speed, of the slowest rotor
// whose surface it regenerates (0 when it regenerates none).
double longest_delay_s(const TimeDomainModel& model);

// ------------------------------------------------------------------ the [simulation] table

struct SimulationTable {
  double duration_s = 0.0;  // required
  double sample_rate_hz = 20000.0;
  DisturbanceSettings disturbance;
  ContactSettings contact;
  std::optional<std::vector<double>> snapshot_times_s;  // default (after validation): the end
  FitWindowSettings fit;
  IntegratorSettings integration;
  SpeedLawSettings wheel_speed, work_speed;
};
const ParamTable<SimulationTable>& simulation_table();

// What single keys cannot check, as InputError naming `path`.<key> with file and line: output
// samples within [64, max_output_samples], snapshot times within the duration (absent: the end),
// a fit window inside the run, speed laws the engine accepts at the model's nominal speeds.
void check_simulation(SimulationTable& table, const TimeDomainModel& model, const std::string& path,
                      const SourceMap& sources);
// The speed-law part of check_simulation, for kinds whose table has speed laws but no duration.
void check_speed_law(const SpeedLawSettings& settings, Rotor rotor, double nominal_rpm, const std::string& path,
                     const SourceMap& sources);

// ------------------------------------------------------------------ to the engine

void apply(const DisturbanceSettings& settings, SimulationSettings& engine);
void apply(const ContactSettings& settings, SimulationSettings& engine);
void apply(const IntegratorSettings& settings, SimulationSettings& engine);
// The speed laws of the rotors whose speed is not a state of the model (TimeDomainModel::angle_state).
void apply_speed_laws(const SpeedLawSettings& wheel, const SpeedLawSettings& work, const TimeDomainModel& model,
                      SimulationSettings& engine);

// The engine settings of a validated [simulation] table for `model`.
SimulationSettings simulation_settings(const SimulationTable& table, const TimeDomainModel& model);

}  // namespace chatterlab::kit
