#pragma once
// Shards for batch arrays (Slurm's sbatch --array, docs/cluster.md): `chatterlab run STUDY
// --shard I/N --out DIR_I` computes one slice of the grid into its own directory, and
// `chatterlab merge OUT DIR_1 ... DIR_N` checks that the directories are the N shards of one
// study, run by the same build, complete and disjoint, and writes into OUT exactly what a single
// run writes (results.csv byte-identical, meta.json, plots drawn once).
#include <filesystem>
#include <string_view>
#include <vector>

#include "chatterlab/runner.hpp"

namespace chatterlab {

// "I/N" with whole numbers 1 <= I <= N. Throws InputError naming the value and the limit.
ShardSpec parse_shard(std::string_view text);

// Merges the shard directories into `out_dir` (which must not be one of them) and draws the
// plots there; `options` supplies threads and progress (out_dir and resume are set here). Throws
// InputError naming the shard and the field when the shards do not belong together, one is
// missing, given twice, unfinished or holds points of another shard; nothing is written then.
RunSummary merge_shards(const std::filesystem::path& out_dir,
                        const std::vector<std::filesystem::path>& shard_dirs, RunOptions options);

}  // namespace chatterlab
