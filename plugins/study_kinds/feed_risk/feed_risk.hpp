#pragma once
// Chatter risk of a feed plan (issue 5; MODELS.md P, G1, G3, G4, S2): the process model that maps
// each plan segment to the G1 parameters of the [model] (docs/feed_risk.md), the rightmost root
// per segment (stability_map's code path), the accumulated amplification and risk class, one
// time-domain simulation along the whole schedule (streamed, reduced per work revolution), and
// chatter-aware re-planning over the spindle speed and a sinusoidal speed modulation.
// Internal to the `feed_risk` study kind and its tests.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/planner/generatrix.hpp"
#include "chatterlab/planner/plan.hpp"

namespace chatterlab::feed_risk {

// ------------------------------------------------------------------ process model (docs 1)

// What the process model needs besides the plan. The [model]'s own parameters hold at its nominal
// speeds (ProcessConditionsModel::nominal_conditions), the reference contact width and the
// reference work radius; the model maps every segment's conditions to its parameters through its
// process-conditions capability (chatterlab/process_conditions.hpp), so any model that declares it
// works, and the structural modes do not change along the plan.
struct ProcessSettings {
  std::shared_ptr<const Model> model;  // built once from [model]; must have process_conditions()
  double reference_contact_width_mm = 0.0;
  double reference_work_radius_mm = 0.0;
  double wheel_speed_rpm = 0.0;    // along the plan (default: the model's)
  double wheel_diameter_mm = 0.0;  // [wheel] diameter_mm
  bool profiled_wheel = false;
  double wheel_thickness_mm = 0.0;  // face width a
  double edge_radius_mm = 0.0, edge_angle_deg = 180.0;
  double depth_of_cut_mm = 0.0;            // radial stock removed by the pass
  std::optional<double> contact_width_mm;  // fixed width instead of the geometric one
  bool speed_scaling = true;               // G4: kw ~ Kv/(1+Kv), kg ~ 1/(1+Kv)
};

// The model's process-conditions capability; throws std::invalid_argument naming the model's
// failing when it has none (the kind refuses such a model at validation).
const ProcessConditionsModel& process_model(const ProcessSettings& p);

// One segment's process quantities (its model parameters: segment_model_table).
struct SegmentProcess {
  double x_mid_mm = 0.0, radius_mm = 0.0;
  double work_speed_rpm = 0.0;
  double work_surface_speed_m_per_s = 0.0;  // v_w = pi d_w n_w / 60
  double speed_ratio = 0.0;                 // Kv = v_w / v_s (G4)
  double equivalent_diameter_mm = 0.0;      // d_e = d_w d_s / (d_w + d_s) (G4, external)
  double contact_length_mm = 0.0;           // l_c = sqrt(depth d_e)
  double contact_width_mm = 0.0;            // engaged width on the wheel (axial)
  double axial_feed_per_rev_mm = 0.0;       // f_a = v_axial 60 / n_w
  double overlap_ratio = 0.0;               // 1 - f_a / b: regenerated share of the width
};

// Engaged axial width of the wheel section on the part: the chord where the section, tangent at
// the contact, lies within depth_of_cut_mm of the part: 2 sqrt(h (2 rho - h)) with
// 1/rho = 1/r_section + kappa_part (kappa > 0 convex part, r_section = edge radius, or infinite
// for a flat face), capped by the section's own width (face a, or arc chord 2 r sin(alpha/2)).
double contact_width_mm(const ProcessSettings& p, const planner::GeneratrixValue& part);

SegmentProcess map_segment(const ProcessSettings& p, const planner::SegmentConditions& c,
                           const planner::Generatrix& generatrix);

// The reference conditions (at which the model's own parameters hold) and one segment's.
ProcessConditions reference_conditions(const ProcessSettings& p);
ProcessConditions segment_conditions(const ProcessSettings& p, const SegmentProcess& s);

// The [model] table (with its type) at one segment's conditions: ProcessConditionsModel::
// parameters_at of the study's model.
Json segment_model_table(const Json& model_table, const ProcessSettings& p, const SegmentProcess& s);

// ------------------------------------------------------------------ risk along the plan (2a)

struct RiskThresholds {
  // marginal: growth rate above -marginal_growth_rate_per_s, or an amplitude still above the
  // disturbance level (accumulated amplification > 1); chatter: accumulated amplification at or
  // above chatter_amplification.
  double marginal_growth_rate_per_s = 0.1;
  double chatter_amplification = 10.0;
};
enum class Risk { stable = 0, marginal = 1, chatter = 2 };
const char* to_string(Risk risk);

struct SegmentRisk {
  double growth_rate_per_s = 0.0, chatter_frequency_hz = 0.0;
  bool certified = false;
  std::size_t group = 0;
  double log_amplification = 0.0;          // integral of the growth rate up to the segment end
  double floored_log_amplification = 0.0;  // the same, never below 0 (disturbance level)
  Risk risk = Risk::stable;
};

struct RootSettings {
  Json stability;                   // validated [stability] table (stability_map's settings)
  double condition_tolerance = 1e-3;  // relative: segments closer than this share a root
};

// Segments grouped by their G1 parameters (relative tolerance, on a log grid), one certified
// rightmost root per group (OpenMP over groups), then the amplification integral and classes.
// Throws PointFailure naming the segment where a root search failed.
struct PlanRisk {
  std::vector<SegmentProcess> process;
  std::vector<SegmentRisk> segments;
  std::size_t groups = 0;
  double max_growth_rate_per_s = 0.0;
  double final_log_amplification = 0.0;
  double max_floored_log_amplification = 0.0;
  Risk worst = Risk::stable;
  double time_in_risk_s[3] = {0.0, 0.0, 0.0};
};
// Each segment's rightmost root at its conditions; with speed_tolerance > 0 the worst (largest)
// growth rate of the spindle speeds n (1 - tol), n, n (1 + tol) (issue 19: a machine holds its
// speed only within a tolerance, and a verdict at an exact wheel/work speed ratio, where the delay
// lattices share roots, does not survive a small speed error).
PlanRisk evaluate_roots(const Json& model_table, const ProcessSettings& p,
                        const std::vector<planner::SegmentConditions>& plan,
                        const planner::Generatrix& generatrix, const RootSettings& roots,
                        const RiskThresholds& thresholds, double speed_tolerance = 0.0);

// Integral of a piecewise-constant growth rate over segments (ln of the amplitude factor), and its
// floored running form; then the classes. Shared by evaluate_roots and the optimiser.
void accumulate(const std::vector<planner::SegmentConditions>& plan, const RiskThresholds& thresholds,
                PlanRisk& risk);

// ------------------------------------------------------------------ simulation along the plan (2b)

struct AlongPlanSettings {
  double sample_rate_hz = 4000.0;
  // The dynamics engine's route: the fixed-step engine (exact propagation of each segment's linear
  // G1 form) or the adaptive ARKODE reference (relative_tolerance applies to it only).
  TimeIntegrator integrator = TimeIntegrator::fixed_step;
  // Its steps per wave of the model's highest frequency: 5, half the engine's default, which is
  // set for pointwise surfaces over long runs; the plan needs per-revolution envelopes and growth
  // rates (docs/feed_risk.md: 0.1 % from the finer steps' growth rate).
  double fixed_steps_per_wave = 5.0;
  double relative_tolerance = 1e-4;
  double samples_per_wave = 8.0;  // surface samples per wave at the highest frequency (engine: 16)
  double initial_waviness_m = 1e-6;  // initial structural displacement (the disturbance)
  // Random initial wheel and work surfaces of +/- initial_waviness_m as well: white noise up to the
  // surface grid's resolution, which the integrator then resolves at every revolution (about 10x
  // the steps on the G8 machine); off by default, the displacement alone excites every mode.
  bool random_initial_surfaces = false;
  std::uint64_t seed = 1;
  double fit_window_revolutions = 10.0;  // rolling fit of ln(envelope) for the growth rate
  // The linear model stops being valid once the vibration exceeds the depth of cut (the wheel
  // leaves the work): the run ends there as "diverged" (the kind sets the depth of cut).
  double divergence_limit_m = 1.0;
  // Work spindle: null = the plan's own speeds (plan_spindle_speed).
  std::shared_ptr<const SpeedLaw> work_speed;
};

// One row per work revolution.
struct RevolutionRow {
  double t_s = 0.0, x_mm = 0.0;
  double vibration_amplitude_m = 0.0;  // half peak-to-peak of the displacement
  double work_waviness_m = 0.0;        // half peak-to-valley of the work surface generated
  double growth_rate_per_s = 0.0;      // rolling least-squares slope of ln amplitude (NaN at ends)
};

struct AlongPlanSimulation {
  std::vector<RevolutionRow> revolutions;
  std::string status;  // engine status, or the failure message
  bool failed = false;    // numerical failure (the integrator gave up)
  bool diverged = false;  // the vibration reached the divergence limit (the depth of cut)
  double end_time_s = 0.0;
  long steps = 0;
  double wall_s = 0.0;
};

// A TimeDomainModel whose contact and derivatives are those of the segment in progress at t
// (one model per condition group; the structural modes are shared, so the state carries over).
std::unique_ptr<TimeDomainModel> along_plan_model(const Json& model_table, const ProcessSettings& p,
                                                  const std::vector<planner::SegmentConditions>& plan,
                                                  const PlanRisk& risk);

// The plan's spindle speed as a SpeedLaw: constant, or (a plan whose segments differ) each
// segment's speed held over the segment, with 1 ms linear ramps between (make_scheduled_speed).
std::shared_ptr<const SpeedLaw> plan_spindle_speed(const std::vector<planner::SegmentConditions>& plan);

// The simulation along the whole plan, bilateral (linear, as the roots) contact, streamed: never
// throws for a numerical failure (recorded in status/failed).
AlongPlanSimulation simulate_along_plan(const Json& model_table, const ProcessSettings& p,
                                        const std::vector<planner::SegmentConditions>& plan,
                                        const PlanRisk& risk, const AlongPlanSettings& settings);

// Least-squares slope of ln(amplitude) against t over rows with t in [t0, t1].
double fitted_growth_rate_per_s(const std::vector<RevolutionRow>& rows, double t0, double t1);

// ------------------------------------------------------------------ chatter-aware planning (3)

struct OptimiseSettings {
  double spindle_min_rpm = 0.0, spindle_max_rpm = 0.0;  // machine range
  int speed_steps = 11;
  std::vector<double> amplitude_ratios{0.0};
  double modulation_frequency_hz = 0.5;
  int phase_samples = 8;              // frozen-speed average over a modulation cycle (S2, 5-37)
  double max_time_factor = 1.2;       // total time <= this x the baseline plan's
  double condition_tolerance = 1e-2;  // coarser grouping for the search
  double speed_tolerance = 0.005;     // candidates rated by their worst case over n (1 +- tol)
};

struct Candidate {
  double spindle_speed_rpm = 0.0, amplitude_ratio = 0.0, planning_speed_rpm = 0.0;
  double total_time_s = 0.0, time_factor = 0.0;
  double max_growth_rate_per_s = 0.0, max_floored_log_amplification = 0.0;
  Risk worst = Risk::stable;  // over the speed band, like the two maxima above
  double nominal_max_growth_rate_per_s = 0.0;  // at the nominal speed alone
  std::string exact_speed_ratio;  // wheel : work speed as p/q (q <= 12) when exact, else empty
  bool admissible = false;  // within the time limit
};

// Re-plans at a spindle speed: the planner's segments at that speed. optimise calls it once per
// planning speed, concurrently from its OpenMP threads: it must be thread-safe.
using Replan = std::function<std::vector<planner::SegmentConditions>(double spindle_speed_rpm)>;

struct OptimiseResult {
  std::vector<Candidate> candidates;
  std::size_t best = 0;
  std::vector<planner::SegmentConditions> best_plan;  // at the best candidate's mean speed
  // Whether the best candidate is stable over its whole speed band, and then the contiguous range
  // of candidate speeds around it (same modulation) that are too: the window the machine may
  // drift in. Its ends are known to the candidate spacing.
  bool stable = false;
  std::optional<std::pair<double, double>> stable_window_rpm;
  double speed_spacing_rpm = 0.0;
};

// Spindle speeds evenly over the admissible range of each amplitude ratio a (mean speeds n with
// n (1 - a) >= min and n (1 + a) <= max); each candidate re-planned at its lowest instantaneous
// speed n (1 - a) (the advance-per-revolution rule then holds at every instant) and rated by the
// frozen-speed average growth rate per segment; best = least max floored amplification among
// those within the time limit (ties: shorter time). Throws InputError-free std::invalid_argument
// when an amplitude ratio leaves no admissible speed (validation checks that first).
OptimiseResult optimise(const Json& model_table, const ProcessSettings& p, const Replan& replan,
                        double baseline_time_s, const planner::Generatrix& generatrix,
                        const RootSettings& roots, const RiskThresholds& thresholds,
                        const OptimiseSettings& settings);

// ------------------------------------------------------------------ levers (issue 19: true advice)

// What would make one segment's conditions stable: the growth rate's sensitivity to a process
// condition, the relative change that a linear extrapolation says reaches the target growth rate,
// and the growth rate actually computed at that change (stability lobes make the speeds' response
// anything but linear, so the check decides, not the extrapolation).
struct Lever {
  std::string name;        // e.g. "width of cut"
  std::string acts_on;     // the process condition it changes
  double growth_per_unit_log = 0.0;  // d Re s / d ln(quantity) [1/s]
  std::optional<double> change_percent;  // the change tried (none: no effect in the model)
  double growth_rate_after_per_s = 0.0;  // rightmost root with that change
  bool reaches_target = false;
};

// The levers at a segment's conditions: width of cut, work speed, wheel speed and depth of cut,
// each changed through the model's process-conditions capability (what the model's parameters
// do with it is the model's business) up to a factor max_factor either way. target_growth_per_s
// < 0 is the growth rate to reach; growth rates are the worst over work speeds n (1 +-
// speed_tolerance), as the re-plan rates its candidates.
std::vector<Lever> stability_levers(const Json& model_table, const ProcessSettings& p, const SegmentProcess& segment,
                                    const RootSettings& roots, double target_growth_per_s, double speed_tolerance,
                                    double max_factor = 3.0);

}  // namespace chatterlab::feed_risk
