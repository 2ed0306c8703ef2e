// Tests of the {{name}} suppression law: the library is loaded exactly as `chatterlab` loads it
// (by path, argument 1), then held to the conformance suite and to properties of the law: its
// closed-form integral against quadrature, its levels, and a kept mean.
#include <chatterlab/plugin_api.hpp>
#include <chatterlab/plugin_test.hpp>
#include <chatterlab/suppression.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace {

// Composite Simpson rule of the level over [0, t] (an independent route to level_integral).
double simpson(const chatterlab::ModulationLaw& law, double t, int intervals) {
  const double h = t / intervals;
  double sum = law.level(0.0) + law.level(t);
  for (int i = 1; i < intervals; ++i) sum += (i % 2 ? 4.0 : 2.0) * law.level(i * h);
  return sum * h / 3.0;
}

}  // namespace

int main(int argc, char** argv) {
  // Loads the library (argument 1) as chatterlab does and runs the conformance suite first.
  return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {

    const auto suppression = chatterlab::suppression_registry().at("{{name}}").create(chatterlab::ParamValues(
        {{"target", "work_speed"}, {"amplitude_ratio", 0.1}, {"frequency_hz", 2.0}, {"dwell", 0.4}}));
    check(suppression->target() == chatterlab::SuppressionTarget::work_speed, "target");
    check(std::abs(suppression->modulation_period_s() - 0.5) < 1e-15, "period = 1 / frequency");
    const auto law = suppression->law(10.0);
    double error = 0.0, lowest = 2.0, highest = 0.0;
    for (double t : {0.01, 0.1, 0.23, 0.37, 0.5, 1.0, 3.14159, 7.77}) {
      error = std::max(error, std::abs(law->level_integral(t) - simpson(*law, t, 200000)));
    }
    for (int i = 0; i <= 10000; ++i) {
      lowest = std::min(lowest, law->level(i * 1e-4));
      highest = std::max(highest, law->level(i * 1e-4));
    }
    check(error < 1e-9, "level_integral agrees with Simpson quadrature");
    check(std::abs(lowest - 0.9) < 1e-12 && std::abs(highest - 1.1) < 1e-12, "levels 1 -/+ amplitude");
    check(std::abs(law->min_level() - 0.9) < 1e-15 && std::abs(law->max_level() - 1.1) < 1e-15, "declared level bounds");
    check(std::abs(law->level_integral(5.0) - 5.0) < 1e-12, "whole periods keep the mean speed");
  });
}
