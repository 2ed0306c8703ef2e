// Out-of-tree plugins (plugin_api.hpp): the example library of tests/external_plugin/ is loaded
// with dlopen, found in the model registry, built from its own example, and used by a
// stability_map study exactly like a built-in model. Every way a library can be refused is checked
// by its message text. Library paths come from tests/external_plugin/CMakeLists.txt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "chatterlab/catalog.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "study/source_map.hpp"
#include "study_test_support.hpp"

namespace chatterlab {
namespace {

namespace fs = std::filesystem;
using testing::input_error_of;
using testing::TempDir;

const std::string example_library = fs::canonical(CHATTERLAB_EXAMPLE_PLUGIN).string();

const Registry<Model>::Entry& load_example() {
  load_plugin_library(CHATTERLAB_EXAMPLE_PLUGIN);
  const auto* entry = model_registry().find("example_delay_model");
  if (entry == nullptr) throw std::runtime_error("example_delay_model not registered");
  return *entry;
}

// The example model's parameters, validated like a study's [model] table.
ParamValues example_values(const Json& overrides) {
  Json table = load_example().info.example_params;
  for (const auto& [key, value] : overrides.items()) table[key] = value;
  LineSourceMap sources("example");
  return ParamValues(validate_params(table, load_example().info.params, "model", sources));
}

TEST(PluginLoader, LoadsTheExampleLibraryIntoTheModelRegistry) {
  const auto& entry = load_example();
  EXPECT_EQ(entry.origin, example_library);
  EXPECT_EQ(entry.info.thread_safety, ThreadSafety::shareable);

  // Its characteristic function is the one written in example_model.cpp:
  // E(s) = s^2/w^2 + 2 zeta s/w + 1 + K (1 - e^{-sT}).
  auto model = entry.create(example_values(Json::object()));
  ASSERT_NE(model, nullptr);
  auto characteristic = model->characteristic();
  ASSERT_NE(characteristic, nullptr);
  const double w = 2 * std::numbers::pi * 50.0, zeta = 0.05, k = 0.5, delay = 60.0 / 600.0;
  const Complex s(-3.0, 310.0);
  const Complex expected =
      s * s / (w * w) + 2.0 * zeta * s / w + 1.0 + k * (1.0 - std::exp(-s * delay));
  const CharacteristicValue value = characteristic->evaluate(s);
  EXPECT_NEAR(std::abs(value.value - expected), 0.0, 1e-12 * std::abs(expected));
  EXPECT_DOUBLE_EQ(characteristic->natural_frequency_scale_hz(), 50.0);
  EXPECT_FALSE(model->wheel_period_s().has_value());
}

TEST(PluginLoader, LoadingTheSameLibraryAgainIsANoOp) {
  load_example();
  const std::size_t models = model_registry().sorted().size();
  // Another spelling of the same file: a relative path through its directory's parent.
  fs::path library(example_library);
  fs::path detour =
      library.parent_path() / ".." / library.parent_path().filename() / library.filename();
  EXPECT_NO_THROW(load_plugin_library(detour.string()));
  EXPECT_NO_THROW(load_plugin_library(example_library));
  EXPECT_EQ(model_registry().sorted().size(), models);
}

TEST(PluginLoader, ListAndDescribeShowTheLoadedPlugin) {
  load_example();
  const std::string list = format_plugin_list();
  const std::size_t at = list.find(" example_delay_model ");
  ASSERT_NE(at, std::string::npos) << list;
  const std::size_t begin = list.rfind('\n', at) + 1, end = list.find('\n', at);
  const std::string line = list.substr(begin, end - begin);
  EXPECT_EQ(line.rfind("model ", 0), 0u) << line;
  const std::string tail =
      "  one structural mode with workpiece regeneration (out-of-tree example)"
      "  (from " +
      example_library + ")";
  EXPECT_EQ(line.substr(line.size() - std::min(line.size(), tail.size())), tail) << line;
  const std::string text = describe_plugin("example_delay_model");
  EXPECT_NE(text.find("example_delay_model (model, " + example_library + ")"), std::string::npos)
      << text;
  EXPECT_NE(text.find("[model]\n  type = \"example_delay_model\"\n  natural_frequency_hz = 50.0\n"),
            std::string::npos)
      << text;
}

TEST(PluginLoader, MissingFileIsReported) {
  EXPECT_EQ(input_error_of([] { load_plugin_library("/nonexistent/libnothing.so"); }),
            "plugin library '/nonexistent/libnothing.so' not found");
}

TEST(PluginLoader, FileThatIsNotASharedLibraryIsReportedWithTheLoaderMessage) {
  TempDir dir;
  // Longer than an ELF header, so the loader reads it and rejects its contents.
  fs::path fake =
      dir.write("libfake.so", std::string(20, '#') + " a text file, not an ELF shared object\n" +
                                  std::string(200, '#') + "\n");
  const std::string path = fs::canonical(fake).string();
  std::string message = input_error_of([&] { load_plugin_library(fake.string()); });
  EXPECT_EQ(message.rfind("cannot load plugin library '" + path + "': ", 0), 0u) << message;
  // dlerror() names the file and the reason.
  EXPECT_NE(message.find("invalid ELF header"), std::string::npos) << message;
}

TEST(PluginLoader, LibraryWithoutTheEntrySymbolIsNotAPlugin) {
  const std::string path = fs::canonical(CHATTERLAB_NO_ENTRY_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_NO_ENTRY_PLUGIN); }),
            "'" + path +
                "' is not a chatterlab plugin: it has no symbol chatterlab_plugin_entry (define it "
                "with CHATTERLAB_PLUGIN_ENTRY from <chatterlab/plugin_api.hpp>)");
}

