// grid_cost (chatterlab/study.hpp): the memory and disk a grid's results take, and the default
// grid-size limit derived from this machine's memory.
#include <unistd.h>

#include <algorithm>
#include <limits>

#include "chatterlab/study.hpp"
#include "runner/mpi_scheduler.hpp"
#include "runner/result_writer.hpp"

namespace chatterlab {

namespace {
std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return std::uint64_t{8} << 30;  // unknown: assume a small machine
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
}
}  // namespace

GridCost grid_cost(std::size_t points, std::size_t grid_keys, std::size_t output_columns) {
  static_assert(GridCost::max_held_rows == runner::max_plot_rows + runner::max_block_points,
                "GridCost::max_held_rows: the plots' rows and one block in flight");
  GridCost cost;
  cost.points = points;
  cost.cells_per_point = grid_keys + output_columns + 1;  // + status
  const std::uint64_t row_bytes = GridCost::memory_bytes_per_cell * cost.cells_per_point;
  cost.held_rows = std::min<std::uint64_t>(points, runner::max_plot_rows) +
                   std::min<std::uint64_t>(points, runner::max_block_points);
  cost.held_rows_bytes = cost.held_rows * row_bytes;
  cost.disk_bytes_per_point = GridCost::disk_bytes_per_cell * cost.cells_per_point;
  // Half: gnuplot draws the maps beside the run, and the machine has other work.
  cost.memory_budget_bytes = physical_memory_bytes() / 2;
  // Past the held rows' cap only the bookkeeping grows: the limit is where it fills the budget.
  const std::uint64_t capped = GridCost::fixed_memory_bytes + GridCost::max_held_rows * row_bytes;
  const std::uint64_t room = cost.memory_budget_bytes > capped ? cost.memory_budget_bytes - capped : 0;
  cost.default_max_points = static_cast<std::size_t>(std::min<std::uint64_t>(
      room / GridCost::bookkeeping_bytes_per_point, std::numeric_limits<std::size_t>::max()));
  return cost;
}

}  // namespace chatterlab
