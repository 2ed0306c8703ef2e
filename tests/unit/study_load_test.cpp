// load_study on valid studies: conversion, key order, defaults, source lines, plugins,
// component tables. Also registers the test-only plugins the other study tests use by name.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include <fmt/format.h>

#include "chatterlab/input_files.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "study_test_support.hpp"

namespace chatterlab::testing {
namespace {

// A structure of independent damped modes, E(s) = prod_m (s^2 + 2 zeta_m w_m s + w_m^2): roots
// known in closed form, so the conformance test can run it like a real model.
class ModalCharacteristic final : public CharacteristicFunction {
 public:
  explicit ModalCharacteristic(std::vector<ParamValues> modes) : modes_(std::move(modes)) {}

  CharacteristicValue evaluate(Complex s) const override {
    Complex value = 1.0, derivative = 0.0;
    for (const auto& mode : modes_) {
      double w = 2 * std::numbers::pi * mode.real("frequency_hz"), zeta = mode.real("damping_ratio");
      Complex q = s * s + 2 * zeta * w * s + w * w, dq = 2.0 * s + 2 * zeta * w;
      derivative = derivative * q + value * dq;
      value *= q;
    }
    return {value, derivative};
  }
  void initial_guesses(double max_angular_frequency_rad_s, std::vector<Complex>& guesses) const override {
    for (const auto& mode : modes_) {
      double w = 2 * std::numbers::pi * mode.real("frequency_hz"), zeta = mode.real("damping_ratio");
      if (w <= max_angular_frequency_rad_s) guesses.emplace_back(-zeta * w, w * std::sqrt(1 - zeta * zeta));
    }
  }
  double real_part_bound() const override { return 1.0; }  // every root has Re s <= 0
  double natural_frequency_scale_hz() const override {
    double highest = 0;
    for (const auto& mode : modes_) highest = std::max(highest, mode.real("frequency_hz"));
    return highest;
  }

 private:
  std::vector<ParamValues> modes_;
};

// test_fake_model: one parameter of every ValueKind, with the limits real models have.
class FakeModel final : public Model {
 public:
  explicit FakeModel(const ParamValues& params) : params_(params) {}

  static PluginInfo info() {
    PluginInfo info;
    info.name = "test_fake_model";
    info.description = "test-only: independent damped modes (study loading tests)";
    info.thread_safety = ThreadSafety::shareable;
    auto speed = param_spec("speed_rpm", ValueKind::real, "rpm", "spindle speed");
    speed.min = 0, speed.min_exclusive = true;
    auto stiffness = param_spec("stiffness_n_per_m", ValueKind::real, "N/m", "contact stiffness");
    stiffness.min = 0, stiffness.min_exclusive = true, stiffness.default_value = 1e7;
    auto mass = param_spec("mass_kg", ValueKind::real, "kg", "modal mass");
    mass.min = 0, mass.min_exclusive = true, mass.default_value = 2.0;
    auto harmonics = param_spec("harmonics", ValueKind::integer, "1", "harmonics kept");
    harmonics.min = 1, harmonics.max = 10, harmonics.default_value = 1;
    auto shape = param_spec("mode_shape", ValueKind::string, "1", "shape of the modes");
    shape.choices = {"torsion", "bending"}, shape.default_value = "bending";
    auto gains = param_spec("gains", ValueKind::real_matrix, "1", "coupling matrix");
    gains.default_value = Json::array({Json::array({1.0, 0.0}), Json::array({0.0, 1.0})});
    auto frequency = param_spec("frequency_hz", ValueKind::real, "Hz", "natural frequency");
    frequency.min = 0, frequency.min_exclusive = true;
    auto damping = param_spec("damping_ratio", ValueKind::real, "1", "modal damping ratio");
    damping.min = 0, damping.max = 1, damping.max_exclusive = true;
    auto modes = param_spec("modes", ValueKind::table_list, "", "structural modes");
    modes.fields = {frequency, damping}, modes.min_items = 1;
    auto trim = param_spec("trim", ValueKind::real_list, "1", "optional trim factors");
    trim.optional = true;
    info.params = {speed, stiffness, mass, harmonics, shape, gains, modes, trim};
    info.example_params = {{"speed_rpm", 1000.0},
                           {"modes", Json::array({{{"frequency_hz", 100.0}, {"damping_ratio", 0.05}}})}};
    return info;
  }