// The host as the messages name it: "0.1.0 (plugin API 2)".
std::string host() {
  return std::string(CHATTERLAB_VERSION) + " (plugin API " +
         std::to_string(CHATTERLAB_PLUGIN_API_VERSION) + ")";
}

TEST(PluginLoader, LibraryForAnotherApiVersionMustBeRebuilt) {
  const std::string path = fs::canonical(CHATTERLAB_WRONG_API_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_WRONG_API_PLUGIN); }),
            "plugin library '" + path + "' was built for chatterlab " + CHATTERLAB_VERSION +
                " (plugin API 999); this chatterlab is " + host() +
                ": rebuild the library against this version");
  // Refused, not remembered: asking again gives the same answer.
  EXPECT_NE(input_error_of([] { load_plugin_library(CHATTERLAB_WRONG_API_PLUGIN); }), "");
}

TEST(PluginLoader, AnEntryPointThrowingAnythingIsBadInputNotTerminate) {
  const std::string path = fs::canonical(CHATTERLAB_THROWING_ENTRY_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_THROWING_ENTRY_PLUGIN); }),
            "plugin library '" + path +
                "' failed to register: an exception of type 'int' (not derived from "
                "std::exception)");
}

TEST(PluginLoader, ALibraryConstructorThrowingAnythingNamesThePluginAndLibrary) {
  load_plugin_library(CHATTERLAB_MISBEHAVING_PLUGIN);
  const std::string path = fs::canonical(CHATTERLAB_MISBEHAVING_PLUGIN).string();
  const auto& entry = model_registry().at("misbehaving_model");
  try {
    entry.create(ParamValues(Json{{"decay_rate_per_s", 1.0},
                                  {"behaviour", "throw_in_constructor"},
                                  {"sleep_s", 0.0}}));
    ADD_FAILURE() << "nothing thrown";
  } catch (const PluginError& e) {
    EXPECT_EQ(e.plugin(), "misbehaving_model");
    EXPECT_EQ(e.library(), path);
    EXPECT_EQ(std::string(e.what()),
              "model plugin 'misbehaving_model' (library " + path +
                  "): its constructor threw an exception of type 'int' (not derived from "
                  "std::exception)");
  }
  // What the plugin's code throws later (at a grid point) is named by the runner, from the
  // plugins a point's document chooses.
  EXPECT_EQ(out_of_tree_plugins_in(Json{{"model", {{"type", "misbehaving_model"}}},
                                        {"analysis", {{"methods", {{{"type", "nothing"}}}}}}}),
            "model plugin 'misbehaving_model' (library " + path + ")");
  EXPECT_EQ(out_of_tree_plugins_in(Json{{"model", {{"type", "plunge_regenerative"}}}}), "");
}

