#pragma once
// What both routes of the dynamics engine share (chatterlab/dynamics.hpp): the rotors (speed laws
// or angle states, angle-indexed surface memories), the model's input at a time and state, the
// surface writes as the contact passes grid angles, output samples, snapshots, divergence and
// the contact-loss log. A route (sundials_engine.cpp, fixed_step_engine.cpp) supplies the time
// stepping and the state inside its last step (state_at).
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "dynamics/surface_memory.hpp"

namespace chatterlab::dynamics_detail {

// Throws std::invalid_argument for settings outside their limits (simulate() calls it first).
void validate_settings(const SimulationSettings& settings);

// How evaluate_contact settles one-sided contact.
enum class Settle {
  by_penetration,  // force and removal zero where penetration <= 0 (the physical law)
  in_contact,      // the in-contact law even at a small negative penetration (a Runge-Kutta stage
                   // of a step that lies in contact: the law continued smoothly across the event)
  free,            // force and removal zero (a stage of a step out of contact)
  none,            // the raw contact output (event functions)
};

class EngineCore {
 public:
  EngineCore(const TimeDomainModel& model, const SimulationSettings& settings);
  virtual ~EngineCore() = default;
  EngineCore(const EngineCore&) = delete;
  EngineCore& operator=(const EngineCore&) = delete;

 protected:
  struct RotorState {
    std::shared_ptr<const SpeedLaw> law;     // null when the angle is a model state
    std::optional<std::size_t> angle_state;  // index of the angle in the state
    std::optional<SurfaceMemory> surface;    // when regenerated
    // A law constant over the run: its speed [rad/s] (angle = omega t), read without the
    // virtual calls of the law (0 otherwise). Reads of speed and angle are the engine's
    // innermost operation (every right-hand side, surface write and sample).
    double constant_rad_per_s = 0.0;
    double constant_rpm = 0.0;
    double arc_rad = 0.0;
  };

  // The state at t inside the route's last step (dense output), or the current state before the
  // first step. May reuse one buffer: the span is valid until the next call.
  virtual std::span<const double> state_at(double t) = 0;
  // Called before each batch of surface writes (the SUNDIALS route invalidates its cache).
  virtual void before_surface_writes() {}

  double rotor_angle(std::size_t r, double t, std::span<const double> x) const;
  double rotor_rpm(std::size_t r, double t, std::span<const double> x) const;
  // The model's input at (t, x) (x may be empty for models whose angles are not states: the
  // linear forcing) and its contact output, settled as asked. known_rotor < rotor_count: that
  // rotor's previous surface is known_previous_m (a surface write at its own grid angle, where it
  // is exactly the sample one revolution back).
  void evaluate_contact(double t, std::span<const double> x, ContactInput& in, ContactOutput& out,
                        Settle settle = Settle::by_penetration, std::size_t known_rotor = rotor_count,
                        double known_previous_m = 0.0) const;
  double penetration(double t, std::span<const double> x) const;
  // The model's input averaged over the time cell [t_a, t_b] for the linear forcing (no state):
  // each regenerated surface (without a contact arc) and the infeed averaged exactly over the
  // cell, time, speeds, angles and arc means at its midpoint.
  void cell_input(double t_a, double t_b, ContactInput& in) const;
  // Time in [t_lo, t_hi] at which rotor r reaches angle `target` (angles increase).
  double time_of_angle(std::size_t r, double target, double t_lo, double t_hi);
  // True if every surface read of `in` used written (or initial) samples only.
  bool reads_settled(const ContactInput& in) const;
  // Writes every surface grid point the contact passed up to t_end (after a step from t_start).
  void write_surfaces(double t_start, double t_end);
  // Output samples with time <= t + slack not yet recorded; false (and the run marked diverged)
  // when an output is not finite. slack > 0: a sample a rounding error beyond t (the fixed-step
  // engine's step ends coincide with sample times up to rounding).
  bool record_samples_until(double t, double slack = 0.0);
  void take_snapshots_until(double t);
  // The time of the next snapshot not yet taken (infinity when none).
  double next_snapshot_time() const;
  // True if the run must stop: x not finite or displacement beyond the limit (status set).
  bool check_divergence(double t, std::span<const double> x);
  // Contact-loss log (one-sided contact): a switch at t.
  void contact_switch(double t, bool entering);
  // Fills the result's end state, counts, status and diagnostics.
  SimulationResult finish(double t_end, std::span<const double> x);

  const TimeDomainModel& model_;
  const SimulationSettings& settings_;
  std::size_t n_;
  RotorState rotors_[rotor_count];
  double f_max_ = 0.0, max_rpm_ = 0.0;
  // The model input of the hot paths (right-hand side, surface writes, output samples), reused:
  // evaluate_contact sets every field, and a fresh one cost a zero fill of 88 bytes per call.
  ContactInput contact_input_;
  std::vector<std::string> diagnostics_;
  SimulationResult result_;
  bool in_contact_ = true;  // one-sided contact: the current side

 private:
  void setup_rotor(Rotor r);
  bool record_sample(double t);
  void take_snapshot(double t);

  std::vector<double> snapshot_times_;
  std::size_t next_snapshot_ = 0;
  std::size_t sample_count_ = 0, next_sample_ = 0;
  double lost_since_ = 0.0;
};

}  // namespace chatterlab::dynamics_detail
