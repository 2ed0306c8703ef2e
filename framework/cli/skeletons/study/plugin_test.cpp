// Tests of the {{name}} study kind: the library is loaded exactly as `chatterlab` loads it (by
// path, argument 1), a study file is read as `chatterlab run` reads it, and one point is checked
// against closed forms of the single-mode compliance. `ctest` runs it; exit code 0 = all passed.
#include <chatterlab/plugin_api.hpp>
#include <chatterlab/plugin_test.hpp>
#include <chatterlab/study.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace {

bool near(double value, double expected, double relative) {
  return std::abs(value - expected) <= relative * std::abs(expected);
}

// One point: G1's built-in plunge_regenerative with a single mode (k = 5e7 N/m, zeta = 0.05).
chatterlab::Json run_one_point(const std::string& library) {
  const auto dir = std::filesystem::temp_directory_path() / "{{name}}_test";
  std::filesystem::create_directories(dir);
  const auto file = dir / "study.toml";
  std::ofstream(file) << "plugins = [\"" << library << "\"]\n"
                      << "[study]\nkind = \"{{name}}\"\n"
                      << "[model]\ntype = \"plunge_regenerative\"\n"
                      << "wheel_speed_rpm = 1500.0\nwork_speed_rpm = 60.0\n"
                      << "contact_stiffness_n_per_m = 1.0e8\nwheel_wear_stiffness_n_per_m = 5.0e9\n"
                      << "work_removal_stiffness_n_per_m = 5.0e7\n"
                      << "[[model.modes]]\nfrequency_hz = 100.0\ndamping_ratio = 0.05\nstiffness_n_per_m = 5.0e7\n"
                      << "[sweep]\nmax_frequency_hz = 200.0\nfrequencies = 200001\n";
  const chatterlab::Study study = chatterlab::load_study(file);
  const auto kind = chatterlab::study_kind_registry().at("{{name}}").create({});
  const auto columns = kind->output_columns(study.document);
  const auto values = kind->run_point(study.point_document(0), {});
  chatterlab::Json row = chatterlab::Json::object();
  for (std::size_t i = 0; i < columns.size(); ++i) row[columns[i]] = values.at(i);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  // Loads the library (argument 1) as chatterlab does and runs the conformance suite first.
  return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {
    // Known answers of one mode (zeta = 0.05, k = 5e7 N/m, 100 Hz), closed forms of
    // G = 1 / (k (1 - r^2 + 2 i zeta r)): max |G| = 1 / (2 zeta k sqrt(1 - zeta^2)) at
    // r = sqrt(1 - 2 zeta^2); min Re G = -1 / (4 zeta (1 + zeta) k) at r = sqrt(1 + 2 zeta).
    const double zeta = 0.05, k = 5.0e7, fn = 100.0;
    const chatterlab::Json row = run_one_point(check.library());
    std::cout << row.dump() << '\n';
    check(near(row["peak_compliance_m_per_n"].get<double>(), 1.0 / (2 * zeta * k * std::sqrt(1 - zeta * zeta)), 1e-6),
          "peak compliance");
    check(near(row["peak_frequency_hz"].get<double>(), fn * std::sqrt(1 - 2 * zeta * zeta), 1e-4),
          "frequency of the peak");
    check(near(row["min_real_compliance_m_per_n"].get<double>(), -1.0 / (4 * zeta * (1 + zeta) * k), 1e-6),
          "most negative real compliance");
    check(near(row["min_real_frequency_hz"].get<double>(), fn * std::sqrt(1 + 2 * zeta), 1e-4),
          "frequency of the most negative real compliance");
    check(row["stable"].is_boolean(), "a stability verdict");
  });
}