  std::unique_ptr<CharacteristicFunction> characteristic() const override {
    return std::make_unique<ModalCharacteristic>(params_.tables("modes"));
  }
  std::optional<double> wheel_period_s() const override { return 60.0 / params_.real("speed_rpm"); }

 private:
  ParamValues params_;
};

// test_fake_kind: [model] through the model registry plus its own [fake_settings] table.
class FakeKind final : public StudyKind {
 public:
  static PluginInfo info() {
    PluginInfo info;
    info.name = "test_fake_kind";
    info.description = "test-only study kind: speed x scale and the first mode frequency";
    auto scale = param_spec("scale", ValueKind::real, "1", "factor applied to the speed");
    scale.min = 0, scale.min_exclusive = true, scale.default_value = 1.0;
    info.params = {scale};
    info.example_params = {{"scale", 2.0}};
    return info;
  }

  std::vector<std::string> tables() const override { return {"model", "fake_settings"}; }

  void validate(Json& document, const SourceMap& sources) const override {
    document["model"] = validate_component(document, "model", model_registry(), sources);
    Json settings = document.contains("fake_settings") ? document["fake_settings"] : Json::object();
    document["fake_settings"] = validate_params(settings, info().params, "fake_settings", sources);
  }
  std::vector<std::string> output_columns(const Json&) const override {
    return {"scaled_speed_rpm", "first_frequency_hz"};
  }
  std::vector<Json> run_point(const Json& point, const PointContext&) const override {
    ParamValues model(point["model"]);
    return {model.real("speed_rpm") * point["fake_settings"]["scale"].get<double>(),
            model.tables("modes").front().real("frequency_hz")};
  }
  void write_artifacts(const Study&, const ResultTable&, const std::filesystem::path&) const override {}
};

}  // namespace
}  // namespace chatterlab::testing

CHATTERLAB_REGISTER_MODEL(chatterlab::testing::FakeModel);
CHATTERLAB_REGISTER_STUDY_KIND(chatterlab::testing::FakeKind);

namespace chatterlab::testing {
namespace {

TEST(StudyLoad, ValidStudyHasKindDefaultsAndOnePoint) {
  TempDir dir;
  Study study = load_text(dir, fake_study());
  EXPECT_EQ(study.kind, "test_fake_kind");
  EXPECT_EQ(study.file, dir.path() / "study.toml");
  const Json& model = study.document["model"];
  EXPECT_EQ(model["type"], "test_fake_model");
  EXPECT_EQ(model["stiffness_n_per_m"], 1e7);  // default filled in
  EXPECT_EQ(model["harmonics"], 1);
  EXPECT_TRUE(model["speed_rpm"].is_number_float()) << "validated reals are doubles";
  EXPECT_TRUE(model["trim"].is_null()) << "optional, absent";
  EXPECT_EQ(study.document["fake_settings"]["scale"], 1.0);
  EXPECT_EQ(study.document["study"]["name"], "study") << "default name: the file stem";
  EXPECT_EQ(study.document["study"]["description"], "");
  EXPECT_TRUE(study.grid.empty());
  EXPECT_EQ(study.point_count(), 1u);
  EXPECT_TRUE(study.point_indices(0).empty());
  EXPECT_EQ(study.point_document(0), study.document);
  EXPECT_TRUE(study.plugin_libraries.empty());
}

TEST(StudyLoad, KeysKeepTheirWrittenOrder) {
  TempDir dir;
  Study study = load_text(dir,
                          "[model]\n"
                          "type = \"test_fake_model\"\n"
                          "mass_kg = 3.0\n"
                          "speed_rpm = 10\n"
                          "modes = [{ damping_ratio = 0.1, frequency_hz = 5.0 }]\n"
                          "[study]\n"
                          "name = \"order\"\n"
                          "kind = \"test_fake_kind\"\n");
  std::vector<std::string> top, model;
  for (const auto& item : study.document.items()) top.push_back(item.key());
  for (const auto& item : study.document["model"].items()) model.push_back(item.key());
  EXPECT_EQ(top, (std::vector<std::string>{"model", "study", "fake_settings"}));
  // Validated tables list `type`, then the declared parameters in declaration order.
  EXPECT_EQ(model, (std::vector<std::string>{"type", "speed_rpm", "stiffness_n_per_m", "mass_kg",
                                             "harmonics", "mode_shape", "gains", "modes", "trim"}));
  EXPECT_EQ(study.document["study"]["name"], "order");
}

TEST(StudyLoad, SourceMapGivesTheLineOfEveryPathAndFallsBackToTheEnclosingTable) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[fake_settings]\n"  // line 10
                                          "scale = 2.5\n"));   // line 11
  const SourceMap& sources = *study.sources;
  std::string file = (dir.path() / "study.toml").string();
  EXPECT_EQ(sources.locate("study.kind").line, 2);
  EXPECT_EQ(sources.locate("model").line, 4);
  EXPECT_EQ(sources.locate("model.speed_rpm").line, 6);
  EXPECT_EQ(sources.locate("model.modes.0.damping_ratio").line, 7);
  EXPECT_EQ(sources.locate("model.modes.1").line, 8);
  EXPECT_EQ(sources.locate("model.modes.1.damping_ratio").line, 8);
  EXPECT_EQ(sources.locate("fake_settings.scale").line, 11);
  // Never written (a default): the enclosing table's header.
  EXPECT_EQ(sources.locate("model.stiffness_n_per_m").line, 4);
  EXPECT_EQ(sources.locate("model.stiffness_n_per_m").str(), file + ":4");
  // Outside every written table: the file alone.
  EXPECT_EQ(sources.locate("nowhere.at_all").line, 0);
  EXPECT_EQ(sources.locate("nowhere.at_all").str(), file);
}

