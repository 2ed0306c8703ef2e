// The block sizes of the MPI scheduler, and its single-process behaviour (one block: OpenMP then
// balances the threads as before). tests/cli/mpi_equivalence.sh runs it across two ranks.
#include "runner/mpi_scheduler.hpp"

#include <gtest/gtest.h>

namespace chatterlab::runner {
namespace {

// Guided blocks cover the list exactly, shrink as it empties, never go below the threads of the
// asking rank (while points remain), and number O(ranks log n), not O(n).
TEST(MpiScheduler, GuidedBlocksCoverTheListAndShrink) {
  for (int ranks : {2, 4, 16}) {
    for (int threads : {1, 2, 8}) {
      const std::size_t points = 100000;
      std::size_t next = 0, blocks = 0, last = points;
      while (next < points) {
        const std::size_t size = guided_block_size(points - next, ranks, threads);
        ASSERT_GT(size, 0u);
        EXPECT_LE(size, last);
        EXPECT_GE(size, std::min<std::size_t>(static_cast<std::size_t>(threads), points - next));
        last = size;
        next += size;
        ++blocks;
      }
      EXPECT_EQ(next, points);
      EXPECT_LT(blocks, static_cast<std::size_t>(8 * ranks * 20));  // 4 ranks x ln(10^5) ~ 12
    }
  }
  // A large grid's blocks stay bounded (rank 0 buffers the blocks that finish early).
  EXPECT_EQ(guided_block_size(10'000'000, 2, 2), max_block_points);
  EXPECT_EQ(guided_block_size(0, 2, 4), 0u);
  EXPECT_EQ(guided_block_size(3, 2, 4), 3u);
}

TEST(MpiScheduler, OneProcessGetsTheWholeListOnce) {
  PointScheduler scheduler(37, 2);
  auto block = scheduler.next(0);
  ASSERT_TRUE(block.has_value());
  EXPECT_EQ(block->begin, 0u);
  EXPECT_EQ(block->end, 37u);
  EXPECT_FALSE(scheduler.next(37).has_value());
  scheduler.serve();  // nothing to answer without MPI
}

TEST(MpiScheduler, NothingToDoIsNoBlock) {
  PointScheduler scheduler(0, 4);
  EXPECT_FALSE(scheduler.next(0).has_value());
}

}  // namespace
}  // namespace chatterlab::runner
