// An out-of-tree model plugin, built as its own shared library against the public headers only
// (docs/plugins.md walks through it). It registers `example_delay_model`: one structural mode
// regenerating its own surface once per workpiece revolution (single-delay version of the
// workpiece chain of MODELS.md G1):
//
//   m x'' + c x' + k x = -kc (x(t) - x(t - T)),   T = 60 / work_speed_rpm,
//
// divided by k, with w = 2 pi natural_frequency_hz and K = kc / k:
//
//   E(s) = s^2 / w^2 + 2 zeta s / w + 1 + K (1 - e^{-sT})    (entire: no denominators)
#include <chatterlab/plugin_api.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

namespace example {

using chatterlab::CharacteristicFunction;
using chatterlab::CharacteristicValue;
using chatterlab::Complex;

class DelayCharacteristic final : public CharacteristicFunction {
 public:
  DelayCharacteristic(double omega, double zeta, double stiffness_ratio, double delay_s)
      : omega_(omega), zeta_(zeta), k_(stiffness_ratio), delay_(delay_s) {}

  CharacteristicValue evaluate(Complex s) const override {
    const Complex regeneration = std::exp(-s * delay_);
    const Complex structure = s * s / (omega_ * omega_) + 2.0 * zeta_ * s / omega_ + 1.0;
    return {structure + k_ * (1.0 - regeneration),
            2.0 * s / (omega_ * omega_) + 2.0 * zeta_ / omega_ + k_ * delay_ * regeneration};
  }

  // Roots sit near the structural pole and along the delay lattice Im s = 2 pi j / T, where
  // |e^{-sT}| = |P(s) + K| / K fixes Re s = -ln(|P + K| / K) / T (P: the structural part).
  void initial_guesses(double max_angular_frequency_rad_s,
                       std::vector<Complex>& guesses) const override {
    guesses.emplace_back(-zeta_ * omega_,
                         omega_ * std::sqrt(std::max(1.0 + k_ - zeta_ * zeta_, 0.0)));
    if (k_ <= 0.0) return;  // no regeneration: the structural pole is the only root
    const double spacing = 2.0 * std::numbers::pi / delay_;
    for (double w = 0.0; w <= max_angular_frequency_rad_s + spacing; w += spacing) {
      const Complex iw(0.0, w);
      const Complex p_plus_k = iw * iw / (omega_ * omega_) + 2.0 * zeta_ * iw / omega_ + 1.0 + k_;
      const double re = -std::log(std::abs(p_plus_k) / k_) / delay_;
      guesses.emplace_back(std::min(re, real_part_bound()), w);
    }
  }

  // Proof: at a zero with Re s = sigma >= 0, |P(s) + K| = K |e^{-sT}| <= K, and
  // P(s) + K = (s - p1)(s - p2) / w^2 with Re p1, Re p2 <= 0 (zeta >= 0, K >= 0), so
  // |P(s) + K| >= sigma^2 / w^2. Hence sigma <= w sqrt(K); the margin keeps the bound strict.
  double real_part_bound() const override { return omega_ * std::sqrt(k_) + 1e-3 * omega_; }

  double natural_frequency_scale_hz() const override { return omega_ / (2.0 * std::numbers::pi); }

 private:
  double omega_, zeta_, k_, delay_;
};

class ExampleDelayModel final : public chatterlab::Model {
 public:
  explicit ExampleDelayModel(const chatterlab::ParamValues& p)
      : omega_(2.0 * std::numbers::pi * p.real("natural_frequency_hz")),
        zeta_(p.real("damping_ratio")),
        stiffness_ratio_(p.real("stiffness_ratio")),
        delay_s_(60.0 / p.real("work_speed_rpm")) {}

  static chatterlab::PluginInfo info() {
    using chatterlab::param_spec;
    using chatterlab::ValueKind;
    chatterlab::PluginInfo info;
    info.name = "example_delay_model";
    info.description = "one structural mode with workpiece regeneration (out-of-tree example)";
    info.models_md_ids = "G1 (workpiece chain, one mode)";
    // evaluate() only reads members: one instance can serve every thread.
    info.thread_safety = chatterlab::ThreadSafety::shareable;

    auto frequency = param_spec("natural_frequency_hz", ValueKind::real, "Hz",
                                "natural frequency of the structural mode");
    frequency.min = 0.0;
    frequency.min_exclusive = true;

    auto damping = param_spec("damping_ratio", ValueKind::real, "1", "modal damping ratio");
    damping.default_value = 0.05;
    damping.min = 0.0;
    damping.max = 1.0;
    damping.max_exclusive = true;

    auto stiffness = param_spec("stiffness_ratio", ValueKind::real, "1",
                                "grinding stiffness over structural stiffness, kc / k");
    stiffness.min = 0.0;

    auto speed = param_spec("work_speed_rpm", ValueKind::real, "rpm",
                            "workpiece speed; the regenerative delay is one revolution, 60 / n");
    speed.min = 0.0;
    speed.min_exclusive = true;

    info.params = {frequency, damping, stiffness, speed};
    info.example_params = {
        {"natural_frequency_hz", 50.0}, {"stiffness_ratio", 0.5}, {"work_speed_rpm", 600.0}};
    return info;
  }

  std::unique_ptr<CharacteristicFunction> characteristic() const override {
    return std::make_unique<DelayCharacteristic>(omega_, zeta_, stiffness_ratio_, delay_s_);
  }

 private:
  double omega_, zeta_, stiffness_ratio_, delay_s_;
};

}  // namespace example

// The library's one exported symbol. The host calls it with its API version; the macro registers
// only when that equals the version these headers carry, and reports its own either way.
CHATTERLAB_PLUGIN_ENTRY(registries) {
  chatterlab::add_plugin<example::ExampleDelayModel>(registries.models, registries.origin);
}
