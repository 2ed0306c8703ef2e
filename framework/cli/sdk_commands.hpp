#pragma once
// The SDK subcommands of `chatterlab` (docs/plugins.md):
//   new-plugin --kind model|study|analysis|kinematics|suppression NAME DIR   a plugin project
//   check-plugin LIB                     the conformance suite on a plugin library
//   init KIND [-o FILE] [--example NAME]  a complete, commented study file for a study kind
//   completion bash|zsh                  the shell completion script (also installed)
// main.cpp registers them and hands over when one of them was given.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "chatterlab/study.hpp"

namespace chatterlab::cli {

struct SdkArguments {
  std::string plugin_kind, name;  // new-plugin
  std::filesystem::path dir;
  std::string library;  // check-plugin
  bool quick = false;
  int threads = 4;
  std::string study_kind;  // init
  std::filesystem::path output;
  std::string model, machine, suppression, study_name, example;
  bool force = false;
  std::vector<std::string> plugin_libraries;
  std::string shell;  // completion
};

void add_sdk_commands(CLI::App& app, SdkArguments& args);

// The exit code when the parsed command is one of the SDK commands, else nullopt. Bad input
// (an unknown kind, an existing directory, a library that does not load) throws InputError.
std::optional<int> run_sdk_command(const CLI::App& app, const SdkArguments& args);

// `--plugin LIB` on validate and run: the libraries are recorded in the study as if it named them
// under `plugins` (absolute paths, hashed into the input snapshot), so meta.json's resolved
// study loads them again and a resume or a worker process notices a rebuilt library.
void record_command_line_plugins(Study& study, const std::vector<std::string>& libraries);

}  // namespace chatterlab::cli
