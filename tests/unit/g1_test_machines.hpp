#pragma once
// G1 machines (MODELS.md G1) that several tests share, as the parameter lines of a [model] table:
// any model with G1's parameters takes them (plunge_regenerative, plunge_with_penetration_damping
// with its extra keys appended). A test that needs a machine of its own (a lobe top, a chain
// switched off) keeps it beside the test and says why.
#include <iomanip>
#include <sstream>
#include <string>

namespace chatterlab::testing {

// The reference G1 grinder of studies/stability_chart.toml and
// studies/simulate_regeneration_dominance.toml (reference_g1_case() of
// models/plunge_regenerative/plunge_time_domain.hpp as a table): one 250 Hz mode; the rightmost
// root grows at 4.79 /s (plunge_regenerative).
inline constexpr const char* g1_reference_machine = R"(wheel_speed_rpm = 1450
work_speed_rpm = 55
contact_stiffness_n_per_m = 1.0e8
wheel_wear_stiffness_n_per_m = 1.0e9
work_removal_stiffness_n_per_m = 2.0e8
modes = [ { frequency_hz = 250.0, damping_ratio = 0.05, stiffness_n_per_m = 5.0e7 } ]
)";

// feed_risk's test machine: one 150 Hz mode and a soft work removal stiffness, so that the work
// chain chatters at 300 rpm (its reference work speed).
inline constexpr const char* g1_feed_risk_machine = R"(wheel_speed_rpm = 1450
work_speed_rpm = 300
contact_stiffness_n_per_m = 2.0e7
wheel_wear_stiffness_n_per_m = 2.0e9
work_removal_stiffness_n_per_m = 1.6e6
modes = [ { frequency_hz = 150.0, damping_ratio = 0.03, stiffness_n_per_m = 2.0e7 } ]
)";

// The machine of studies/suppression_wheel_speed.toml and suppression_work_speed.toml (MODELS.md
// S1-S3): kc 1e8, kg 3e9, kw 5e7 N/m and one mode (zeta 0.03, 5e7 N/m), as a plunge_regenerative
// [model] table (after a blank line) at the given speeds and mode frequency; `switches` are extra
// lines before the modes (a regeneration chain switched off: "work_regeneration = false\n").
inline std::string g1_suppression_machine(double wheel_speed_rpm, double work_speed_rpm, double mode_frequency_hz,
                                          const std::string& switches = "") {
  std::ostringstream s;
  s << std::setprecision(17) << "\n[model]\ntype = \"plunge_regenerative\"\nwheel_speed_rpm = " << wheel_speed_rpm
    << "\nwork_speed_rpm = " << work_speed_rpm
    << "\ncontact_stiffness_n_per_m = 1.0e8\nwheel_wear_stiffness_n_per_m = 3.0e9\n"
       "work_removal_stiffness_n_per_m = 5.0e7\n"
    << switches << "modes = [ { frequency_hz = " << mode_frequency_hz
    << ", damping_ratio = 0.03, stiffness_n_per_m = 5.0e7 } ]\n";
  return s.str();
}

// "[model]" with `type = "<model_type>"` and the machine's lines (then `extra` lines, if any).
inline std::string model_table_toml(const std::string& model_type, const std::string& machine,
                                    const std::string& extra = "") {
  return "[model]\ntype = \"" + model_type + "\"\n" + machine + extra;
}

}  // namespace chatterlab::testing
