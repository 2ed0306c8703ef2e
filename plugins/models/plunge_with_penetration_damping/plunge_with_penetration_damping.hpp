#pragma once
// MODELS.md G1 with the dynamic grinding force of G4 (book eqs 2-75..2-78): the work removal
// force has a static part kw (= ks, proportional to the depth of cut, regenerating once per work
// revolution) and a dynamic part kd (proportional to the penetration rate, damping-like, not
// regenerating):
//
//   Fn = kw (Ww(t) - Ww(t - Tw)) + kd dWw/dt   ->   Ww = Fn / (kw (1 - e^{-Tw s}) + kd s),
//   D(s) = 1 + kc [ H(s) + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s}) + kd s) ].
//
// kd = 0 is plunge_regenerative. G1's entire function is affine in B = 1 - e^{-Tw s}, and kd only
// replaces B by B + (kd/kw) s, so E(s) = E_G1(s) + (kd/kw) s E_G1,work off(s): the characteristic
// function is built from two plunge_regenerative ones. kd = ks sqrt(de u0)/vw
// (grinding_process.hpp). Docs: docs/models/plunge_with_penetration_damping.md.
#include <memory>
#include <optional>

#include "chatterlab/characteristic.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/registry.hpp"
#include "models/plunge_regenerative/plunge_regenerative.hpp"

namespace chatterlab {

class PenetrationDampingCharacteristic final : public CharacteristicFunction {
 public:
  PenetrationDampingCharacteristic(const PlungeRegenerativeParameters& parameters,
                                   double penetration_damping_n_s_per_m);

  CharacteristicValue evaluate(Complex s) const override;
  std::vector<Complex> neutral_roots(double max_angular_frequency_rad_s) const override;
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override;
  double real_part_bound() const override;
  double natural_frequency_scale_hz() const override;

 private:
  PlungeRegenerativeParameters parameters_;
  PlungeCharacteristic full_, work_off_;
  double delay_ratio_;  // kd/kw [s] (0 when the work chain is off)
};

class PlungeWithPenetrationDamping final : public Model {
 public:
  explicit PlungeWithPenetrationDamping(const ParamValues& values);

  static PluginInfo info();

  std::unique_ptr<CharacteristicFunction> characteristic() const override;
  std::optional<double> wheel_period_s() const override;

 private:
  PlungeRegenerativeParameters parameters_;
  double penetration_damping_n_s_per_m_;
};

}  // namespace chatterlab
