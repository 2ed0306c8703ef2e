// A plugin library that breaks the contract on purpose, for `chatterlab check-plugin` (tests/sdk):
// its characteristic function reports a wrong derivative, and it declares itself shareable
// although evaluate() counts its calls in a member that changes the result (a cache gone wrong).
// The conformance suite must name both failures and exit 1.
#include <chatterlab/plugin_api.hpp>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

namespace {

using chatterlab::Complex;

class CountingCharacteristic final : public chatterlab::CharacteristicFunction {
 public:
  explicit CountingCharacteristic(int* calls) : calls_(calls) {}
  // E(s) = s^2 / w^2 + 2 zeta s / w + 1 + (calls so far) * 1e-9: depends on the history.
  chatterlab::CharacteristicValue evaluate(Complex s) const override {
    const double w = 2.0 * std::numbers::pi * 100.0;
    ++*calls_;
    return {s * s / (w * w) + 0.1 * s / w + 1.0 + 1e-9 * *calls_, 3.0 * s / (w * w)};  // E' is wrong
  }
  void initial_guesses(double, std::vector<Complex>& guesses) const override {
    guesses.emplace_back(-31.4, 628.0);
  }
  double real_part_bound() const override { return 1.0; }
  double natural_frequency_scale_hz() const override { return 100.0; }

 private:
  int* calls_;
};

class BrokenModel final : public chatterlab::Model {
 public:
  explicit BrokenModel(const chatterlab::ParamValues&) {}
  static chatterlab::PluginInfo info() {
    chatterlab::PluginInfo info;
    info.name = "broken_model";
    info.description = "breaks the plugin contract on purpose (check-plugin test)";
    info.thread_safety = chatterlab::ThreadSafety::shareable;  // it is not
    return info;
  }
  std::unique_ptr<chatterlab::CharacteristicFunction> characteristic() const override {
    return std::make_unique<CountingCharacteristic>(&calls_);
  }

 private:
  mutable int calls_ = 0;
};

}  // namespace

CHATTERLAB_PLUGIN_ENTRY(registries) {
  chatterlab::add_plugin<BrokenModel>(registries.models, registries.origin);
}