TEST(StudyLoad, ArrayOfTablesAreLocatedAtTheirHeaders) {
  TempDir dir;
  Study study = load_text(dir,
                          "[study]\n"                          // 1
                          "kind = \"test_fake_kind\"\n"        // 2
                          "[model]\n"                          // 3
                          "type = \"test_fake_model\"\n"       // 4
                          "speed_rpm = 1500\n"                 // 5
                          "[[model.modes]]\n"                  // 6
                          "frequency_hz = 100.0\n"             // 7
                          "damping_ratio = 0.1\n"              // 8
                          "[[model.modes]]\n"                  // 9
                          "frequency_hz = 200.0\n"             // 10
                          "damping_ratio = 0.2\n");            // 11
  EXPECT_EQ(study.sources->locate("model.modes.0").line, 6);
  EXPECT_EQ(study.sources->locate("model.modes.1").line, 9);
  EXPECT_EQ(study.sources->locate("model.modes.1.damping_ratio").line, 11);
  EXPECT_EQ(study.document["model"]["modes"][1]["frequency_hz"], 200.0);
}

TEST(StudyLoad, StudyTableNameAndDescriptionAreKept) {
  TempDir dir;
  Study study = load_text(dir, "[study]\nkind = \"test_fake_kind\"\nname = \"trial 3\"\n"
                               "description = \"wheel wear\"\n" +
                                   fake_study().substr(fake_study().find("[model]")));
  EXPECT_EQ(study.document["study"]["name"], "trial 3");
  EXPECT_EQ(study.document["study"]["description"], "wheel wear");
}

TEST(StudyLoad, ComponentTableListsValidTypesWhenTypeIsMissingOrUnknown) {
  TempDir dir;
  std::string base = fake_study();
  std::string missing = base;
  missing.replace(missing.find("type = \"test_fake_model\"\n"), 25, "");
  std::string message = input_error_of([&] { load_text(dir, missing); });
  EXPECT_NE(message.find("study.toml:4: missing required key 'model.type'"), std::string::npos) << message;
  EXPECT_NE(message.find("test_fake_model"), std::string::npos) << message;

  std::string unknown = base;
  unknown.replace(unknown.find("test_fake_model"), 15, "test_fake_modl");
  message = input_error_of([&] { load_text(dir, unknown); });
  EXPECT_NE(message.find("study.toml:5: model.type = \"test_fake_modl\": unknown model"), std::string::npos)
      << message;
  EXPECT_NE(message.find("did you mean 'test_fake_model'?"), std::string::npos) << message;
  EXPECT_NE(message.find("valid names: "), std::string::npos) << message;

  message = input_error_of([&] { load_text(dir, "[study]\nkind = \"test_fake_kind\"\n"); });
  EXPECT_NE(message.find("missing table [model]"), std::string::npos) << message;
}

TEST(StudyLoad, PluginPathsResolveAgainstTheStudyDirectory) {
  TempDir dir;
  std::filesystem::create_directories(dir.path() / "sub");
  std::filesystem::path file = dir.write("sub/study.toml", "plugins = [\"../lib/libnot_there.so\"]\n" + fake_study());
  std::string message = input_error_of([&] { load_study(file); });
  // Resolved next to the study, not the working directory, and named with file, line and key.
  std::string resolved = (dir.path() / "lib" / "libnot_there.so").string();
  EXPECT_NE(message.find("sub/study.toml:1: plugins.0 = \"../lib/libnot_there.so\" (" + resolved + ")"),
            std::string::npos)
      << message;

  message = input_error_of([&] { load_text(dir, "plugins = \"libx.so\"\n" + fake_study()); });
  EXPECT_NE(message.find("study.toml:1: plugins = \"libx.so\": expected a list of shared library paths"),
            std::string::npos)
      << message;
}

