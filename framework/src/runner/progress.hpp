#pragma once
// Progress bar with ETA on stderr, e.g.
//   [##########..........]  50%  1200/2400 points  12 s elapsed  ETA 12 s
// Redrawn in place ('\r') at most every 0.2 s, so thousands of points per second cost nothing.
// Thread-safe: grid points finish on any OpenMP thread.
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace chatterlab::runner {

class ProgressBar {
 public:
  // `total`: points of the run still to compute (all ranks). Disabled bars print nothing at all.
  ProgressBar(bool enabled, std::size_t total);
  void point_done();
  void points_done(std::size_t n);  // n points finished elsewhere (other MPI ranks)
  void finish();  // final state and a newline

  // The text of one bar, for a given state (no terminal codes): unit-testable.
  static std::string format(std::size_t done, std::size_t total, double elapsed_s);

 private:
  void draw(std::size_t done, double elapsed_s);

  bool enabled_;
  std::size_t total_;
  std::size_t done_ = 0;
  std::chrono::steady_clock::time_point start_, last_draw_;
  std::mutex mutex_;
};

// true when stderr is a terminal: the default for showing the bar.
bool stderr_is_terminal();

}  // namespace chatterlab::runner
