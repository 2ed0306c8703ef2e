#pragma once
// The plugin conformance suite: the contract every plugin and study kind is held to, run by
// `chatterlab check-plugin LIB` on a user's library and by tests/unit/conformance_test.cpp on
// every registered plugin (docs/plugins.md, "Checking a plugin"). A plugin's own tests may call it
// too. The checks, per registered entry:
//   naming        snake_case name, one-line description, `chatterlab describe` shows every key
//   specs         each parameter spec: description, unit for quantities, min <= max, a default
//                 that passes its own limits; nested fields likewise
//   example       example_params validate against the specs and the plugin builds from them
//   NaN           a NaN for any real parameter of the example is refused with the key named;
//                 a model's E(NaN) is not a number; an analysis refuses a series holding NaN;
//                 a machine's inverse() of a NaN target throws or answers NaN
//   model         E'(s) agrees with a difference of E, neutral roots are zeros, initial guesses
//                 exist, the root solver finds a root at or left of real_part_bound(); a
//                 time-domain form simulates briefly with finite outputs
//   time domain   (where a model has both forms) the growth rate and frequency of a bilateral
//                 (linear) simulation agree with the rightmost characteristic root
//   threads       the declared ThreadSafety holds: shareable instances used from several threads
//                 at once, copy_per_thread copies on several threads, give the serial results
//                 (to 1e-9 relative)
//   study kind    reads at least one table
#include <string>
#include <vector>

namespace chatterlab {

struct ConformanceOptions {
  // Only entries registered from this origin: a library's canonical path, "built-in"; "" = all.
  std::string origin;
  // Only this registry ("model", "kinematics", "suppression", "analysis", "study kind"); "" = all.
  std::string registry_kind;
  bool time_domain = true;  // the (seconds-long) characteristic-vs-simulation check
  bool threads = true;      // the concurrency check of the thread-safety declaration
  int thread_count = 4;
};

struct ConformanceResult {
  std::string plugin;  // "model 'example_delay_model'"
  std::string check;   // "specs", "example", "NaN", "model", "time domain", "threads", ...
  bool passed = true;
  bool skipped = false;  // the check does not apply (the message says why)
  std::string message;   // what failed (or why skipped, or what was measured)
};

struct ConformanceReport {
  std::vector<ConformanceResult> results;
  std::size_t plugins = 0;  // entries checked
  std::size_t failures() const;
  bool ok() const { return failures() == 0; }
  // One line per check ("PASS model 'x': specs"), failures with their message, and a summary.
  std::string text() const;
};

ConformanceReport check_conformance(const ConformanceOptions& options = {});

}  // namespace chatterlab
