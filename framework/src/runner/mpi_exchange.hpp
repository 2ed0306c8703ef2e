#pragma once
// The few collective operations the runner needs across MPI ranks. Every function is a no-op
// (or the identity) in a single process, so run_study() has one code path for both cases.
// Only the thread that initialised MPI calls these (MPI_THREAD_FUNNELED): never from inside an
// OpenMP region.
#include <string>
#include <vector>

namespace chatterlab::runner {

// rank 0's `text` on every rank.
void broadcast_from_root(std::string& text);

// true on every rank iff `value` is true on every rank.
bool all_ranks_agree(bool value);

// Rank 0 receives every rank's text (index = rank); other ranks receive an empty vector.
std::vector<std::string> gather_to_root(const std::string& text);

}  // namespace chatterlab::runner
