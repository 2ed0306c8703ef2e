// Tests of two_dof_model: the conformance suite (the derived characteristic function against the
// simulated time-domain form, thread safety, parameter checks), then a known answer from outside
// the tutorial: two modes in series are MODELS.md G1 with two summed modal compliances, whose
// characteristic function eq 2-16 chatterlab's built-in plunge_regenerative writes out by hand.
#include <chatterlab/kit/model.hpp>
#include <chatterlab/plugin_test.hpp>

#include <cmath>
#include <complex>

int main(int argc, char** argv) {
  return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {
    for (double work_rpm : {30.0, 60.0, 120.0}) {
      const chatterlab::Json tutorial = {
          {"type", "two_dof_model"}, {"wheel_speed_rpm", 1500.0}, {"work_speed_rpm", work_rpm},
          {"contact_stiffness_n_per_m", 1e8}, {"wheel_wear_stiffness_n_per_m", 5e9},
          {"work_removal_stiffness_n_per_m", 5e7}, {"wheelhead_frequency_hz", 120.0},
          {"wheelhead_damping_ratio", 0.05}, {"wheelhead_stiffness_n_per_m", 5e7},
          {"workpiece_frequency_hz", 300.0}, {"workpiece_damping_ratio", 0.03},
          {"workpiece_stiffness_n_per_m", 8e7}};
      const chatterlab::Json g1 = {
          {"type", "plunge_regenerative"}, {"wheel_speed_rpm", 1500.0}, {"work_speed_rpm", work_rpm},
          {"contact_stiffness_n_per_m", 1e8}, {"wheel_wear_stiffness_n_per_m", 5e9},
          {"work_removal_stiffness_n_per_m", 5e7},
          {"modes", {{{"frequency_hz", 120.0}, {"damping_ratio", 0.05}, {"stiffness_n_per_m", 5e7}},
                     {{"frequency_hz", 300.0}, {"damping_ratio", 0.03}, {"stiffness_n_per_m", 8e7}}}}};
      chatterlab::kit::StabilitySettings settings;
      settings.max_frequency_hz = 600.0;
      const auto derived = chatterlab::kit::rightmost_root(*chatterlab::kit::build_model(tutorial), settings);
      const auto by_hand = chatterlab::kit::rightmost_root(*chatterlab::kit::build_model(g1), settings);
      check(derived.certified, "work speed " + std::to_string(work_rpm) + " rpm: the derived root is certified");
      check(std::abs(derived.root - by_hand.root) <= 1e-9 * std::abs(by_hand.root),
            "... and equals G1 eq 2-16's rightmost root to 1e-9");
    }
  });
}
