// Tests of the {{name}} analysis: the library is loaded exactly as `chatterlab` loads it (by path,
// argument 1), then held to the conformance suite and to the known answers of a sine.
#include <chatterlab/analysis.hpp>
#include <chatterlab/plugin_api.hpp>
#include <chatterlab/plugin_test.hpp>

#include <cmath>
#include <numbers>
#include <string>

int main(int argc, char** argv) {
  // Loads the library (argument 1) as chatterlab does and runs the conformance suite first.
  return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {

    // A pure sine, amplitude 2, 50 Hz on a bin centre (1 kHz, 4000 samples: 0.25 Hz bins):
    // RMS = 2 / sqrt 2, crest factor sqrt 2, the line at 50 Hz holds all the power.
    chatterlab::SampledSeries sine;
    sine.sample_interval = 1e-3;
    sine.name = "sine";
    for (int i = 0; i < 4000; ++i) sine.values.push_back(2.0 * std::sin(2.0 * std::numbers::pi * 50.0 * i * 1e-3));
    const auto analysis = chatterlab::analysis_registry().at("{{name}}").create(chatterlab::ParamValues({{"band_hz", 5.0}, {"min_samples", 64}}));
    const chatterlab::Json r = analysis->analyse(sine, chatterlab::Json::object());
    std::cout << r.dump() << '\n';
    check(std::abs(r["rms"].get<double>() - std::sqrt(2.0)) < 1e-9, "RMS of a sine");
    check(std::abs(r["crest_factor"].get<double>() - std::sqrt(2.0)) < 1e-6, "crest factor of a sine");
    check(std::abs(r["dominant_frequency_hz"].get<double>() - 50.0) < 0.01, "dominant frequency");
    check(std::abs(r["dominant_amplitude"].get<double>() - 2.0) < 1e-6, "line amplitude");
    check(r["line_power_share"].get<double>() > 0.99, "the line holds the power");

    // Bad input is refused with the reason.
    sine.values.resize(10);
    bool refused = false;
    try {
      analysis->analyse(sine, chatterlab::Json::object());
    } catch (const chatterlab::InputError& e) {
      refused = std::string(e.what()).find("at least 64") != std::string::npos;
    }
    check(refused, "a series shorter than min_samples is refused, naming the minimum");
  });
}
