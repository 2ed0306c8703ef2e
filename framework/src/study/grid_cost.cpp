// grid_cost (chatterlab/study.hpp): the memory and disk a grid's results take, and the default
// grid-size limit derived from this machine's memory.
#include <unistd.h>

#include <algorithm>
#include <limits>

#include "chatterlab/study.hpp"

namespace chatterlab {

namespace {
std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t{8} << 30;  // unknown: assume a small machine
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
}
}  // namespace

GridCost grid_cost(std::size_t points, std::size_t grid_keys, std::size_t output_columns) {
  GridCost cost;
  cost.points = points;
  cost.cells_per_point = grid_keys + output_columns + 1;  // + status
  cost.memory_bytes_per_point = GridCost::memory_bytes_per_cell * cost.cells_per_point;
  cost.disk_bytes_per_point = GridCost::disk_bytes_per_cell * cost.cells_per_point;
  // Half: gnuplot draws the maps while the results are still held (it needs about half as much
  // again for a 2-D map), and the machine has other work.
  cost.memory_budget_bytes = physical_memory_bytes() / 2;
  cost.default_max_points = static_cast<std::size_t>(
      std::min<std::uint64_t>(cost.memory_budget_bytes / cost.memory_bytes_per_point,
                              std::numeric_limits<std::size_t>::max()));
  return cost;
}

}  // namespace chatterlab
