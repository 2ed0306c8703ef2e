// The harness of plugin libraries' own tests (chatterlab/plugin_test.hpp; named *_harness.cpp because
// *_test.cpp files are tests, not library code).
#include "chatterlab/plugin_test.hpp"

#include <exception>
#include <filesystem>
#include <iostream>

#include "chatterlab/conformance.hpp"
#include "chatterlab/plugin_api.hpp"

namespace chatterlab {

void PluginChecks::operator()(bool passed, const std::string& what) {
  std::cout << (passed ? "ok   " : "FAIL ") << what << '\n';
  if (!passed) ++failures_;
}

int plugin_test_main(int argc, char** argv, const std::function<void(PluginChecks&)>& known_answers) {
  if (argc != 2) {
    std::cerr << "usage: " << (argc > 0 ? argv[0] : "test") << " path/to/libPLUGIN.so\n";
    return 2;
  }
  std::string library;
  try {
    library = std::filesystem::canonical(argv[1]).string();
    load_plugin_library(library);
  } catch (const std::exception& e) {
    std::cerr << "cannot load " << argv[1] << ": " << e.what() << '\n';
    return 2;
  }
  PluginChecks check(library);
  try {
    ConformanceOptions options;
    options.origin = library;
    const ConformanceReport report = check_conformance(options);
    std::cout << report.text();
    check(report.ok() && report.plugins > 0, "conformance suite");
    known_answers(check);
  } catch (const std::exception& e) {
    check(false, std::string("unexpected exception: ") + e.what());
  }
  std::cout << (check.failures() == 0 ? "all checks passed\n" : std::to_string(check.failures()) + " checks failed\n");
  return check.failures() == 0 ? 0 : 1;
}

}  // namespace chatterlab
