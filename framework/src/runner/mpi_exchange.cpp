#include "runner/mpi_exchange.hpp"

#include <mpi.h>

#include <climits>
#include <stdexcept>

#include "chatterlab/detail/mpi_env.hpp"

namespace chatterlab::runner {

namespace {
bool distributed() { return mpi_size() > 1; }

int checked_count(std::size_t n) {
  // MPI counts are int; a rank's share of a grid under the 10^7-point limit stays far below.
  if (n > static_cast<std::size_t>(INT_MAX))
    throw std::runtime_error("runner: MPI message over 2 GiB");
  return static_cast<int>(n);
}
}  // namespace

void broadcast_from_root(std::string& text) {
  if (!distributed()) return;
  unsigned long long size = text.size();
  MPI_Bcast(&size, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(size));
  if (size > 0) MPI_Bcast(text.data(), checked_count(text.size()), MPI_CHAR, 0, MPI_COMM_WORLD);
}

bool all_ranks_agree(bool value) {
  if (!distributed()) return value;
  int mine = value ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return all != 0;
}

std::vector<std::string> gather_to_root(const std::string& text) {
  if (!distributed()) return {text};
  const int size = mpi_size(), rank = mpi_rank();
  int mine = checked_count(text.size());
  std::vector<int> counts(rank == 0 ? static_cast<std::size_t>(size) : 0);
  MPI_Gather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<int> offsets(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = checked_count(total);
    total += static_cast<std::size_t>(counts[r]);
  }
  std::string all(total, '\0');
  MPI_Gatherv(text.data(), mine, MPI_CHAR, all.data(), counts.data(), offsets.data(), MPI_CHAR, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> out;
  for (std::size_t r = 0; r < counts.size(); ++r)
    out.push_back(
        all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(counts[r])));
  return out;
}

}  // namespace chatterlab::runner
