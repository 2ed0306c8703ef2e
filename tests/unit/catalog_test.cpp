// `chatterlab list` / `chatterlab describe` text (catalog.hpp): the parameter table of a plugin
// with one parameter of each shape, the unknown-name message, and, for every registered plugin,
// that the printed TOML example is valid TOML holding exactly the plugin's example_params.
#include "chatterlab/catalog.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/analysis.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/kinematics.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/study_kind.hpp"
#include "chatterlab/suppression.hpp"
#include "study/toml_reader.hpp"
#include "study_test_support.hpp"

namespace chatterlab::catalog_test {

class CatalogModel final : public Model {
 public:
  explicit CatalogModel(const ParamValues&) {}
  static PluginInfo info() {
    PluginInfo info;
    info.name = "catalog_test_model";
    info.description = "test-only model with one parameter of each shape (catalog_test)";
    auto speed = param_spec("speed_rpm", ValueKind::real, "rpm", "spindle speed");
    speed.min = 0, speed.min_exclusive = true;
    auto damping = param_spec("damping_ratio", ValueKind::real, "1", "damping ratio");
    damping.min = 0, damping.max = 1, damping.max_exclusive = true, damping.default_value = 0.05;
    auto stiffness = param_spec("stiffness_n_per_m", ValueKind::real, "N/m", "contact stiffness");
    stiffness.min = 1e6, stiffness.default_value = 2e8;
    auto shape = param_spec("mode_shape", ValueKind::string, "1", "shape of the mode");
    shape.choices = {"bending", "torsion"}, shape.default_value = "bending";
    auto trims = param_spec("trims", ValueKind::real_list, "1", "trim factors");
    trims.optional = true, trims.min_items = 2;
    auto gap = param_spec("gap_m", ValueKind::real, "m", "gap of the stage");
    gap.min = 0, gap.min_exclusive = true;
    auto count = param_spec("count", ValueKind::integer, "1", "repetitions");
    count.min = 1, count.max = 10, count.default_value = 2;
    auto stages = param_spec("stages", ValueKind::table_list, "", "feed stages");
    stages.fields = {gap, count}, stages.min_items = 1;
    auto rate = param_spec("rate_m_per_s", ValueKind::real, "m/s", "infeed rate");
    rate.default_value = 1e-5;
    auto infeed = param_spec("infeed", ValueKind::table, "", "[model.infeed]: the infeed");
    infeed.fields = {rate}, infeed.default_value = Json::object();
    info.params = {speed, damping, stiffness, shape, trims, stages, infeed};
    info.example_params = {
        {"speed_rpm", 1500},
        {"trims", {1, 0.5}},
        {"stages", Json::array({{{"gap_m", 1.5e-5}}, {{"gap_m", 2e-5}, {"count", 3}}})},
        {"infeed", {{"rate_m_per_s", 2e-5}}}};
    return info;
  }
};

// A study kind with two settings tables of its own: describe cannot tell which one holds its
// parameters, so the example shows them commented out.
class TwoTableKind final : public StudyKind {
 public:
  static PluginInfo info() {
    return testing::one_parameter_kind_info(
        "catalog_test_kind", "test-only study kind reading two settings tables (catalog_test)", "level", "a level", 2.0);
  }
  std::vector<std::string> tables() const override { return {"model", "first", "second"}; }
  void validate(Json&, const SourceMap&) const override {}
  std::vector<std::string> output_columns(const Json&) const override { return {"level"}; }
  std::vector<Json> run_point(const Json&, const PointContext&) const override { return {1.0}; }
  void write_artifacts(const Study&, const ResultTable&,
                       const std::filesystem::path&) const override {}
};

TEST(Catalog, StudyKindSettingsGoUnderTheirTable) {
  const std::string text = describe_plugin("stability_map");
  EXPECT_NE(text.find("Reads tables:   [model], [stability], [suppression]\n"), std::string::npos) << text;
  EXPECT_NE(text.find("\nParameters ([stability]):\n"), std::string::npos) << text;
  EXPECT_NE(text.find("Example:\n  [study]\n  kind = \"stability_map\"\n\n  [stability]\n"),
            std::string::npos)
      << text;

  const std::string two = describe_plugin("catalog_test_kind");
  EXPECT_NE(two.find("\nParameters:\n"), std::string::npos) << two;
  EXPECT_NE(two.find("Example:\n  [study]\n  kind = \"catalog_test_kind\"\n\n  # settings of this "
                     "kind (in one of its tables, see its documentation):\n  # level = 2.0\n"),
            std::string::npos)
      << two;
}

TEST(Catalog, DescribePrintsEveryParameterWithTypeUnitLimitsAndDefault) {
  EXPECT_EQ(describe_plugin("catalog_test_model"),
            R"(catalog_test_model (model, built-in)
  test-only model with one parameter of each shape (catalog_test)

  Used as:        [model] type = "catalog_test_model"
  MODELS.md:      -
  Thread safety:  copy per thread (each thread of a run builds its own instance)

Parameters ([model]):
  key                    type        unit  limits                   default    description
  speed_rpm              real        rpm   > 0                      required   spindle speed
  damping_ratio          real        1     [0, 1)                   0.05       damping ratio
  stiffness_n_per_m      real        N/m   >= 1e6                   2e8        contact stiffness
  mode_shape             string      1     one of bending, torsion  "bending"  shape of the mode
  trims                  real list   1     at least 2 entries       optional   trim factors
  stages                 table list  -     at least 1 entry         required   feed stages
    stages[].gap_m       real        m     > 0                      required   gap of the stage
    stages[].count       integer     1     [1, 10]                  2          repetitions
  infeed                 table       -     -                        -          [model.infeed]: the infeed
    infeed.rate_m_per_s  real        m/s   -                        1e-5       infeed rate

Example:
  [model]
  type = "catalog_test_model"
  speed_rpm = 1500.0
  trims = [1.0, 0.5]

  [model.infeed]
  rate_m_per_s = 2e-5

  [[model.stages]]
  gap_m = 1.5e-5

  [[model.stages]]
  gap_m = 2e-5
  count = 3
)");
}

TEST(Catalog, UnknownNameListsEveryValidNameSorted) {
  std::vector<std::string> names;
  auto add = [&](const auto& registry) {
    for (const auto* entry : registry.sorted()) names.push_back(entry->info.name);
  };
  add(study_kind_registry());
  add(model_registry());
  add(kinematics_registry());
  add(suppression_registry());
  add(analysis_registry());
  std::sort(names.begin(), names.end());
  std::string expected = "unknown plugin or study kind 'plunge_regenerativ'; valid names: ";
  for (std::size_t i = 0; i < names.size(); ++i) expected += (i ? ", " : "") + names[i];
  EXPECT_EQ(testing::input_error_of([] { describe_plugin("plunge_regenerativ"); }), expected);
  EXPECT_NE(expected.find("catalog_test_model, "), std::string::npos);
}

// The lines after "Example:" in describe's text, without their two-space indent.
std::string example_block(const std::string& text) {
  const std::string marker = "\nExample:\n";
  std::size_t at = text.find(marker);
  if (at == std::string::npos) return {};
  std::string block;
  for (std::size_t start = at + marker.size(); start < text.size();) {
    std::size_t end = text.find('\n', start);
    std::string line = text.substr(start, end - start);
    block += (line.rfind("  ", 0) == 0 ? line.substr(2) : line) + '\n';
    start = end == std::string::npos ? text.size() : end + 1;
  }
  return block;
}

// Key order is presentation (TOML puts plain keys before arrays of tables): compare as unordered.
nlohmann::json unordered(const Json& v) { return nlohmann::json::parse(v.dump()); }

// Reads the printed example back with the study reader and compares it with the declared table.
template <class Product>
void expect_examples_read_back(const Registry<Product>& registry,
                               const std::string& table_of_kind) {
  testing::TempDir dir;
  for (const auto* entry : registry.sorted()) {
    SCOPED_TRACE(registry.kind() + " " + entry->info.name);
    const std::string example = example_block(describe_plugin(entry->info.name));
    Json document;
    ASSERT_NO_THROW(document = read_toml_study(dir.write("example.toml", example)).document)
        << example;
    Json table = entry->info.example_params;
    if (table_of_kind.empty()) {  // a study kind: [study] kind = ..., then its settings table
      EXPECT_EQ(document["study"]["kind"], entry->info.name) << example;
      document.erase("study");
      if (table.empty()) {
        EXPECT_TRUE(document.empty()) << example;
        continue;
      }
      if (example.find("# settings of this kind") != std::string::npos) {
        EXPECT_TRUE(document.empty()) << example;  // shown commented out: no table to name
        continue;
      }
      ASSERT_EQ(document.size(), 1u) << example;
      EXPECT_EQ(unordered(document.begin().value()), unordered(table)) << example;
    } else if (table_of_kind == "analysis") {  // listed by name, parameters in [analysis.<name>]
      EXPECT_EQ(document["analysis"]["methods"], Json::array({entry->info.name})) << example;
      if (table.empty())
        EXPECT_FALSE(document["analysis"].contains(entry->info.name)) << example;
      else
        EXPECT_EQ(unordered(document["analysis"][entry->info.name]), unordered(table)) << example;
    } else {
      table["type"] = entry->info.name;
      EXPECT_EQ(unordered(document[table_of_kind]), unordered(table)) << example;
    }
  }
}

TEST(Catalog, PrintedExamplesAreValidTomlWithTheDeclaredValues) {
  expect_examples_read_back(study_kind_registry(), "");
  expect_examples_read_back(model_registry(), "model");
  expect_examples_read_back(kinematics_registry(), "kinematics");
  expect_examples_read_back(suppression_registry(), "suppression");
  expect_examples_read_back(analysis_registry(), "analysis");
}

}  // namespace chatterlab::catalog_test

CHATTERLAB_REGISTER_MODEL(chatterlab::catalog_test::CatalogModel);
CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::catalog_test::TwoTableKind);
