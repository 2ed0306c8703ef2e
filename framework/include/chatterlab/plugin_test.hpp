#pragma once
// A small harness for a plugin library's own tests (the projects of `chatterlab new-plugin` use
// it): loads the library named on the command line exactly as chatterlab loads it, runs the
// conformance suite (chatterlab/conformance.hpp) on everything it registered, then the plugin's
// known-answer checks, printing one line per check ("ok   what" or "FAIL what").
//
//     int main(int argc, char** argv) {
//       return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {
//         check(std::abs(root.real()) < 1e-6, "at the limit the root lies on the axis");
//       });
//     }
#include <functional>
#include <string>

namespace chatterlab {

class PluginChecks {
 public:
  explicit PluginChecks(std::string library) : library_(std::move(library)) {}
  // Records one check and prints its line.
  void operator()(bool passed, const std::string& what);
  int failures() const { return failures_; }
  const std::string& library() const { return library_; }  // canonical path of the library

 private:
  std::string library_;
  int failures_ = 0;
};

// The whole test program: argv[1] is the library. Returns the exit code: 0 every check passed,
// 1 a check failed (or the checks threw), 2 a usage error or a library that does not load.
int plugin_test_main(int argc, char** argv, const std::function<void(PluginChecks&)>& known_answers);

}  // namespace chatterlab
