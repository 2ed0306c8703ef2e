#include "runner/mpi_scheduler.hpp"

#include <mpi.h>

#include <algorithm>

#include "chatterlab/detail/mpi_env.hpp"

namespace chatterlab::runner {

namespace {
// Tags of the scheduler's messages: a request carries {points the rank finished, its threads},
// an answer {begin, end} (begin == end: no work left).
constexpr int tag_request = 2301;
constexpr int tag_block = 2302;
}  // namespace

std::size_t guided_block_size(std::size_t remaining, int ranks, int threads) {
  const std::size_t share = remaining / (4 * static_cast<std::size_t>(std::max(ranks, 1)));
  return std::min(remaining, std::max(share, static_cast<std::size_t>(std::max(threads, 1))));
}

PointScheduler::PointScheduler(std::size_t points, int threads,
                               std::function<void(std::size_t)> remote_points_done)
    : points_(points),
      threads_(threads),
      rank_(mpi_rank()),
      ranks_(mpi_size()),
      owner_(std::this_thread::get_id()),
      remote_points_done_(std::move(remote_points_done)),
      reported_done_(static_cast<std::size_t>(ranks_), 0) {}

PointScheduler::~PointScheduler() {
  // A run that stops early (an exception between blocks) leaves an answer in flight.
  if (pending_ && reply_request_ != nullptr) {
    auto* request = static_cast<MPI_Request*>(reply_request_);
    MPI_Cancel(request);
    MPI_Request_free(request);
  }
  delete static_cast<MPI_Request*>(reply_request_);
}

PointBlock PointScheduler::take(int threads) {
  const std::size_t size = guided_block_size(points_ - next_, ranks_, threads);
  PointBlock block{next_, next_ + size};
  next_ = block.end;
  return block;
}

void PointScheduler::answer(int rank, const std::uint64_t request[2]) {
  auto& before = reported_done_[static_cast<std::size_t>(rank)];
  if (remote_points_done_ && request[0] > before) remote_points_done_(request[0] - before);
  before = std::max(before, request[0]);
  PointBlock block = take(static_cast<int>(request[1]));
  if (block.size() == 0) ++ranks_finished_;
  std::uint64_t reply[2] = {block.begin, block.end};
  MPI_Send(reply, 2, MPI_UINT64_T, rank, tag_block, MPI_COMM_WORLD);
}

void PointScheduler::serve() {
  if (rank_ != 0 || ranks_ == 1 || std::this_thread::get_id() != owner_) return;
  for (;;) {
    int arrived = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, tag_request, MPI_COMM_WORLD, &arrived, &status);
    if (!arrived) return;
    std::uint64_t request[2];
    MPI_Recv(request, 2, MPI_UINT64_T, status.MPI_SOURCE, tag_request, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    answer(status.MPI_SOURCE, request);
  }
}

std::optional<PointBlock> PointScheduler::next(std::size_t points_done) {
  if (ranks_ == 1) {
    if (next_ == points_) return std::nullopt;
    next_ = points_;
    return PointBlock{0, points_};
  }
  if (rank_ == 0) {
    serve();
    if (next_ < points_) return take(threads_);
    // Own work done: answer until every other rank has heard that nothing is left.
    while (ranks_finished_ < ranks_ - 1) {
      std::uint64_t request[2];
      MPI_Status status;
      MPI_Recv(request, 2, MPI_UINT64_T, MPI_ANY_SOURCE, tag_request, MPI_COMM_WORLD, &status);
      answer(status.MPI_SOURCE, request);
    }
    return std::nullopt;
  }
  if (reply_request_ == nullptr) reply_request_ = new MPI_Request;
  auto* request = static_cast<MPI_Request*>(reply_request_);
  auto ask = [&] {
    std::uint64_t message[2] = {points_done, static_cast<std::uint64_t>(threads_)};
    MPI_Irecv(reply_, 2, MPI_UINT64_T, 0, tag_block, MPI_COMM_WORLD, request);
    MPI_Send(message, 2, MPI_UINT64_T, 0, tag_request, MPI_COMM_WORLD);
    pending_ = true;
  };
  if (!pending_) ask();
  MPI_Wait(request, MPI_STATUS_IGNORE);
  pending_ = false;
  const PointBlock block{reply_[0], reply_[1]};
  if (block.size() == 0) return std::nullopt;
  ask();  // the next block travels while this one is computed
  return block;
}

}  // namespace chatterlab::runner
