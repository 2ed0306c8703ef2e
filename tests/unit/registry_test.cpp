// Registry<Product> (registry.hpp): duplicate names, unknown names, and the one-line registration
// macros. The two plugins registered at the bottom of this file stay in the global registries of
// the test executable, so the conformance test checks them like any other plugin.
#include "chatterlab/registry.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <memory>
#include <stdexcept>
#include <string>

#include "chatterlab/analysis.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"

namespace chatterlab::registry_test {

PluginInfo info_named(const std::string& name) {
  PluginInfo info;
  info.name = name;
  info.description = "registry test entry " + name;
  return info;
}

Registry<Model>::Factory null_factory() {
  return [](const ParamValues&) -> std::unique_ptr<Model> { return nullptr; };
}

// A minimal model registered with the macro: one parameter, a gain, read at construction.
class MacroModel final : public Model {
 public:
  explicit MacroModel(const ParamValues& values) : gain_(values.real("gain")) {}
  static PluginInfo info() {
    PluginInfo info;
    info.name = "registry_test_model";
    info.description = "test-only model registered by CHATTERLAB_REGISTER_MODEL (registry_test)";
    ParamSpec gain;
    gain.key = "gain";
    gain.unit = "1";
    gain.description = "a gain the test reads back";
    gain.default_value = 2.0;
    gain.min = 0.0;
    gain.max = 10.0;
    info.params = {gain};
    info.example_params = {{"gain", 3.0}};
    return info;
  }
  double gain() const { return gain_; }

 private:
  double gain_;
};

// Registering an analysis shows the macro of another kind works and that the conformance test
// covers every kind, not just models.
class MacroAnalysis final : public Analysis {
 public:
  explicit MacroAnalysis(const ParamValues&) {}
  Json analyse(const SampledSeries& series, const Json&) const override {
    // Held to the conformance suite like any analysis: a NaN sample is bad input.
    for (double v : series.values)
      if (!std::isfinite(v)) throw InputError("registry_test_analysis: a sample is not finite");
    return {{"samples", series.values.size()}};
  }
  static PluginInfo info() {
    PluginInfo info;
    info.name = "registry_test_analysis";
    info.description = "test-only analysis registered by CHATTERLAB_REGISTER_ANALYSIS";
    info.thread_safety = ThreadSafety::serial;
    return info;
  }
};

TEST(Registry, DuplicateNameIsAHardError) {
  Registry<Model> registry("model");
  registry.add(info_named("alpha"), null_factory());
  try {
    registry.add(info_named("alpha"), null_factory(), "/opt/plugins/libalpha.so");
    FAIL() << "a duplicate name was accepted";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(),
                 "chatterlab: duplicate model plugin name 'alpha' (registered by built-in and by "
                 "/opt/plugins/libalpha.so)");
  }
  // The first registration is untouched.
  ASSERT_NE(registry.find("alpha"), nullptr);
  EXPECT_EQ(registry.find("alpha")->origin, "built-in");
  EXPECT_EQ(registry.sorted().size(), 1u);
}

TEST(Registry, NamelessPluginIsRejected) {
  Registry<Analysis> registry("analysis");
  try {
    registry.add(info_named(""),
                 [](const ParamValues&) -> std::unique_ptr<Analysis> { return nullptr; });
    FAIL() << "a plugin without a name was accepted";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(), "chatterlab: a plugin in the analysis registry has no name");
  }
}

TEST(Registry, UnknownNameListsTheSortedValidNames) {
  Registry<Model> registry("model");
  for (const char* name : {"plunge", "alpha", "linear", "Zeta"})
    registry.add(info_named(name), null_factory());
  try {
    registry.at("plunj");
    FAIL() << "an unknown name was found";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown model 'plunj'; valid names: Zeta, alpha, linear, plunge");
  }
  EXPECT_EQ(registry.find("plunj"), nullptr);
  std::vector<std::string> names;
  for (const auto* entry : registry.sorted()) names.push_back(entry->info.name);
  EXPECT_EQ(names, (std::vector<std::string>{"Zeta", "alpha", "linear", "plunge"}));
}

TEST(Registry, UnknownNameInAnEmptyRegistrySaysSo) {
  Registry<Model> registry("suppression");
  try {
    registry.at("variable_speed");
    FAIL() << "an unknown name was found";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "unknown suppression 'variable_speed'; valid names: (none registered)");
  }
}

TEST(Registry, RegistrationMacroAddsTheClassToTheGlobalRegistry) {
  const auto* entry = model_registry().find("registry_test_model");
  ASSERT_NE(entry, nullptr);
  EXPECT_EQ(entry->origin, "built-in");
  EXPECT_EQ(entry->info.description,
            "test-only model registered by CHATTERLAB_REGISTER_MODEL (registry_test)");
  Json params = {{"gain", 7.5}};
  std::unique_ptr<Model> model = entry->create(ParamValues(params));
  auto* typed = dynamic_cast<MacroModel*>(model.get());
  ASSERT_NE(typed, nullptr);
  EXPECT_EQ(typed->gain(), 7.5);

  const auto* analysis = analysis_registry().find("registry_test_analysis");
  ASSERT_NE(analysis, nullptr);
  EXPECT_EQ(analysis->info.thread_safety, ThreadSafety::serial);
  EXPECT_NE(dynamic_cast<MacroAnalysis*>(analysis->create(ParamValues{}).get()), nullptr);
  // Registries are per kind: the analysis is not a model.
  EXPECT_EQ(model_registry().find("registry_test_analysis"), nullptr);
}

TEST(Registry, AddPluginRecordsTheOrigin) {
  Registry<Model> registry("model");
  add_plugin<MacroModel>(registry, "/usr/lib/libmacro.so");
  const auto& entry = registry.at("registry_test_model");
  EXPECT_EQ(entry.origin, "/usr/lib/libmacro.so");
  EXPECT_EQ(entry.info.params.at(0).key, "gain");
}

}  // namespace chatterlab::registry_test

CHATTERLAB_REGISTER_MODEL(chatterlab::registry_test::MacroModel);
CHATTERLAB_REGISTER_ANALYSIS(chatterlab::registry_test::MacroAnalysis);
