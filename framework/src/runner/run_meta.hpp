#pragma once
// meta.json: what it says while a run goes and after it ends (docs/studies.md, "meta.json").
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"
#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::runner {

// meta.json "state" values.
inline constexpr const char* state_running = "running (or interrupted: complete it with --resume)";
inline constexpr const char* state_complete = "complete";
inline constexpr const char* state_output_failed = "output_failed";
inline constexpr const char* state_input_changed = "input_changed";
inline constexpr const char* state_ended_by_plugin = "ended_by_plugin";

struct MetaInputs {
  const Study& study;
  const RunOptions& options;
  const std::vector<std::string>& columns;
  std::string fingerprint;
  std::string started_utc;
  int threads = 1;
  bool serial = false;
  std::string isolation;  // "" (in-process), or why points run in worker processes
  std::optional<double> point_timeout_s;
};

// study_file, kind, study (resolved), grid, output_columns, points, inputs, fingerprint, build.
Json meta_header(const MetaInputs& in);
// The "run" object: start, out_dir, resume, ranks, threads, isolation, time limit.
Json run_description(const MetaInputs& in);
// meta.json of a run that has not finished: header, `state`, and `run`.
Json meta_with_state(const MetaInputs& in, const std::string& state);
// meta.json's entry of a point whose status is not ok (null for ok): index, grid values, status
// (failed | timeout), reason, elapsed_s for timeouts.
Json failed_point(const Study& study, std::size_t point, std::string_view status, double elapsed_s);

}  // namespace chatterlab::runner