TEST(PluginLoader, LibraryForAnotherChatterlabVersionMustBeRebuilt) {
  // Same plugin API, another minor version: refused from the build record, before its entry
  // (which would throw) is called.
  const std::string path = fs::canonical(CHATTERLAB_WRONG_VERSION_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_WRONG_VERSION_PLUGIN); }),
            "plugin library '" + path + "' was built for chatterlab 9.9.0 (plugin API " +
                std::to_string(CHATTERLAB_PLUGIN_API_VERSION) + "); this chatterlab is " + host() +
                ": rebuild the library against this version");
  const PluginLibraryBuild build = plugin_library_build(CHATTERLAB_WRONG_VERSION_PLUGIN);
  EXPECT_EQ(build.chatterlab_version, "9.9.0");
  EXPECT_EQ(build.compiler, "GCC 99");
}

TEST(PluginLoader, LibraryOfPluginApi1MustBeRebuilt) {
  // API 1 libraries carry no build record; their entry reports the version they were built for.
  const std::string path = fs::canonical(CHATTERLAB_API1_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_API1_PLUGIN); }),
            "plugin library '" + path +
                "' was built for plugin API 1 (a chatterlab that records no version); this "
                "chatterlab is " + host() + ": rebuild the library against this version");
}

TEST(PluginLoader, BuildRecordOfTheExampleNamesThisVersion) {
  const PluginLibraryBuild build = plugin_library_build(CHATTERLAB_EXAMPLE_PLUGIN);
  EXPECT_EQ(build.plugin_api_version, CHATTERLAB_PLUGIN_API_VERSION);
  EXPECT_EQ(build.chatterlab_version, CHATTERLAB_VERSION);
  EXPECT_EQ(build.compiler.rfind("GCC ", 0), 0u) << build.compiler;
}

TEST(PluginLoader, DuplicatePluginNameNamesBothLibraries) {
  load_example();
  const std::string copy = fs::canonical(CHATTERLAB_EXAMPLE_PLUGIN_COPY).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_EXAMPLE_PLUGIN_COPY); }),
            "plugin library '" + copy +
                "' cannot be loaded: duplicate model plugin name 'example_delay_model' (already "
                "registered by " +
                example_library + ")");
  // The registry still holds the first library's plugin.
  EXPECT_EQ(model_registry().at("example_delay_model").origin, example_library);
}

TEST(PluginLoader, NameRegisteredTwiceByOneLibraryRefusesTheWholeLibrary) {
  const std::string path = fs::canonical(CHATTERLAB_TWICE_PLUGIN).string();
  EXPECT_EQ(input_error_of([] { load_plugin_library(CHATTERLAB_TWICE_PLUGIN); }),
            "plugin library '" + path +
                "' failed to register: chatterlab: duplicate model plugin name "
                "'twice_registered_model' (registered by " +
                path + " and by " + path + ")");
  EXPECT_EQ(model_registry().find("twice_registered_model"), nullptr);
}

