#include "study/grid.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <optional>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "study/json_path.hpp"
#include "study/messages.hpp"
#include "study/source_map.hpp"

namespace chatterlab {
namespace {

// `{ from, to, steps, log }` is itself checked like a plugin's parameter table.
const std::vector<ParamSpec>& range_specs() {
  static const std::vector<ParamSpec> specs = [] {
    std::vector<ParamSpec> s = {
        param_spec("from", ValueKind::real, "", "first value of the range"),
        param_spec("to", ValueKind::real, "", "last value of the range (inclusive)"),
        param_spec("steps", ValueKind::integer, "1", "number of values, both ends included"),
        param_spec("log", ValueKind::boolean, "1", "geometric spacing (from and to > 0)")};
    s[2].min = 1;
    s[3].default_value = false;
    return s;
  }();
  return specs;
}

// Rounds to 15 significant digits, so that decimal steps come out as the decimals a user means
// (0.01 + 3 * 0.01 gives 0.04, not 0.039999999999999994) and print that way in results.csv.
double tidy(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.15g", value);
  return std::strtod(text, nullptr);
}

struct Range {
  double from = 0, to = 0;
  std::size_t steps = 1;
  bool log = false;

  std::vector<Json> values() const {
    std::vector<Json> out;
    out.reserve(steps);
    const double last = static_cast<double>(steps - 1);
    for (std::size_t i = 0; i < steps; ++i) {
      if (i == 0 || i + 1 == steps) {  // the ends exactly as written
        out.push_back(i == 0 ? from : to);
        continue;
      }
      const double up = static_cast<double>(i), down = last - up;
      // Weighted ends, not from + t (to - from): exact for whole-number ends, so a range through
      // zero (-1 to 1) hits 0 exactly rather than 2e-13. Base 10 for log: decade ranges (1e6 to
      // 1e9) have whole exponents and give exact powers of ten.
      double v = log ? std::pow(10.0, (std::log10(from) * down + std::log10(to) * up) / last)
                     : (from * down + to * up) / last;
      out.push_back(tidy(v));
    }
    return out;
  }
};

// An axis before expansion: a range is expanded only after the grid size passed its limit.
struct PendingAxis {
  GridAxis axis;
  std::optional<Range> range;
  std::size_t size() const { return range ? range->steps : axis.values.size(); }
};

class GridBuilder {
 public:
  GridBuilder(const Json& validated, const StudyKind& kind, const SourceMap& sources)
      : validated_(validated), kind_(kind), sources_(sources), tables_(kind.tables()) {}

  // One axis with its values as written (a list) or its range; not yet validated.
  PendingAxis axis(const std::string& key, const Json& spec) const {
    GridAxis axis{.key = key,
                  .path = key.find('.') == std::string::npos ? "model." + key : key,
                  .values = {},
                  .where = sources_.locate("grid." + key)};
    check_path(axis);
    if (spec.is_array()) {
      if (spec.empty())
        fail(axis, "[grid] {} = []: empty list; a grid axis needs at least one value", key);
      axis.values.assign(spec.begin(), spec.end());
      return {std::move(axis), std::nullopt};
    }
    if (spec.is_object()) return {std::move(axis), range(key, spec)};
    fail(axis, "[grid] {} = {}: expected a list of values or a range {{ from, to, steps }} "
               "(optionally with log = true)", key, messages::show(spec));
  }

  // Writes each value at the axis path into the validated study and validates it again, so every
  // limit of the kind and its plugins applies; keeps the value as validation normalised it (an
  // integer parameter stays an integer, a real becomes a double). Long axes are checked on all
  // cores: a 10^6-value axis costs 10^6 validations of the whole study. The error reported is
  // that of the first bad value, whichever thread found it.
  void validate_values(GridAxis& axis) const {
    OverlaySourceMap at_grid_line(sources_, axis.path, axis.where);
    const auto count = static_cast<std::ptrdiff_t>(axis.values.size());
    std::ptrdiff_t first_bad = count;
    std::exception_ptr first_error;
    std::mutex mutex;
#pragma omp parallel for schedule(dynamic, 64) if (count >= 1024)
    for (std::ptrdiff_t i = 0; i < count; ++i) {
      try {
        axis.values[i] = validated_value(axis.path, axis.values[i], at_grid_line);
      } catch (...) {  // nothing may leave an OpenMP region
        std::lock_guard lock(mutex);
        if (i < first_bad) first_bad = i, first_error = std::current_exception();
      }
    }
    if (!first_error) return;
    try {
      std::rethrow_exception(first_error);
    } catch (const InputError& e) {
      std::string reason = e.what();
      std::string prefix = axis.where.str() + ": ";
      if (reason.rfind(prefix, 0) == 0) reason.erase(0, prefix.size());
      fail(axis, "[grid] {}, value {} of {} ({}): {}", axis.key, first_bad + 1, count,
           messages::show(axis.values[first_bad]), reason);
    } catch (...) {  // a plugin's constructor or check threw something else: still bad input
      fail(axis, "[grid] {}, value {} of {} ({}): {}", axis.key, first_bad + 1, count,
           messages::show(axis.values[first_bad]), describe_current_exception());
    }
  }

