// An out-of-tree model plugin that misbehaves on request, for the tests of what a run survives
// (tests/cli/isolate.sh, point_timeout.sh, journal_flush.sh, plugin_errors.sh): at a grid point
// whose `behaviour` says so it hangs, sleeps, crashes, aborts, calls exit(0) or throws a
// non-standard exception. Otherwise it is a first-order system E(s) = s + decay_rate_per_s with
// its one root at s = -decay_rate_per_s, so the ok points have a known answer.
//
// The behaviour happens in evaluate(), which only the root search at run time calls: loading the
// study (which builds the model and asks for its characteristic function) stays well-behaved.
// Except "throw_in_constructor", which is for the load-time error.
#include <chatterlab/plugin_api.hpp>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace misbehaving {

using chatterlab::CharacteristicValue;
using chatterlab::Complex;

class FirstOrder final : public chatterlab::CharacteristicFunction {
 public:
  FirstOrder(double decay, std::string behaviour, double sleep_s)
      : decay_(decay), behaviour_(std::move(behaviour)), sleep_s_(sleep_s) {}

  CharacteristicValue evaluate(Complex s) const override {
    if (!acted_) {
      acted_ = true;
      act();
    }
    return {s + decay_, Complex(1.0, 0.0)};
  }
  void initial_guesses(double, std::vector<Complex>& guesses) const override {
    guesses.emplace_back(-decay_, 0.0);
  }
  double real_part_bound() const override { return 1.0; }
  double natural_frequency_scale_hz() const override { return 1.0; }

 private:
  void act() const {
    if (behaviour_ == "hang")
      for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
    if (behaviour_ == "sleep")
      std::this_thread::sleep_for(std::chrono::duration<double>(sleep_s_));
    if (behaviour_ == "segfault") std::raise(SIGSEGV);
    if (behaviour_ == "abort") std::abort();
    if (behaviour_ == "exit0") std::exit(0);
    if (behaviour_ == "throw_int") throw 42;
  }

  double decay_;
  std::string behaviour_;
  double sleep_s_;
  mutable bool acted_ = false;  // one characteristic function per point and thread
};

class MisbehavingModel final : public chatterlab::Model {
 public:
  explicit MisbehavingModel(const chatterlab::ParamValues& p)
      : decay_(p.real("decay_rate_per_s")),
        behaviour_(p.string("behaviour")),
        sleep_s_(p.real("sleep_s")) {
    if (behaviour_ == "throw_in_constructor") throw 7;
  }

  static chatterlab::PluginInfo info() {
    using chatterlab::param_spec;
    using chatterlab::ValueKind;
    chatterlab::PluginInfo info;
    info.name = "misbehaving_model";
    info.description = "first-order test model that hangs, crashes or exits on request";
    info.thread_safety = chatterlab::ThreadSafety::shareable;
    auto decay = param_spec("decay_rate_per_s", ValueKind::real, "1/s",
                            "the root is at s = -decay_rate_per_s");
    decay.default_value = 2.0;
    decay.min = 0.0;
    decay.min_exclusive = true;
    auto behaviour = param_spec("behaviour", ValueKind::string, "1",
                                "what the point does besides its root search");
    behaviour.default_value = "ok";
    behaviour.choices = {"ok",    "hang",  "sleep",     "segfault",
                         "abort", "exit0", "throw_int", "throw_in_constructor"};
    auto sleep = param_spec("sleep_s", ValueKind::real, "s", "with behaviour = \"sleep\"");
    sleep.default_value = 0.0;
    sleep.min = 0.0;
    info.params = {decay, behaviour, sleep};
    info.example_params = chatterlab::Json::object();
    return info;
  }

  std::unique_ptr<chatterlab::CharacteristicFunction> characteristic() const override {
    return std::make_unique<FirstOrder>(decay_, behaviour_, sleep_s_);
  }

 private:
  double decay_;
  std::string behaviour_;
  double sleep_s_;
};

// A study kind from a library whose constructor throws a non-standard exception: loading a
// study of this kind must be bad input at its `[study] kind` line, naming the kind and library.
class ThrowingStudyKind final : public chatterlab::StudyKind {
 public:
  ThrowingStudyKind() { throw 7; }
  static chatterlab::PluginInfo info() {
    chatterlab::PluginInfo info;
    info.name = "throwing_study_kind";
    info.description = "test study kind whose constructor throws an int";
    return info;
  }
  void validate(chatterlab::Json&, const chatterlab::SourceMap&) const override {}
  std::vector<std::string> output_columns(const chatterlab::Json&) const override { return {}; }
  std::vector<chatterlab::Json> run_point(const chatterlab::Json&,
                                          const chatterlab::PointContext&) const override {
    return {};
  }
  void write_artifacts(const chatterlab::Study&, const chatterlab::ResultTable&,
                       const std::filesystem::path&) const override {}
};

}  // namespace misbehaving

CHATTERLAB_PLUGIN_ENTRY(registries) {
  chatterlab::add_plugin<misbehaving::MisbehavingModel>(registries.models, registries.origin);
  chatterlab::add_study_kind<misbehaving::ThrowingStudyKind>(registries.study_kinds,
                                                             registries.origin);
}
