#pragma once
// One grid point, computed the same way in the runner's own threads and in a worker process
// (runner/worker_pool.hpp), so both give the same bytes. And the guard that makes an in-process
// run that a plugin kills (a crash, exit()) say which point did it.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

struct ComputedPoint {
  PointResult result;
  double compute_s = 0.0;      // wall time of run_point
  bool output_failed = false;  // an output write failed during the point (exit 3)
};

// Computes `point` of `study`. Nothing escapes: any exception, of any type, becomes the point's
// failure status; a failure from an out-of-tree plugin names the plugins of the point.
ComputedPoint compute_point(const StudyKind& kind, const Study& study, std::size_t point,
                            const std::vector<std::string>& columns,
                            const std::filesystem::path& out_dir, bool plots);

// `what` went wrong at a point whose document is `point_document`: when the point uses
// out-of-tree plugins, the message names them and the study file (the failure most likely came
// from one of them).
std::string with_plugin_context(const std::string& what, const Json& point_document,
                                const std::string& study_file);

// While it lives, points computed in this process are watched: a fatal signal (SIGSEGV, SIGBUS,
// SIGFPE, SIGILL, SIGABRT) prints which points were running and how to go on (--isolate) before
// the process dies as it would have; exit() called by a plugin during a point ends the process
// with exit code 3 after `on_exit_during_point` (which records it in meta.json) and a message.
class InProcessGuard {
 public:
  // `before_dying(context)` runs first in the fatal-signal handler (the journal writes what it
  // has queued), so a crash loses no point that had finished.
  InProcessGuard(int threads, std::function<void(const std::string&)> on_exit_during_point,
                 void (*before_dying)(void*), void* context);
  ~InProcessGuard();
  InProcessGuard(const InProcessGuard&) = delete;
  InProcessGuard& operator=(const InProcessGuard&) = delete;

  void started(int thread, std::size_t point);
  void finished(int thread);
};

}  // namespace chatterlab::runner
