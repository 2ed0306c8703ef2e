#pragma once
// [grid] -> axes: resolves each key to a parameter path, expands lists and ranges, checks the
// size limit and validates every axis value once at its path.
#include <vector>

#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab {

// `grid` is the flat [grid] table (see read_toml_study); `validated` the study document after
// kind.validate, without [grid]. Throws InputError naming the grid key's line, key, value and the
// violated limit.
// `output_columns` (the kind's) sizes the results for the grid-size limit (grid_cost).
std::vector<GridAxis> build_grid(const Json& grid, const Json& validated, const StudyKind& kind,
                                 const SourceMap& sources, const LoadOptions& options,
                                 std::size_t output_columns);

// Number of points of a grid with these axis sizes (1 for none); nullopt when it overflows.
std::optional<std::size_t> grid_point_count(const std::vector<std::size_t>& axis_sizes);

}  // namespace chatterlab
