// Conformance: every registered plugin of every kind, and every study kind, is held to the same
// contract, so a new plugin is checked the moment its registration line compiles in (and the
// out-of-tree example of tests/external_plugin/ the moment it loads):
//  - a snake_case name and a one-line description; `chatterlab describe` works;
//  - every parameter spec has a description, a unit where the value is a quantity ("1" when
//    dimensionless), min <= max, and a default that passes its own limits;
//  - the example parameters validate against the plugin's own specs and the plugin builds from
//    them;
//  - a model's characteristic function has a correct derivative, exact neutral roots, and the
//    root solver finds a finite root in a small band, at or left of the declared bound.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/catalog.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/roots.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/dynamics.hpp"
#include "chatterlab/suppression.hpp"
#include "study/source_map.hpp"

namespace chatterlab {
namespace {

bool is_snake_case(const std::string& name) {
  if (name.empty() || !(name.front() >= 'a' && name.front() <= 'z')) return false;
  for (char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

// Quantities carry a unit; strings, booleans and lists of tables (whose fields carry their own)
// do not.
bool needs_unit(ValueKind kind) {
  return kind == ValueKind::real || kind == ValueKind::integer || kind == ValueKind::real_list ||
         kind == ValueKind::real_matrix;
}

void check_specs(const std::vector<ParamSpec>& specs, const std::string& path) {
  for (const ParamSpec& spec : specs) {
    const std::string key = path + "." + spec.key;
    SCOPED_TRACE("parameter " + key);
    EXPECT_TRUE(is_snake_case(spec.key)) << "key is not snake_case";
    EXPECT_FALSE(spec.description.empty()) << "no description";
    EXPECT_EQ(spec.description.find('\n'), std::string::npos) << "description is not one line";
    if (needs_unit(spec.kind)) {
      EXPECT_FALSE(spec.unit.empty()) << "no unit (\"1\" if dimensionless)";
    }
    EXPECT_FALSE(std::isnan(spec.min) || std::isnan(spec.max));
    EXPECT_LE(spec.min, spec.max) << "min > max";
    if (!spec.default_value.is_null()) {
      // The default must pass the spec's own checks (type and limits).
      LineSourceMap sources("default of " + key);
      EXPECT_NO_THROW(validate_params(Json{{spec.key, spec.default_value}}, {spec}, path, sources))
          << "default " << spec.default_value.dump() << " violates its own spec";
    }
    if (spec.kind == ValueKind::table_list) {
      EXPECT_FALSE(spec.fields.empty()) << "a list of tables without fields";
      check_specs(spec.fields, key + "[]");
    }
    if (spec.kind == ValueKind::table) {
      EXPECT_FALSE(spec.fields.empty()) << "a table without fields";
      EXPECT_TRUE(spec.optional || spec.default_value.is_object())
          << "a table is optional or defaults to its fields' defaults ({})";
      check_specs(spec.fields, key);
    }
  }
}

// Relative distance between the analytic derivative and a central difference of E.
double derivative_error(const CharacteristicFunction& e, Complex s) {
  const double h = 1e-7 * std::max(1.0, std::abs(s));
  const Complex difference = (e.evaluate(s + h).value - e.evaluate(s - h).value) / (2.0 * h);
  const Complex analytic = e.evaluate(s).derivative;
  return std::abs(difference - analytic) / std::max(std::abs(analytic), 1e-300);
}

void check_characteristic(const Model& model) {
  auto e = model.characteristic();
  if (!e) return;  // a model without linear stability (nonlinear only)
  const double f = e->natural_frequency_scale_hz();
  ASSERT_TRUE(std::isfinite(f) && f > 0) << "natural_frequency_scale_hz = " << f;
  const double w = 2 * std::numbers::pi * f;
  const double bound = e->real_part_bound();
  ASSERT_TRUE(std::isfinite(bound)) << "real_part_bound = " << bound;

  for (Complex s :
       {Complex(-0.1 * w, 0.7 * w), Complex(0.01 * w, 1.3 * w), Complex(-0.02 * w, 0.2 * w)})
    EXPECT_LT(derivative_error(*e, s), 1e-5) << "E'(s) disagrees with a difference of E at " << s;

  for (Complex r : e->neutral_roots(2 * w)) {
    // "An exact zero": tiny next to E a little way off.
    const double nearby = std::abs(e->evaluate(r + Complex(0, 1e-3 * w)).value);
    EXPECT_LE(std::abs(e->evaluate(r).value), 1e-8 * nearby) << "neutral root " << r;
  }

  std::vector<Complex> guesses;
  e->initial_guesses(w, guesses);
  EXPECT_FALSE(guesses.empty()) << "no initial guesses";

  RootSearchOptions options;
  options.max_frequency_hz = f;  // a small band: one structural frequency
  RightmostRoot found = find_rightmost_root(*e, options);
  EXPECT_TRUE(std::isfinite(found.root.real()) && std::isfinite(found.root.imag())) << found.root;
  EXPECT_GE(found.root.imag(), 0.0);
  EXPECT_LE(found.root.real(), bound) << "a root right of the declared real_part_bound";
  // A root, not just a number: the Newton step there is negligible.
  const CharacteristicValue at_root = e->evaluate(found.root);
  EXPECT_LE(std::abs(at_root.value / at_root.derivative),
            1e-8 * std::max(1.0, std::abs(found.root)))
      << "E(" << found.root << ") = " << at_root.value;
}

// A model with a time-domain form (dynamics engine) runs a short simulation at its example
// parameters: consistent sizes, finite outputs, a positive frequency scale.
void check_time_domain(const Model& model) {
  auto td = model.time_domain();
  if (!td) return;
  ASSERT_GT(td->state_size(), 0u);
  ASSERT_TRUE(std::isfinite(td->highest_frequency_hz()) && td->highest_frequency_hz() > 0);
  for (Rotor r : {Rotor::wheel, Rotor::work}) {
    if (!td->angle_state(r)) {
      EXPECT_GT(td->nominal_speed_rpm(r), 0.0) << to_string(r);
    }
  }
  SimulationSettings settings;
  settings.duration_s = 0.05;
  settings.sample_rate_hz = 4000.0;
  settings.infeed_rate_m_per_s = 1e-5;
  SimulationResult result;
  ASSERT_NO_THROW(result = simulate(*td, settings));
  EXPECT_EQ(result.t_s.size(), 201u);
  for (double x : result.displacement_m) ASSERT_TRUE(std::isfinite(x));
  for (double f : result.force_n) ASSERT_TRUE(std::isfinite(f));
}

template <class Product, class Check>
void check_registry(const Registry<Product>& registry, Check&& check_product) {
  for (const auto* entry : registry.sorted()) {
    const PluginInfo& info = entry->info;
    SCOPED_TRACE(registry.kind() + " '" + info.name + "' from " + entry->origin);
    EXPECT_TRUE(is_snake_case(info.name)) << "name is not snake_case";
    EXPECT_FALSE(info.description.empty()) << "no description";
    EXPECT_EQ(info.description.find('\n'), std::string::npos) << "description is not one line";

    std::string text;
    EXPECT_NO_THROW(text = describe_plugin(info.name));
    EXPECT_NE(text.find(info.description), std::string::npos);
    for (const ParamSpec& spec : info.params) EXPECT_NE(text.find(spec.key), std::string::npos);

    check_specs(info.params, registry.kind());

    LineSourceMap sources("example_params of " + info.name);
    Json validated;
    ASSERT_NO_THROW(validated =
                        validate_params(info.example_params, info.params, registry.kind(), sources))
        << "example_params " << info.example_params.dump() << " fail the plugin's own specs";
    std::unique_ptr<Product> product;
    ASSERT_NO_THROW(product = entry->create(ParamValues(validated)));
    ASSERT_NE(product, nullptr) << "the factory returned null";
    check_product(*product);
  }
}

class Conformance : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef CHATTERLAB_EXAMPLE_PLUGIN
    // Out-of-tree plugins obey the same contract: include the example library.
    load_plugin_library(CHATTERLAB_EXAMPLE_PLUGIN);
    ASSERT_NE(model_registry().find("example_delay_model"), nullptr);
#endif
  }
};

TEST_F(Conformance, EveryModel) {
  ASSERT_FALSE(model_registry().sorted().empty());
  check_registry(model_registry(), [](const Model& model) {
    check_characteristic(model);
    check_time_domain(model);
    if (auto period = model.wheel_period_s()) {
      EXPECT_GT(*period, 0.0) << "wheel period";
    }
  });
}

TEST_F(Conformance, EveryKinematicsSuppressionAndAnalysisPlugin) {
  // Their interfaces arrive with the capabilities that need them; the shared contract holds now.
  check_registry(kinematics_registry(), [](const Kinematics&) {});
  check_registry(suppression_registry(), [](const Suppression&) {});
  check_registry(analysis_registry(), [](const Analysis&) {});
}

TEST_F(Conformance, EveryStudyKind) {
  ASSERT_NE(study_kind_registry().find("stability_map"), nullptr);
  check_registry(study_kind_registry(), [](const StudyKind& kind) {
    EXPECT_FALSE(kind.tables().empty()) << "a study kind reads no table";
  });
}

// True when `list` has the line "<kind>  <name>  <description>" (columns padded with spaces).
bool listed(const std::string& list, const std::string& kind, const PluginInfo& info) {
  std::istringstream lines(list);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(kind + "  ", 0) != 0) continue;
    std::istringstream rest(line.substr(kind.size()));
    std::string name;
    rest >> name;
    if (name == info.name && line.find(info.name + "  ") != std::string::npos &&
        line.find("  " + info.description) != std::string::npos)
      return true;
  }
  return false;
}

TEST_F(Conformance, ListShowsEveryRegisteredPluginOnItsOwnLine) {
  const std::string list = format_plugin_list();
  auto expect_listed = [&](const auto& registry) {
    for (const auto* entry : registry.sorted())
      EXPECT_TRUE(listed(list, registry.kind(), entry->info))
          << registry.kind() << " " << entry->info.name << " is not listed in\n"
          << list;
  };
  expect_listed(study_kind_registry());
  expect_listed(model_registry());
  expect_listed(kinematics_registry());
  expect_listed(suppression_registry());
  expect_listed(analysis_registry());
}

}  // namespace
}  // namespace chatterlab