TEST(StudyLoad, LoadingWritesNothing) {
  TempDir dir;
  dir.write("study.toml", fake_study("[grid]\nspeed_rpm = [1000, 2000]\n"));
  auto before = dir.listing();
  Study study = load_study(dir.path() / "study.toml");
  EXPECT_EQ(study.point_count(), 2u);
  EXPECT_EQ(dir.listing(), before);
}

TEST(StudyLoad, RecordsEveryInputFileWithItsHash) {
  TempDir dir;
  const std::string text = "plugins = [\"" CHATTERLAB_EXAMPLE_PLUGIN "\"]\n" + fake_study();
  Study study = load_text(dir, text);
  ASSERT_TRUE(study.inputs);
  const auto files = study.inputs->files();
  ASSERT_EQ(files.size(), 2u);
  const auto& library = files[0].role == InputRole::plugin ? files[0] : files[1];
  const auto& study_file = files[0].role == InputRole::plugin ? files[1] : files[0];
  EXPECT_EQ(study_file.role, InputRole::study);
  EXPECT_EQ(study_file.path, input_key(dir.path() / "study.toml"));
  EXPECT_EQ(study_file.sha256, sha256_hex(text));
  EXPECT_EQ(library.path, input_key(CHATTERLAB_EXAMPLE_PLUGIN));
  EXPECT_EQ(library.sha256.size(), 64u);
  EXPECT_EQ(study.output_columns, (std::vector<std::string>{"scaled_speed_rpm", "first_frequency_hz"}));
}

TEST(StudyLoad, RunTableIsCheckedAndNeverReachesTheKind) {
  TempDir dir;
  Study study = load_text(dir, fake_study("[run]\npoint_timeout_s = 2.5\n[grid]\nspeed_rpm = [1, 2]\n"));
  EXPECT_EQ(study.document["run"]["point_timeout_s"], 2.5);
  EXPECT_EQ(study.document["run"]["isolate"], false);
  EXPECT_FALSE(study.point_document(1).contains("run"));
  EXPECT_NE(load_error(dir, fake_study("[run]\npoint_timeout_s = 0\n"))
                .find("study.toml:11: run.point_timeout_s = 0"),
            std::string::npos);
  EXPECT_NE(load_error(dir, fake_study("[run]\nthreads = 2\n")).find("unknown key"), std::string::npos);
  // A study without [run] keeps its resolved document as before (meta.json shows no [run]).
  EXPECT_FALSE(load_text(dir, fake_study()).document.contains("run"));
}

TEST(StudyLoad, WhateverAPluginConstructorThrowsIsBadInputAtItsTablesLine) {
  TempDir dir;
  const std::string plugin = "plugins = [\"" CHATTERLAB_MISBEHAVING_PLUGIN "\"]\n";
  const std::string message = load_error(
      dir, plugin + "[study]\nkind = \"stability_map\"\n[model]\ntype = \"misbehaving_model\"\n"
                    "behaviour = \"throw_in_constructor\"\n");
  for (const std::string& part : {std::string("study.toml:5: model plugin 'misbehaving_model' (library "),
                                 std::string(CHATTERLAB_MISBEHAVING_PLUGIN),
                                 std::string("its constructor threw an exception of type 'int' (not "
                                             "derived from std::exception)")})
    EXPECT_NE(message.find(part), std::string::npos) << message;
}

TEST(StudyLoad, AStudyKindConstructorThrowingAnythingIsBadInputAtTheKindsLine) {
  TempDir dir;
  const std::string plugin = "plugins = [\"" CHATTERLAB_MISBEHAVING_PLUGIN "\"]\n";
  const std::string message = load_error(dir, plugin + "[study]\nkind = \"throwing_study_kind\"\n");
  for (const std::string& part :
       {std::string("study.toml:3: study kind plugin 'throwing_study_kind' (library "),
        std::string(CHATTERLAB_MISBEHAVING_PLUGIN),
        std::string("its constructor threw an exception of type 'int' (not derived from "
                    "std::exception)")})
    EXPECT_NE(message.find(part), std::string::npos) << message;
}

