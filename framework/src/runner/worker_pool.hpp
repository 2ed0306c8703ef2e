#pragma once
// Grid points in worker processes (docs/studies.md, "Isolation and time limits"), for
// `--isolate` and for a per-point time limit: an OpenMP thread that runs a point forever cannot
// be reclaimed, a process can be killed. Up to `workers` processes each compute one point at a
// time (the same compute_point as in-process). A worker that dies (a plugin's segfault, abort,
// exit()) fails only its point, with the signal or exit status; a point over its time limit is
// killed and recorded as timeout with its time. Either way a fresh worker takes over the
// remaining points.
//
// Workers are separate executables (`<executable> __worker`), not fork()s of the runner: after
// a fork, a child of a process that has used OpenMP (GNU libgomp) hangs in its first parallel
// region, and the analyses' points use parallel loops.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "runner/point_compute.hpp"

namespace chatterlab::runner {

class WorkerPool {
 public:
  // Starts `workers` worker processes and waits until each has rebuilt the study. Throws
  // InputError when one cannot start (the study cannot be computed this way: nothing has been
  // written yet).
  WorkerPool(const Study& study, const std::vector<std::string>& columns,
             const RunOptions& options, int workers, std::optional<double> point_timeout_s);
  ~WorkerPool();  // kills and reaps what still runs
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Computes the points `todo`, calling done(k, computed) for todo[k] as each finishes (on this
  // thread). Stops dispatching, and kills the running points, once `stop` becomes true.
  void run(const std::vector<std::size_t>& todo,
           const std::function<void(std::size_t k, ComputedPoint&&)>& done,
           const std::atomic<bool>& stop);

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    bool busy = false;
    std::size_t k = 0;  // index into todo while busy
    std::chrono::steady_clock::time_point started;
  };
  Worker spawn();
  std::string reap(Worker& worker, bool killed);  // "" or how it ended ("killed by signal 11 ...")

  const Study* study_;
  std::string setup_;
  std::vector<std::shared_ptr<const std::string>> sent_bytes_;
  std::string executable_;
  std::optional<double> timeout_s_;
  std::size_t columns_ = 0;
  std::vector<Worker> workers_;
  std::string start_error_;  // why the last replacement worker could not start
};

}  // namespace chatterlab::runner
