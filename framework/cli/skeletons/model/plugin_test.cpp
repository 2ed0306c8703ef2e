// Tests of {{name}}: the library is loaded exactly as `chatterlab` loads it (by path, argument 1),
// then held to the conformance suite and to known answers computed independently of the plugin.
// `ctest` runs it (CMakeLists.txt); exit code 0 = every check passed.
#include <chatterlab/kit/model.hpp>
#include <chatterlab/plugin_test.hpp>

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

namespace {

constexpr double two_pi = 2.0 * std::numbers::pi;

// The rightmost characteristic root of the model with these parameters (certified search of the
// study kit, the same one `stability_map` runs).
std::complex<double> rightmost_root(double removal_ratio, double work_speed_rpm) {
  const double contact = 4.0e7, modal = 2.0e7;  // K = kc / k = 2
  const chatterlab::Json table = {{"type", "{{name}}"},
                                  {"natural_frequency_hz", 150.0},
                                  {"damping_ratio", 0.05},
                                  {"modal_stiffness_n_per_m", modal},
                                  {"contact_stiffness_n_per_m", contact},
                                  {"work_removal_stiffness_n_per_m", contact / removal_ratio},
                                  {"work_speed_rpm", work_speed_rpm},
                                  {"wheel_speed_rpm", 1500.0}};
  const auto model = chatterlab::kit::build_model(table);
  return chatterlab::kit::rightmost_root(*model, {}).root;
}

// Known answer (derived by hand from E(s) = (1 - z)(P + K) + Q P, not by the plugin's code): on
// s = i wc the lattice roots have |z| = 1 exactly where Q (2 + Q) |P|^2 + 2 Q K Re P = 0, i.e.
// Q = 2 K u / |P|^2 - 2 with u = (wc/w)^2 - 1 > 0 and |P|^2 = u^2 + 4 zeta^2 (1 + u). That limit
// is largest at u = 2 zeta (here 0.1): there every other frequency is stable, so at the speed
// that puts a root of the delay lattice on i wc the rightmost root crosses the axis when Q
// passes the limit: chatter below it, stable above it.
void stability_limit_is_reproduced(chatterlab::PluginChecks& check) {
  const double zeta = 0.05, k_ratio = 2.0, w = two_pi * 150.0;
  const double u = 2.0 * zeta;
  const double q_limit = 2.0 * k_ratio * u / (u * u + 4.0 * zeta * zeta * (1.0 + u)) - 2.0;
  const double wc = w * std::sqrt(1.0 + u);
  const std::complex<double> p(-u, 2.0 * zeta * std::sqrt(1.0 + u));  // P(i wc)
  const std::complex<double> z = 1.0 + q_limit * p / (p + k_ratio);     // e^{-i wc T}
  check(std::abs(std::abs(z) - 1.0) < 1e-12, "|z| = 1 at the limit (the algebra above)");
  const double delay_s = (two_pi * 60.0 - std::arg(z)) / wc;  // 60 waves per revolution
  const double rpm = 60.0 / delay_s;

  const std::complex<double> at_limit = rightmost_root(q_limit, rpm);
  check(std::abs(at_limit.real()) < 1e-6 * w, "at the limit the rightmost root lies on the axis");
  check(std::abs(at_limit.imag() - wc) < 1e-6 * w, "... at the predicted chatter frequency");
  check(rightmost_root(0.98 * q_limit, rpm).real() > 0.0, "2 % below the limit: chatter");
  check(rightmost_root(1.02 * q_limit, rpm).real() < 0.0, "2 % above the limit: stable");
}

}  // namespace

int main(int argc, char** argv) {
  // Loads the library (argument 1) as chatterlab does and runs the conformance suite (including
  // the agreement of the time-domain form with the characteristic function) first.
  return chatterlab::plugin_test_main(argc, argv, stability_limit_is_reproduced);
}