 private:
  Json validated_value(const std::string& path, const Json& value, const SourceMap& sources) const {
    Json point = validated_;
    set_at_path(point, path, value);
    kind_.validate(point, sources);
    std::string problem;
    const Json* normalised = find_at_path(point, path, problem);
    if (normalised == nullptr)  // the kind's validation restructured the table
      throw InputError(fmt::format("validation removed {}: {}", path, problem));
    return *normalised;
  }

  template <class... Args>
  [[noreturn]] static void fail(const GridAxis& axis, fmt::format_string<Args...> format,
                                Args&&... args) {
    throw InputError(axis.where.str() + ": " + fmt::format(format, std::forward<Args>(args)...));
  }

  void check_path(const GridAxis& axis) const {
    std::string table = axis.path.substr(0, axis.path.find('.'));
    if (std::find(tables_.begin(), tables_.end(), table) == tables_.end())
      fail(axis, "[grid] key '{}' sets '{}', outside the tables of this study kind; grid keys "
                 "start with one of: {} (a name without dots means model.<name>)",
           axis.key, axis.path, messages::sorted_list(tables_));
    std::string problem;
    if (find_at_path(validated_, axis.path, problem) == nullptr)
      fail(axis, "[grid] key '{}': {}", axis.key, problem);
  }

  Range range(const std::string& key, const Json& spec) const {
    std::string path = "grid." + key;
    ParamValues checked(validate_params(spec, range_specs(), path, sources_));
    Range r{.from = checked.real("from"), .to = checked.real("to"),
            .steps = static_cast<std::size_t>(checked.integer("steps")),
            .log = checked.boolean("log")};
    if (r.log)
      for (const char* end : {"from", "to"})
        if (checked.real(end) <= 0)
          throw InputError(fmt::format("{}: {}.{} = {}: out of range, must be > 0 with log = true",
                                       sources_.locate(path + "." + end).str(), path, end,
                                       checked.real(end)));
    return r;
  }

  const Json& validated_;
  const StudyKind& kind_;
  const SourceMap& sources_;
  std::vector<std::string> tables_;
};

}  // namespace

std::optional<std::size_t> grid_point_count(const std::vector<std::size_t>& axis_sizes) {
  std::size_t count = 1;
  for (std::size_t size : axis_sizes)
    if (__builtin_mul_overflow(count, size, &count)) return std::nullopt;
  return count;
}

std::vector<GridAxis> build_grid(const Json& grid, const Json& validated, const StudyKind& kind,
                                 const SourceMap& sources, const LoadOptions& options,
                                 std::size_t output_columns) {
  GridBuilder builder(validated, kind, sources);
  std::vector<PendingAxis> pending;
  for (const auto& [key, spec] : grid.items()) {
    PendingAxis next = builder.axis(key, spec);
    const GridAxis& axis = next.axis;
    // Two keys writing the same parameter (or one inside the other) would make the point's
    // value depend on key order.
    for (const auto& [earlier, unused] : pending)
      if (path_within(axis.path, earlier.path) || path_within(earlier.path, axis.path))
        throw InputError(fmt::format("{}: [grid] key '{}' sets {}, which overlaps [grid] key '{}' "
                                     "(line {}) setting {}", axis.where.str(), axis.key, axis.path,
                                     earlier.key, earlier.where.line, earlier.path));
    pending.push_back(std::move(next));
  }

  std::vector<std::size_t> sizes;
  std::string shape;
  for (const auto& axis : pending) {
    sizes.push_back(axis.size());
    shape += (shape.empty() ? "" : " x ") + std::to_string(axis.size());
  }
  auto count = grid_point_count(sizes);
  std::string where = sources.locate("grid").str();
  if (!count)
    throw InputError(fmt::format("{}: [grid] has more points ({}) than can be counted", where, shape));
  const GridCost cost = grid_cost(*count, pending.size(), output_columns);
  if (*count > cost.default_max_points && !options.allow_large)
    throw InputError(fmt::format(
        "{}: [grid] has {} points ({}), more than the limit of {} on this machine: the run "
        "would hold about {:.1f} GiB at rank 0 ({} bytes of bookkeeping per point beside {} MiB "
        "of held rows and program), more than half of the machine's memory; pass --allow-large "
        "to run it anyway",
        where, *count, shape, cost.default_max_points,
        static_cast<double>(cost.memory_bytes()) / (1u << 30), GridCost::bookkeeping_bytes_per_point,
        (GridCost::fixed_memory_bytes + cost.held_rows_bytes) >> 20));

  std::vector<GridAxis> axes;
  for (auto& [axis, range] : pending) {
    if (range) axis.values = range->values();
    builder.validate_values(axis);
    axes.push_back(std::move(axis));
  }
  return axes;
}

}  // namespace chatterlab
