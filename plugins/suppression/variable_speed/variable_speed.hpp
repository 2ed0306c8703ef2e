#pragma once
// Suppression plugin `variable_speed` (MODELS.md S1-S3, book 5.3): modulation of the wheel speed
// (S2), the work speed (S3) or the infeed rate (S1) around its mean,
//
//   q(t) = q_mean (1 + amplitude_ratio w(t)),   |w| <= 1,   0 <= amplitude_ratio < 1,
//
// so the modulated quantity never reaches zero (a spindle that would stop or reverse is refused).
// Shapes w: sinusoidal sin(2 pi f t), triangular and square waves in the sine's phase (the dynamics
// engine's waveforms, chatterlab/dynamics.hpp), and `random`: seeded, reproducible levels L_k
// uniform in [-1, 1] at knots t_k = k/f (L_0 = 0), joined by raised-cosine segments
// w = L_k + (L_{k+1} - L_k)(1 - cos(pi u))/2, u = f t - k. Its rms is 1/2 (E[L^2] = 1/3 times
// the mean 3/4 of (1-s)^2 + s^2 over a segment), its autocorrelation vanishes beyond the lag 2/f
// (knots independent), so its power lies below ~f: a smooth random speed with correlation time 1/f.
// Docs: docs/suppression.md.
#include <cstdint>
#include <memory>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/suppression.hpp"

namespace chatterlab {

enum class ModulationShape { sinusoidal, triangular, square, random };

struct VariableSpeedParameters {
  SuppressionTarget target = SuppressionTarget::wheel_speed;
  ModulationShape shape = ModulationShape::sinusoidal;
  double amplitude_ratio = 0.0;
  double frequency_hz = 1.0;
  std::uint64_t seed = 1;
};

// The unit random waveform w(t) above on [0, horizon] (levels beyond it are drawn on demand, the
// same values: each level is a hash of (seed, k), not a stream position).
class RandomWaveform {
 public:
  RandomWaveform(std::uint64_t seed, double frequency_hz, double horizon_s);
  double value(double t_s) const;
  double integral(double t_s) const;  // integral of w from 0 [s]

 private:
  double knot_level(std::size_t k) const;
  double draw(std::size_t k) const;  // level k from (seed, k) alone
  double prefix_integral(std::size_t k) const;  // integral up to knot k [s]
  std::uint64_t seed_;
  double frequency_hz_;
  std::vector<double> levels_, prefix_;  // knots 0..K and the integral up to each
};

// The law q(t)/q_mean of the parameters (horizon: for the random shape).
std::shared_ptr<const ModulationLaw> make_modulation_law(const VariableSpeedParameters& p,
                                                         double horizon_s);

class VariableSpeed final : public Suppression {
 public:
  explicit VariableSpeed(const ParamValues& values);
  explicit VariableSpeed(VariableSpeedParameters parameters);
  static PluginInfo info();

  SuppressionTarget target() const override { return p_.target; }
  std::shared_ptr<const ModulationLaw> law(double horizon_s) const override;
  double modulation_period_s() const override;
  const VariableSpeedParameters& parameters() const { return p_; }

 private:
  VariableSpeedParameters p_;
};

}  // namespace chatterlab
