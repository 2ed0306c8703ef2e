#pragma once
// The runner's side of --shard (chatterlab/shards.hpp has the user's side and merge).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/runner.hpp"
#include "runner/results_io.hpp"
#include "runner/run_meta.hpp"

namespace chatterlab::runner {

inline constexpr const char* state_shard_complete = "shard_complete";

// The points a run computes, in grid order: not finished earlier (`done`, one '0'/'1' per point)
// and, with a shard, in it.
std::vector<std::size_t> points_to_compute(const std::string& done,
                                           const std::optional<ShardSpec>& shard);

bool in_shard(std::size_t point, const ShardSpec& shard);
std::size_t shard_point_count(std::size_t points, const ShardSpec& shard);

// Throws InputError when the grid has fewer points than shards (before anything is written).
void check_shard(const ShardSpec& shard, std::size_t points, const std::string& study_file);

struct ShardRun {
  int session = 1;
  std::size_t resumed = 0, computed = 0;
  double compute_s = 0.0, wall_s = 0.0;
  std::vector<std::string> journal_errors;
  std::string output_error;  // points that could not write their files
};
struct ShardOutcome {
  std::size_t failed = 0, timed_out = 0;
  std::string output_error;
};

// Rank 0 at the end of a shard run: meta.json with state shard_complete and the shard's failed
// points, instead of results.csv and plots (those come once, from `chatterlab merge`).
// `results`: one per grid point, done for the shard's points.
ShardOutcome write_shard_meta(const MetaInputs& in, const std::vector<PointResult>& results,
                              const ShardRun& run);

}  // namespace chatterlab::runner
