#pragma once
// Helpers for the study-loading tests (study_load_test, grid_test, bad_input_test, params_test).
//
// The test-only plugins `test_fake_model` and study kind `test_fake_kind` are registered once, in
// study_load_test.cpp; the other test files name them in their study texts (one test executable).
#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <type_traits>
#include <utility>

#include <omp.h>

#include <gtest/gtest.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/registry.hpp"
#include "chatterlab/study.hpp"

namespace chatterlab::testing {

// compute() run with one OpenMP thread, with two, and with two again (the previous setting
// restored): the tests that a result does not depend on the thread count or the schedule
// compare the three bit for bit.
template <class Compute>
std::array<std::invoke_result_t<const Compute&>, 3> with_one_two_two_threads(const Compute& compute) {
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  auto one = compute();
  omp_set_num_threads(2);
  auto two = compute();
  auto again = compute();
  omp_set_num_threads(before);
  return {std::move(one), std::move(two), std::move(again)};
}

// A fresh directory under the system temporary directory, removed with its contents at scope exit.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "chatterlab_test_XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }

  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::filesystem::path file = path_ / name;
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

  // Every file and directory below the temporary directory, to check that nothing was written.
  std::set<std::filesystem::path> listing() const {
    std::set<std::filesystem::path> out;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(path_)) out.insert(entry.path());
    return out;
  }

 private:
  std::filesystem::path path_;
};

// The message of the InputError that `action` throws; a test failure (and "") when it throws
// nothing or something else.
template <class Action>
std::string input_error_of(Action&& action) {
  try {
    std::forward<Action>(action)();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError, got another exception: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected InputError, nothing was thrown";
  return {};
}

// Writes `text` as <dir>/study.toml and loads it.
inline Study load_text(const TempDir& dir, const std::string& text, LoadOptions options = {}) {
  return load_study(dir.write("study.toml", text), options);
}

// The InputError message of loading `text` as <dir>/study.toml; checks that nothing was written.
inline std::string load_error(const TempDir& dir, const std::string& text, LoadOptions options = {}) {
  std::filesystem::path file = dir.write("study.toml", text);
  auto before = dir.listing();
  std::string message = input_error_of([&] { load_study(file, options); });
  EXPECT_EQ(dir.listing(), before) << "loading a bad study wrote files";
  return message;
}

// A valid study of the fake kind: lines 1-9 are fixed (line numbers in expectations depend on
// them), `tail` is appended from line 10 on.
//   1 [study]
//   2 kind = "test_fake_kind"
//   3
//   4 [model]
//   5 type = "test_fake_model"
//   6 speed_rpm = 1500
//   7 modes = [ { frequency_hz = 120.0, damping_ratio = 0.05 },
//   8           { frequency_hz = 480.0, damping_ratio = 0.02 } ]
//   9
inline std::string fake_study(const std::string& tail = "") {
  return "[study]\n"
         "kind = \"test_fake_kind\"\n"
         "\n"
         "[model]\n"
         "type = \"test_fake_model\"\n"
         "speed_rpm = 1500\n"
         "modes = [ { frequency_hz = 120.0, damping_ratio = 0.05 },\n"
         "          { frequency_hz = 480.0, damping_ratio = 0.02 } ]\n"
         "\n" +
         tail;
}

// A `[model]` table of TOML text with the registered model's example parameters (what `chatterlab
// describe <type>` shows), one `key = value` line each.
inline std::string example_model_toml(const std::string& type) {
  std::string text = "[model]\ntype = \"" + type + "\"\n";
  for (const auto& [key, value] : model_registry().at(type).info.example_params.items())
    text += key + " = " + value.dump() + "\n";
  return text;
}

// PluginInfo of a test-only study kind `name` with one real parameter `key` (unit 1, default 1),
// whose example is `example`.
inline PluginInfo one_parameter_kind_info(const std::string& name, const std::string& description,
                                          const std::string& key, const std::string& doc, double example) {
  PluginInfo info;
  info.name = name;
  info.description = description;
  ParamSpec spec = param_spec(key, ValueKind::real, "1", doc);
  spec.default_value = 1.0;
  info.params = {spec};
  info.example_params = {{key, example}};
  return info;
}

}  // namespace chatterlab::testing
