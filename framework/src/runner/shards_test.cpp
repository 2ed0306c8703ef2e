// --shard I/N: the value's parsing and the split of a grid into shards (tests/cli/shards.cli.sh
// runs and merges real shards).
#include "runner/shards.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/shards.hpp"

namespace chatterlab {
namespace {

using ::testing::HasSubstr;

std::string shard_error(std::string_view text) {
  try {
    parse_shard(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(Shards, ParsesIndexAndCount) {
  const ShardSpec shard = parse_shard("3/8");
  EXPECT_EQ(shard.index, 3u);
  EXPECT_EQ(shard.count, 8u);
  EXPECT_EQ(parse_shard("1/1").count, 1u);
}

TEST(Shards, RefusesMalformedValuesNamingValueAndLimit) {
  EXPECT_THAT(shard_error("0/4"), HasSubstr("--shard 0/4: the shard number I must be between 1 and N = 4"));
  EXPECT_THAT(shard_error("5/4"), HasSubstr("--shard 5/4: the shard number I must be between 1 and N = 4"));
  EXPECT_THAT(shard_error("2/0"), HasSubstr("--shard 2/0: the number of shards N must be at least 1"));
  for (const char* bad : {"", "3", "3/", "/8", "-1/8", "3/8/2", "a/b", "3 /8", "99999999999999999999999/1"})
    EXPECT_THAT(shard_error(bad), HasSubstr("expected I/N, two whole numbers with 1 <= I <= N")) << bad;
}

// Every point belongs to exactly one shard, and shard_point_count says how many each holds.
TEST(Shards, SplitTheGridCompletelyAndDisjointly) {
  for (std::size_t points : {1u, 7u, 12u, 13u}) {
    for (std::size_t count = 1; count <= points; ++count) {
      std::vector<int> owners(points, 0);
      for (std::size_t index = 1; index <= count; ++index) {
        const ShardSpec shard{index, count};
        const auto todo = runner::points_to_compute(std::string(points, '0'), shard);
        EXPECT_EQ(todo.size(), runner::shard_point_count(points, shard));
        for (std::size_t p : todo) ++owners[p];
      }
      for (std::size_t p = 0; p < points; ++p) EXPECT_EQ(owners[p], 1) << points << " " << count;
    }
  }
}

TEST(Shards, LeaveOutPointsFinishedEarlier) {
  EXPECT_EQ(runner::points_to_compute("0101000", ShardSpec{1, 2}), (std::vector<std::size_t>{0, 2, 4, 6}));
  EXPECT_EQ(runner::points_to_compute("0110000", ShardSpec{2, 2}), (std::vector<std::size_t>{3, 5}));
  EXPECT_EQ(runner::points_to_compute("0110", std::nullopt), (std::vector<std::size_t>{0, 3}));
}

TEST(Shards, RefuseMoreShardsThanPoints) {
  EXPECT_NO_THROW(runner::check_shard(ShardSpec{1, 12}, 12, "s.toml"));
  try {
    runner::check_shard(ShardSpec{2, 13}, 12, "s.toml");
    FAIL() << "accepted 13 shards of 12 points";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--shard 2/13: s.toml has 12 grid point(s), so at most 12 shard(s)"));
  }
}

}  // namespace
}  // namespace chatterlab
