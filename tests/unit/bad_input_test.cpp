// Bad study files: every category of the "Bad input" paragraph gives an InputError whose
// text names the file, the line, the key, the value and the violated limit, and nothing is
// written (load_error checks the directory listing).
#include <gtest/gtest.h>

#include "chatterlab/study.hpp"
#include "study_test_support.hpp"

namespace chatterlab::testing {
namespace {

// Checks that `message` contains every one of `parts`, reporting the missing ones.
void expect_mentions(const std::string& message, const std::vector<std::string>& parts) {
  for (const auto& part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << "missing \"" << part << "\" in: " << message;
}

// fake_study() with line `line` (1-based) replaced by `text`.
std::string with_line(int line, const std::string& text) {
  std::string study = fake_study();
  std::size_t begin = 0;
  for (int i = 1; i < line; ++i) begin = study.find('\n', begin) + 1;
  std::size_t end = study.find('\n', begin);
  return study.replace(begin, end - begin, text);
}

class BadInput : public ::testing::Test {
 protected:
  std::string error(const std::string& text, LoadOptions options = {}) { return load_error(dir_, text, options); }
  TempDir dir_;
};

TEST_F(BadInput, MalformedTomlGivesLineAndColumn) {
  expect_mentions(error(with_line(6, "speed_rpm = [1500,")), {"study.toml:7:", "invalid TOML"});
  expect_mentions(error(with_line(6, "speed_rpm = 1500 rpm")), {"study.toml:6:", "invalid TOML"});
  expect_mentions(error(fake_study("[model]\nx = 1\n")), {"study.toml:10:", "invalid TOML", "model"});
}

TEST_F(BadInput, UnreadableFile) {
  std::string message = input_error_of([&] { load_study(dir_.path() / "absent.toml"); });
  expect_mentions(message, {"absent.toml", "cannot read the study file", "No such file"});
  message = input_error_of([&] { load_study(dir_.path()); });
  expect_mentions(message, {"cannot read the study file: it is a directory"});
}

TEST_F(BadInput, UnknownKeysListTheValidOnes) {
  expect_mentions(error(with_line(6, "speed = 1500")),
                  {"study.toml:6:", "unknown key 'model.speed'", "valid keys: gains, harmonics, mass_kg",
                   "speed_rpm, stiffness_n_per_m, trim"});
  expect_mentions(error(with_line(7, "modes = [ { frequency_hz = 120.0, damping = 0.05 },")),
                  {"study.toml:7:", "unknown key 'model.modes.0.damping'", "did you mean 'damping_ratio'?",
                   "valid keys: damping_ratio, frequency_hz"});
  expect_mentions(error(fake_study("[stability]\nmax_frequency_hz = 100.0\n")),
                  {"study.toml:10:", "unknown top-level key 'stability'",
                   "valid: fake_settings, grid, model, output, plugins, run, study"});
  expect_mentions(error("title = \"x\"\n" + fake_study()), {"study.toml:1:", "unknown top-level key 'title'"});
  expect_mentions(error(with_line(2, "kind = \"test_fake_kind\"\nkinds = 1")),
                  {"study.toml:3:", "unknown key 'study.kinds'", "valid keys: description, kind, name"});
}

TEST_F(BadInput, OutputTableNamesTheFileLineKeyValueAndTheFormats) {
  expect_mentions(error(fake_study("[output]\nformat = \"hdf\"\n")),
                  {"study.toml:11:", "output.format = \"hdf\"", "csv", "hdf5", "auto"});
  expect_mentions(error(fake_study("[output]\nformat = 5\n")),
                  {"study.toml:11:", "output.format = 5", "expected a string"});
  expect_mentions(error(fake_study("[output]\nkeep_journals = true\n")),
                  {"study.toml:11:", "unknown key 'output.keep_journals'", "keep_journal"});
  expect_mentions(error("output = \"hdf5\"\n" + fake_study()),
                  {"study.toml:1:", "output = \"hdf5\"", "expected a table [output]"});
}

TEST_F(BadInput, UnknownStudyKindListsTheKindsSorted) {
  expect_mentions(error(with_line(2, "kind = \"stability_mapp\"")),
                  {"study.toml:2:", "study.kind = \"stability_mapp\"", "unknown study kind 'stability_mapp'",
                   "valid names: ", "test_fake_kind"});
}

TEST_F(BadInput, MissingRequiredKeys) {
  std::string no_study = fake_study().substr(fake_study().find("[model]"));
  expect_mentions(error(no_study), {"study.toml: missing required key 'study.kind'", "test_fake_kind"});
  expect_mentions(error(with_line(6, "")),
                  {"study.toml:4: missing required key 'model.speed_rpm'", "spindle speed [rpm]"});
  expect_mentions(error(with_line(7, "modes = [ { frequency_hz = 120.0 },")),
                  {"study.toml:7: missing required key 'model.modes.0.damping_ratio'"});
}

TEST_F(BadInput, WrongTypes) {
  expect_mentions(error(with_line(6, "speed_rpm = \"fast\"")),
                  {"study.toml:6:", "model.speed_rpm = \"fast\"", "expected a real number"});
  expect_mentions(error(with_line(6, "speed_rpm = 1500\nharmonics = 1.5")),
                  {"study.toml:7:", "model.harmonics = 1.5", "expected an integer"});
  expect_mentions(error(with_line(6, "speed_rpm = 1500\nmodes_x = 1")), {"study.toml:7:", "model.modes_x"});
  expect_mentions(error("model = 3\n" + fake_study().substr(0, fake_study().find("[model]"))),
                  {"study.toml:1:", "model = 3: expected a table [model]"});
  expect_mentions(error(with_line(2, "kind = 7")), {"study.toml:2:", "study.kind = 7: expected a string"});
}

TEST_F(BadInput, NonPositivePhysicalQuantities) {
  expect_mentions(error(with_line(6, "speed_rpm = 0")),
                  {"study.toml:6:", "model.speed_rpm = 0 [rpm]", "must be > 0"});
  expect_mentions(error(with_line(6, "speed_rpm = 1500\nstiffness_n_per_m = -1e7")),
                  {"study.toml:7:", "model.stiffness_n_per_m = -10000000 [N/m]", "must be > 0"});
  expect_mentions(error(with_line(6, "speed_rpm = 1500\nmass_kg = 0.0")),
                  {"study.toml:7:", "model.mass_kg = 0 [kg]", "must be > 0"});
  expect_mentions(error(with_line(8, "{ frequency_hz = -480.0, damping_ratio = 0.02 } ]")),
                  {"study.toml:8:", "model.modes.1.frequency_hz = -480 [Hz]", "must be > 0"});
}

TEST_F(BadInput, DampingOutsideZeroToOne) {
  const std::vector<std::pair<std::string, std::string>> written_and_shown = {
      {"1.0", "1"}, {"1.2", "1.2"}, {"-0.01", "-0.01"}};
  for (const auto& [written, shown] : written_and_shown)
    expect_mentions(error(with_line(8, "{ frequency_hz = 480.0, damping_ratio = " + written + " } ]")),
                    {"study.toml:8:", "model.modes.1.damping_ratio = " + shown, "must be >= 0 and < 1"});
}

TEST_F(BadInput, NanAndInfAreRejectedWhereverTheyAre) {
  expect_mentions(error(with_line(6, "speed_rpm = nan")), {"study.toml:6:", "model.speed_rpm = nan", "must be finite"});
  expect_mentions(error(with_line(6, "speed_rpm = +inf")), {"study.toml:6:", "model.speed_rpm = inf", "must be finite"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = [1000, -inf]\n")),
                  {"study.toml:11:", "grid.speed_rpm.1 = -inf", "must be finite"});
}

TEST_F(BadInput, GridValueOutsideItsLimitNamesTheGridLine) {
  std::string message = error(fake_study("[grid]\n"
                                         "speed_rpm = [1000, 2000]\n"
                                         "\"model.modes.0.damping_ratio\" = [0.02, 0.5, 1.2]\n"));
  expect_mentions(message, {"study.toml:12: [grid] model.modes.0.damping_ratio, value 3 of 3 (1.2)",
                            "model.modes.0.damping_ratio = 1.2", "must be >= 0 and < 1"});
  message = error(fake_study("[grid]\nspeed_rpm = { from = -100, to = 100, steps = 3 }\n"));
  expect_mentions(message, {"study.toml:11: [grid] speed_rpm, value 1 of 3 (-100)", "model.speed_rpm = -100 [rpm]",
                            "must be > 0"});
  // Long axes are validated on several threads: still the first bad value is reported.
  message = error(fake_study("[grid]\nspeed_rpm = { from = 2000, to = -1999, steps = 4000 }\n"));
  expect_mentions(message, {"study.toml:11: [grid] speed_rpm, value 2001 of 4000 (0)", "model.speed_rpm = 0 [rpm]"});
  message = error(fake_study("[grid]\nharmonics = { from = 1, to = 2, steps = 3 }\n"));
  expect_mentions(message, {"study.toml:11: [grid] harmonics, value 2 of 3 (1.5)", "expected an integer"});
}

TEST_F(BadInput, GridPathThatDoesNotExistListsWhatExists) {
  expect_mentions(error(fake_study("[grid]\n\"model.modes.5.damping_ratio\" = [0.1]\n")),
                  {"study.toml:11: [grid] key 'model.modes.5.damping_ratio'",
                   "model.modes is a list and it has 2 entries (indices 0 to 1); there is no index 5"});
  expect_mentions(error(fake_study("[grid]\nsped_rpm = [1000]\n")),
                  {"study.toml:11: [grid] key 'sped_rpm'", "model has no key 'sped_rpm'",
                   "did you mean 'speed_rpm'?", "it has: gains, harmonics, mass_kg, mode_shape, modes"});
  expect_mentions(error(fake_study("[grid]\n\"study.name\" = [\"a\"]\n")),
                  {"study.toml:11: [grid] key 'study.name' sets 'study.name', outside the tables of this study kind",
                   "fake_settings, model"});
}

TEST_F(BadInput, EmptyOrMalformedGridAxes) {
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = []\n")),
                  {"study.toml:11: [grid] speed_rpm = []: empty list"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = 1, to = 2, steps = 0 }\n")),
                  {"study.toml:11:", "grid.speed_rpm.steps = 0", "must be >= 1"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = 1, to = 2, steps = 2.5 }\n")),
                  {"study.toml:11:", "grid.speed_rpm.steps = 2.5", "expected an integer"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = \"a\", to = 2, steps = 2 }\n")),
                  {"study.toml:11:", "grid.speed_rpm.from = \"a\"", "expected a real number"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = 1, steps = 2 }\n")),
                  {"study.toml:11:", "missing required key 'grid.speed_rpm.to'"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = 1, to = 2, step = 2 }\n")),
                  {"study.toml:11:", "unknown key 'grid.speed_rpm.step'", "valid keys: from, log, steps, to"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = { from = 0, to = 2, steps = 2, log = true }\n")),
                  {"study.toml:11:", "grid.speed_rpm.from = 0", "must be > 0 with log = true"});
  expect_mentions(error(fake_study("[grid]\nspeed_rpm = 1500\n")),
                  {"study.toml:11: [grid] speed_rpm = 1500: expected a list of values or a range"});
  expect_mentions(error("grid = 3\n" + fake_study()), {"study.toml:1:", "grid = 3: expected a table [grid]"});
}

TEST_F(BadInput, OverlappingGridKeys) {
  expect_mentions(error(fake_study("[grid]\n"
                                   "speed_rpm = [1000]\n"
                                   "\"model.speed_rpm\" = [2000]\n")),
                  {"study.toml:12: [grid] key 'model.speed_rpm' sets model.speed_rpm, which overlaps [grid] "
                   "key 'speed_rpm' (line 11)"});
  expect_mentions(error(fake_study("[grid]\n"
                                   "\"model.modes.0.damping_ratio\" = [0.1]\n"
                                   "\"model.modes\" = [[{ frequency_hz = 1.0, damping_ratio = 0.1 }]]\n")),
                  {"study.toml:12:", "overlaps [grid] key 'model.modes.0.damping_ratio' (line 11)"});
  expect_mentions(error(fake_study("[grid]\n\"model.speed_rpm\" = [1000]\nmodel.speed_rpm = [2000]\n")),
                  {"[grid] key 'model.speed_rpm' is written twice"});
}

TEST_F(BadInput, OversizeGridNamesTheSizeAndTheFlag) {
  expect_mentions(error(fake_study("[grid]\n"
                                   "speed_rpm = { from = 1, to = 2, steps = 100000 }\n"
                                   "mass_kg = { from = 1, to = 2, steps = 1000000 }\n")),
                  {"study.toml:10: [grid] has 100000000000 points (100000 x 1000000), more than the limit of",
                   "on this machine: the run would hold about 14", " GiB at rank 0 (16 bytes of "
                   "bookkeeping per point beside ", " MiB of held rows and program), more than half "
                   "of the machine's memory", "--allow-large"});
  expect_mentions(error(fake_study("[grid]\n"
                                   "speed_rpm = { from = 1, to = 2, steps = 4294967296 }\n"
                                   "mass_kg = { from = 1, to = 2, steps = 4294967296 }\n"),
                        {.allow_large = true}),
                  {"study.toml:10: [grid] has more points (4294967296 x 4294967296) than can be counted"});
}

TEST_F(BadInput, MissingPluginLibrary) {
  expect_mentions(error("plugins = [\"libnot_there.so\"]\n" + fake_study()),
                  {"study.toml:1: plugins.0 = \"libnot_there.so\" (", "libnot_there.so)"});
  // Not a shared library at all: dlopen's reason, under the study's file, line and key.
  std::string library = dir_.write("libgarbage.so", "not an ELF file").string();
  expect_mentions(error("plugins = [\"libgarbage.so\"]\n" + fake_study()),
                  {"study.toml:1: plugins.0 = \"libgarbage.so\" (" + library + "): "});
  expect_mentions(error("plugins = [3]\n" + fake_study()),
                  {"study.toml:1: plugins.0 = 3: expected the path of a shared library"});
}

}  // namespace
}  // namespace chatterlab::testing
