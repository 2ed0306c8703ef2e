#pragma once
// Dynamic work split across MPI ranks (issue 23, "balanced MPI"): the points still to compute
// form one list, the same on every rank, and a shared counter on rank 0 (an MPI window) says
// where the unclaimed part starts. A rank that needs work claims the next block with one atomic
// fetch-and-add (MPI_Fetch_and_op), so no rank waits for another to answer: on one node (shared
// memory) and on RDMA networks the claim completes whatever rank 0 is doing; on networks where
// one-sided operations need the target's help (plain TCP), rank 0's main thread lends it
// between its points (serve()). Block sizes are guided (a quarter of an even share of what
// remains, never below the claiming rank's thread count, never above max_block_points), so early
// blocks are large (few claims) and the last ones small (no rank is left with a long tail while
// the others idle).
//
// Which rank computes a point never changes a result: rank 0 writes results.csv in grid order.
// Without MPI, or with one rank, the single block is the whole list.
//
// MPI_THREAD_FUNNELED: every member function communicates only on the thread that constructed
// the scheduler (serve() does nothing on any other thread, so OpenMP worker threads may call it).
// Constructing and destroying a scheduler are collective (every rank, in the same order).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <thread>
#include <vector>

namespace chatterlab::runner {

// Positions [begin, end) in the list of points to compute.
struct PointBlock {
  std::size_t begin = 0, end = 0;
  std::size_t size() const { return end - begin; }
};

// The largest block: a rank sends each finished block to rank 0, which buffers the blocks that
// finish ahead of an earlier one, so a block must not grow with the grid (16384 points, one
// HDF5 chunk row, a few MB of results).
inline constexpr std::size_t max_block_points = 16'384;

// Guided block size: a quarter of an even share of what remains, at most max_block_points, at
// least `threads` (every thread of the rank gets a point), at most `remaining`.
std::size_t guided_block_size(std::size_t remaining, int ranks, int threads);

class PointScheduler {
 public:
  // `points` to hand out in total (the same on every rank), `threads` of this rank.
  // `points_done_elsewhere(n)`: rank 0 hears that n more points were finished by other ranks
  // (the progress bar), each time it claims a block.
  PointScheduler(std::size_t points, int threads,
                 std::function<void(std::size_t)> points_done_elsewhere = {});
  ~PointScheduler();
  PointScheduler(const PointScheduler&) = delete;
  PointScheduler& operator=(const PointScheduler&) = delete;

  // This rank's next block, or nullopt when every point has been claimed. `points_done`: how
  // many points this rank has finished so far.
  std::optional<PointBlock> next(std::size_t points_done);

  // Rank 0: lets MPI progress the other ranks' claims (needed where one-sided operations are
  // not asynchronous). Does nothing elsewhere or off the constructing thread.
  void serve();

 private:
  std::size_t points_;
  int threads_, rank_, ranks_;
  std::thread::id owner_;
  std::function<void(std::size_t)> points_done_elsewhere_;
  std::size_t claimed_ = 0;         // where the unclaimed part started at this rank's last claim
  std::uint64_t reported_done_ = 0;  // this rank's points already added to the shared count
  std::uint64_t seen_done_ = 0;      // rank 0: the shared count at its last claim
  std::uint64_t* counters_ = nullptr;  // rank 0: {next unclaimed position, points finished}
  void* window_ = nullptr;             // MPI_Win, kept out of this header
};

}  // namespace chatterlab::runner
