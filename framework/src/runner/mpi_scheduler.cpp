#include "runner/mpi_scheduler.hpp"

#include <mpi.h>

#include <algorithm>

#include "chatterlab/detail/mpi_env.hpp"

namespace chatterlab::runner {

std::size_t guided_block_size(std::size_t remaining, int ranks, int threads) {
  const std::size_t share = remaining / (4 * static_cast<std::size_t>(std::max(ranks, 1)));
  return std::min(remaining, std::max(std::min(share, max_block_points),
                                      static_cast<std::size_t>(std::max(threads, 1))));
}

PointScheduler::PointScheduler(std::size_t points, int threads,
                               std::function<void(std::size_t)> points_done_elsewhere)
    : points_(points),
      threads_(threads),
      rank_(mpi_rank()),
      ranks_(mpi_size()),
      owner_(std::this_thread::get_id()),
      points_done_elsewhere_(std::move(points_done_elsewhere)) {
  if (ranks_ == 1) return;
  auto* window = new MPI_Win;
  const MPI_Aint bytes = rank_ == 0 ? 2 * sizeof(std::uint64_t) : 0;
  MPI_Win_allocate(bytes, sizeof(std::uint64_t), MPI_INFO_NULL, MPI_COMM_WORLD, &counters_,
                   window);
  window_ = window;
  if (rank_ == 0) {
    MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, *window);
    counters_[0] = counters_[1] = 0;
    MPI_Win_unlock(0, *window);
  }
  MPI_Barrier(MPI_COMM_WORLD);  // nobody claims before the counters are zero
}

PointScheduler::~PointScheduler() {
  if (window_ == nullptr) return;
  auto* window = static_cast<MPI_Win*>(window_);
  if (mpi_active()) MPI_Win_free(window);
  delete window;
}

void PointScheduler::serve() {
  if (rank_ != 0 || ranks_ == 1 || std::this_thread::get_id() != owner_) return;
  int ignored = 0;
  MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &ignored, MPI_STATUS_IGNORE);
}

std::optional<PointBlock> PointScheduler::next(std::size_t points_done) {
  if (ranks_ == 1) {
    if (claimed_ == points_) return std::nullopt;
    claimed_ = points_;
    return PointBlock{0, points_};
  }
  auto& window = *static_cast<MPI_Win*>(window_);
  // The size is judged from what was unclaimed at this rank's last claim: a little large when
  // others claimed since, which the guided shrinking absorbs.
  const std::uint64_t size = std::max<std::size_t>(
      1, guided_block_size(points_ - std::min(claimed_, points_), ranks_, threads_));
  const std::uint64_t newly_done = points_done - reported_done_;
  std::uint64_t start = 0, done_before = 0;
  MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, window);
  MPI_Fetch_and_op(&size, &start, MPI_UINT64_T, 0, 0, MPI_SUM, window);
  MPI_Fetch_and_op(&newly_done, &done_before, MPI_UINT64_T, 0, 1, MPI_SUM, window);
  MPI_Win_unlock(0, window);
  reported_done_ = points_done;
  if (rank_ == 0 && points_done_elsewhere_) {
    // Everyone's finished points, less rank 0's own (its bar counts those itself).
    const std::uint64_t everywhere = done_before + newly_done - points_done;
    if (everywhere > seen_done_) points_done_elsewhere_(everywhere - seen_done_);
    seen_done_ = std::max(seen_done_, everywhere);
  }
  claimed_ = static_cast<std::size_t>(std::min<std::uint64_t>(start + size, points_));
  if (start >= points_) return std::nullopt;
  return PointBlock{static_cast<std::size_t>(start), claimed_};
}

}  // namespace chatterlab::runner