TEST(GridCost, HeldRowsAreBoundedAndOnlyTheBookkeepingGrowsWithTheGrid) {
  // Results stream: rows are held up to the plots' table and one block in flight, then only the
  // per-point bookkeeping grows.
  const GridCost tiny = grid_cost(9, 2, 3), small = grid_cost(10'000, 2, 3),
                 large = grid_cost(10'000'000, 2, 3), wide = grid_cost(10'000'000, 2, 13);
  EXPECT_EQ(small.cells_per_point, 6u);
  EXPECT_EQ(tiny.held_rows, 18u);
  EXPECT_EQ(small.held_rows, 10'000u + 10'000u);
  EXPECT_EQ(large.held_rows, GridCost::max_held_rows);
  EXPECT_EQ(small.memory_bytes(), GridCost::fixed_memory_bytes + 20'000 * 6 * GridCost::memory_bytes_per_cell +
                                      10'000 * GridCost::bookkeeping_bytes_per_point);
  EXPECT_EQ(large.memory_bytes() - grid_cost(1'000'000, 2, 3).memory_bytes(),
            9'000'000 * GridCost::bookkeeping_bytes_per_point);
  EXPECT_EQ(wide.disk_bytes(), 10'000'000 * 16 * GridCost::disk_bytes_per_cell);
  EXPECT_GT(wide.memory_bytes(), large.memory_bytes());
  EXPECT_GT(small.default_max_points, wide.default_max_points);
  // What the limit accepts fits in the budget; one point more would not.
  EXPECT_LE(grid_cost(small.default_max_points, 2, 3).memory_bytes(), small.memory_budget_bytes);
  EXPECT_GT(grid_cost(small.default_max_points + 1, 2, 3).memory_bytes(), small.memory_budget_bytes);
}

TEST(GridCost, AGridOverTheLimitNeedsAllowLarge) {
  TempDir dir;
  const GridCost cost = grid_cost(0, 2, 2);
  // Two axes whose product passes this machine's limit (never expanded: refused from the sizes).
  const std::size_t side = static_cast<std::size_t>(std::sqrt(double(cost.default_max_points))) + 2;
  const std::string grid = fmt::format(
      "[grid]\nspeed_rpm = {{ from = 1, to = 2, steps = {0} }}\n\"fake_settings.scale\" = "
      "{{ from = 1, to = 2, steps = {0} }}\n",
      side);
  const std::string message = load_error(dir, fake_study(grid));
  EXPECT_NE(message.find(fmt::format("more than the limit of {} on this machine", cost.default_max_points)),
            std::string::npos)
      << message;
}

TEST(SetAtPath, WritesNestedItemsAndNamesWhatExistsWhenThePathDoesNot) {
  Json document = Json::parse(R"({"model": {"modes": [{"damping_ratio": 0.1}], "gains": [[1, 2], [3, 4]]}})");
  set_at_path(document, "model.modes.0.damping_ratio", 0.3);
  set_at_path(document, "model.gains.1.0", 7.5);
  EXPECT_EQ(document["model"]["modes"][0]["damping_ratio"], 0.3);
  EXPECT_EQ(document["model"]["gains"][1][0], 7.5);

  std::string message = input_error_of([&] { set_at_path(document, "model.modes.5.damping_ratio", 0.1); });
  EXPECT_EQ(message, "model.modes is a list and it has 1 entry (index 0); there is no index 5");
  message = input_error_of([&] { set_at_path(document, "model.gains.x", 1.0); });
  EXPECT_EQ(message, "model.gains is a list: 'x' is not an index; it has 2 entries (indices 0 to 1)");
  message = input_error_of([&] { set_at_path(document, "model.modes.0.damping", 0.1); });
  EXPECT_EQ(message, "model.modes.0 has no key 'damping' (did you mean 'damping_ratio'?); it has: damping_ratio");
  message = input_error_of([&] { set_at_path(document, "model.gains.0.1.x", 0.1); });
  EXPECT_EQ(message, "model.gains.0.1 is a number (2), it has no item 'x'");
  message = input_error_of([&] { set_at_path(document, "modle.gains", 0.1); });
  EXPECT_EQ(message, "the study has no table 'modle' (did you mean 'model'?); it has: model");
  message = input_error_of([&] { set_at_path(document, "model..gains", 0.1); });
  EXPECT_EQ(message, "'model..gains' is not a parameter path (empty part between dots)");
}

}  // namespace
}  // namespace chatterlab::testing
