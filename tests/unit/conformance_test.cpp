// Conformance: every registered plugin of every kind, and every study kind, is held to the same
// contract, so a new plugin is checked the moment its registration line compiles in (and the
// out-of-tree example of tests/external_plugin/ the moment it loads). The checks themselves are
// the library's (chatterlab/conformance.hpp), the ones `chatterlab check-plugin` runs on a
// user's library: naming, parameter specs, example parameters, NaN handling, the model contract,
// the thread-safety declaration, and (ConformanceAccuracy) a model's characteristic function
// against its time-domain form.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "chatterlab/catalog.hpp"
#include "chatterlab/conformance.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {
namespace {

// Every check of the selected registry passes; returns the report for further assertions.
ConformanceReport expect_conforming(const std::string& registry_kind, bool time_domain = false) {
  ConformanceOptions options;
  options.registry_kind = registry_kind;
  options.time_domain = time_domain;
  options.threads = !time_domain;  // the accuracy test checks the time domain alone
  const ConformanceReport report = check_conformance(options);
  for (const ConformanceResult& r : report.results)
    EXPECT_TRUE(r.passed) << r.plugin << ": " << r.check << ": " << r.message;
  return report;
}

class Conformance : public ::testing::Test {
 protected:
  void SetUp() override {
    // Out-of-tree plugins obey the same contract: include the example library.
    load_plugin_library(CHATTERLAB_EXAMPLE_PLUGIN);
    ASSERT_NE(model_registry().find("example_delay_model"), nullptr);
  }
};
using ConformanceAccuracy = Conformance;

TEST_F(Conformance, EveryModel) {
  EXPECT_GT(expect_conforming("model").plugins, 5u);
}

TEST_F(Conformance, EveryKinematicsSuppressionAndAnalysisPlugin) {
  EXPECT_GT(expect_conforming("kinematics").plugins, 0u);
  EXPECT_GT(expect_conforming("suppression").plugins, 0u);
  EXPECT_GT(expect_conforming("analysis").plugins, 0u);
}

TEST_F(Conformance, EveryStudyKind) {
  ASSERT_NE(study_kind_registry().find("stability_map"), nullptr);
  EXPECT_GT(expect_conforming("study kind").plugins, 0u);
}

// Models with both forms (G1's plunge_regenerative in tree): the growth rate of a bilateral
// simulation against the rightmost root. Seconds of simulation, hence an accuracy test.
TEST_F(ConformanceAccuracy, CharacteristicFunctionAgreesWithTheTimeDomainForm) {
  const ConformanceReport report = expect_conforming("model", true);
  int compared = 0;
  for (const ConformanceResult& r : report.results)
    if (r.check == "time domain" && !r.skipped && r.passed) ++compared;
  EXPECT_GE(compared, 1) << report.text();
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
