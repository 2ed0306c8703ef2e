#pragma once
// Dynamic work split across MPI ranks (issue 23, "balanced MPI"): the points still to compute
// form one list, the same on every rank; rank 0 hands out blocks of it on request and computes
// blocks itself in between. Block sizes are guided (a share of what remains, never below the
// requesting rank's thread count), so early blocks are large (few messages) and the last ones
// small (no rank is left with a long tail while the others idle), whatever the cost per point.
// A rank asks for its next block as soon as it starts one, so the answer is there when it
// finishes; rank 0 answers between its own points.
//
// Which rank computes a point never changes a result: rank 0 writes results.csv in grid order.
// Without MPI, or with one rank, the single block is the whole list.
//
// MPI_THREAD_FUNNELED: every member function communicates only on the thread that constructed
// the scheduler (serve() does nothing on any other thread, so OpenMP worker threads may call it).
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

// Guided block size: a quarter of an even share of what remains, at least `threads` (every
// thread of the rank gets a point), at most `remaining`.
std::size_t guided_block_size(std::size_t remaining, int ranks, int threads);

class PointScheduler {
 public:
  // `points` to hand out in total (the same on every rank), `threads` of this rank.
  // `remote_points_done(n)`: rank 0 hears that other ranks finished n more points (progress).
  PointScheduler(std::size_t points, int threads,
                 std::function<void(std::size_t)> remote_points_done = {});
  ~PointScheduler();
  PointScheduler(const PointScheduler&) = delete;
  PointScheduler& operator=(const PointScheduler&) = delete;

  // This rank's next block, or nullopt when every point has been handed out. `points_done`: how
  // many points this rank has finished so far. On rank 0, the nullopt comes only after every
  // other rank has been told that no work is left.
  std::optional<PointBlock> next(std::size_t points_done);

  // Rank 0: answers the requests that have arrived, without waiting. Does nothing elsewhere or
  // off the constructing thread.
  void serve();

 private:
  void answer(int rank, const std::uint64_t request[2]);
  PointBlock take(int threads);

  std::size_t points_;
  int threads_, rank_, ranks_;
  std::thread::id owner_;
  std::function<void(std::size_t)> remote_points_done_;
  // rank 0
  std::size_t next_ = 0;
  int ranks_finished_ = 0;
  std::vector<std::uint64_t> reported_done_;
  // other ranks: the request in flight and its answer
  bool pending_ = false;
  std::uint64_t reply_[2] = {0, 0};
  void* reply_request_ = nullptr;  // MPI_Request, kept out of this header
};

}  // namespace chatterlab::runner