// A study names the library under `plugins`; the stability_map kind then runs the out-of-tree
// model through the framework's root solver. Known answers of this model:
//  - K = 0 (no regeneration): the structural pole, Re s = -zeta w, Im s = w sqrt(1 - zeta^2);
//  - the regenerative stability limit K_lim = 2 zeta (1 + zeta) at the speed where the chatter
//    frequency w_c = w sqrt(1 + 2 zeta) satisfies E(i w_c) = 0: stable just below it, chatter
//    just above, at that speed.
class ExampleStudy : public ::testing::Test {
 protected:
  Json run_point(double stiffness_ratio, double work_speed_rpm) {
    std::string text =
        "plugins = [\"" + std::string(CHATTERLAB_EXAMPLE_PLUGIN) + "\"]\n" +
        "[study]\nkind = \"stability_map\"\n"
        "[model]\ntype = \"example_delay_model\"\n"
        "natural_frequency_hz = 50.0\n" +
        fmt::format("stiffness_ratio = {}\nwork_speed_rpm = {}\n", stiffness_ratio, work_speed_rpm);
    Study study = load_study(dir_.write("study.toml", text));
    EXPECT_EQ(study.plugin_libraries, std::vector<std::string>{CHATTERLAB_EXAMPLE_PLUGIN});
    auto kind = study_kind_registry().at("stability_map").create(ParamValues{});
    std::vector<std::string> columns = kind->output_columns(study.document);
    std::vector<Json> values = kind->run_point(study.point_document(0), {});
    Json row = Json::object();
    for (std::size_t i = 0; i < columns.size() && i < values.size(); ++i)
      row[columns[i]] = values[i];
    return row;
  }
  TempDir dir_;
};

TEST_F(ExampleStudy, WithoutRegenerationTheRootIsTheStructuralPole) {
  const double w = 2 * std::numbers::pi * 50.0, zeta = 0.05;
  Json row = run_point(0.0, 600.0);
  EXPECT_NEAR(row["growth_rate_per_s"].get<double>(), -zeta * w, 1e-9 * w) << row.dump();
  EXPECT_NEAR(row["chatter_frequency_hz"].get<double>(), 50.0 * std::sqrt(1 - zeta * zeta), 1e-9)
      << row.dump();
}

TEST_F(ExampleStudy, StabilityLimitOfTheRegenerativeModeIsReproduced) {
  const double w = 2 * std::numbers::pi * 50.0, zeta = 0.05;
  const double k_lim = 2 * zeta * (1 + zeta);
  const double w_c = w * std::sqrt(1 + 2 * zeta);
  // E(i w_c) = 0 at K_lim: e^{-i w_c T} = (P(i w_c) + K) / K fixes w_c T modulo 2 pi; take the
  // lobe with 8 chatter waves per revolution (about 400 rpm).
  const Complex iw(0.0, w_c);
  const Complex ratio = (iw * iw / (w * w) + 2.0 * zeta * iw / w + 1.0 + k_lim) / k_lim;
  ASSERT_NEAR(std::abs(ratio), 1.0, 1e-12);
  const double delay = (2 * std::numbers::pi * 8 - std::arg(ratio)) / w_c;
  const double rpm = 60.0 / delay;
  EXPECT_LT(run_point(0.98 * k_lim, rpm)["growth_rate_per_s"].get<double>(), 0.0);
  EXPECT_GT(run_point(1.02 * k_lim, rpm)["growth_rate_per_s"].get<double>(), 0.0);
  Json at_limit = run_point(k_lim, rpm);
  EXPECT_NEAR(at_limit["growth_rate_per_s"].get<double>(), 0.0, 1e-6) << at_limit.dump();
  EXPECT_NEAR(at_limit["chatter_frequency_hz"].get<double>(), w_c / (2 * std::numbers::pi), 1e-6)
      << at_limit.dump();
}

TEST(PluginLoader, BadLibraryInAStudyIsBadInput) {
  TempDir dir;
  const std::string path = fs::canonical(CHATTERLAB_WRONG_API_PLUGIN).string();
  fs::path file =
      dir.write("study.toml", "plugins = [\"" + path + "\"]\n[study]\nkind = \"stability_map\"\n");
  std::string message = input_error_of([&] { load_study(file); });
  EXPECT_NE(message.find("study.toml:1: "), std::string::npos) << message;
  EXPECT_NE(message.find("(plugin API 999); this chatterlab is " + host()), std::string::npos)
      << message;
}

}  // namespace
}  // namespace chatterlab
