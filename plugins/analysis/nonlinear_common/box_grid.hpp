#pragma once
// Fixed-radius neighbour search on a box grid over the first one or two delay coordinates, shared
// by the pair loops of the nonlinear analyses that need every neighbour within a radius
// (kantz_scan, correlation sums over all pairs): cheaper than a k-d tree when all neighbours
// within one radius are wanted.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace chatterlab::nonlinear {

// A box grid over the first `axes` (1 or 2) delay coordinates of x (vectors 0..points-1),
// boxes at least `radius` wide, so the neighbours of a point lie in its own and the adjacent
// boxes. Points are stored box by box (coordinates copied next to the index) so a query streams
// through contiguous memory.
class BoxGrid {
 public:
  struct Entry {
    double a, b;
    std::uint32_t index;
  };
  BoxGrid(const std::vector<double>& x, int delay, int axes, std::size_t points, double radius)
      : axes_(axes), delay_(std::size_t(delay)) {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    low_ = *lo;
    // At most 1024 boxes per axis (2-d: 1M boxes): a tiny radius makes wider boxes, not more.
    constexpr double max_boxes = 1024;
    const double range = *hi - *lo;
    width_ = std::max(radius, range / max_boxes);
    per_axis_ = std::size_t(range / width_) + 1;
    const std::size_t cells = axes == 2 ? per_axis_ * per_axis_ : per_axis_;
    start_.assign(cells + 1, 0);
    std::vector<std::size_t> cell_of(points);
    for (std::size_t j = 0; j < points; ++j) {
      cell_of[j] = cell(x[j], axes == 2 ? x[j + delay_] : 0.0);
      ++start_[cell_of[j] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    entries_.resize(points);
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t j = 0; j < points; ++j)
      entries_[fill[cell_of[j]]++] = {x[j], axes == 2 ? x[j + delay_] : 0.0, std::uint32_t(j)};
  }
  // Box of a point (its order in the grid's storage).
  std::size_t cell(double a, double b) const {
    return axes_ == 2 ? axis_box(a) * per_axis_ + axis_box(b) : axis_box(a);
  }
  // The stored points in the boxes around (a, b): up to three runs [first, last) of entries()
  // (the adjacent boxes of one row lie next to each other in storage). Returns the run count.
  std::size_t runs_near(double a, double b, std::size_t (&first)[3], std::size_t (&last)[3]) const {
    const std::size_t ia = axis_box(a);
    const std::size_t ib = axes_ == 2 ? axis_box(b) : 0;
    std::size_t n = 0;
    if (axes_ == 1) {
      first[0] = start_[ia > 0 ? ia - 1 : 0];
      last[0] = start_[std::min(ia + 1, per_axis_ - 1) + 1];
      return 1;
    }
    for (std::size_t u = ia > 0 ? ia - 1 : 0; u <= std::min(ia + 1, per_axis_ - 1); ++u, ++n) {
      first[n] = start_[u * per_axis_ + (ib > 0 ? ib - 1 : 0)];
      last[n] = start_[u * per_axis_ + std::min(ib + 1, per_axis_ - 1) + 1];
    }
    return n;
  }
  // Half of that neighbourhood, for visiting each pair once: the entries after entry q up to the
  // end of the next box in its row, and the three adjacent boxes of the next row (1 axis: the
  // rest of its box and the next box). Over all q every pair of points in adjacent boxes is met
  // exactly once. Returns the run count.
  std::size_t forward_runs(std::size_t q, std::size_t (&first)[2], std::size_t (&last)[2]) const {
    const Entry& e = entries_[q];
    const std::size_t ia = axis_box(e.a);
    if (axes_ == 1) {
      first[0] = q + 1;
      last[0] = start_[std::min(ia + 1, per_axis_ - 1) + 1];
      return 1;
    }
    const std::size_t ib = axis_box(e.b);
    first[0] = q + 1;
    last[0] = start_[ia * per_axis_ + std::min(ib + 1, per_axis_ - 1) + 1];
    if (ia + 1 >= per_axis_) return 1;
    first[1] = start_[(ia + 1) * per_axis_ + (ib > 0 ? ib - 1 : 0)];
    last[1] = start_[(ia + 1) * per_axis_ + std::min(ib + 1, per_axis_ - 1) + 1];
    return 2;
  }
  const Entry* entries() const { return entries_.data(); }
  // Rows: the boxes of the first axis. Row u's points are entries [row_begin(u), row_begin(u + 1))
  // (stored box by box along the second axis), so adjacent rows are adjacent in storage.
  std::size_t rows() const { return per_axis_; }
  std::size_t row_begin(std::size_t u) const { return start_[axes_ == 2 ? u * per_axis_ : u]; }
  // The non-empty rows, the most work first: a row's pair work grows with its points times the
  // points of it and its neighbour rows. Handed out in this order (dynamic scheduling), the big
  // rows start early and the threads finish together.
  std::vector<std::size_t> rows_most_work_first() const {
    auto points = [&](std::size_t u) { return row_begin(u + 1) - row_begin(u); };
    std::vector<std::pair<double, std::size_t>> work;
    for (std::size_t u = 0; u < per_axis_; ++u) {
      if (points(u) == 0) continue;
      const std::size_t around =
          points(u) + (u > 0 ? points(u - 1) : 0) + (u + 1 < per_axis_ ? points(u + 1) : 0);
      work.emplace_back(-double(points(u)) * double(around), u);
    }
    std::sort(work.begin(), work.end());
    std::vector<std::size_t> order;
    for (const auto& w : work) order.push_back(w.second);
    return order;
  }

 private:
  std::size_t axis_box(double v) const {
    return std::min(per_axis_ - 1, std::size_t(std::max(0.0, (v - low_) / width_)));
  }
  int axes_;
  std::size_t delay_, per_axis_ = 1;
  double low_ = 0, width_ = 1;
  std::vector<std::size_t> start_;
  std::vector<Entry> entries_;
};

// The delay coordinates x_{j + l delay}, l < used, of the points of a range of grid entries (a
// few adjacent rows), copied densely in grid order with `stride` values per point (zeros from
// `used` on): the candidates of a box then lie in contiguous memory instead of at random places
// of the series, which is what the pair loops were waiting on.
class CopiedCoordinates {
 public:
  void fill(const BoxGrid& grid, const double* x, std::size_t delay, std::size_t first_entry,
            std::size_t end_entry, std::size_t used, std::size_t stride) {
    begin_ = first_entry;
    stride_ = stride;
    values_.resize((end_entry - first_entry) * stride);
    const BoxGrid::Entry* entries = grid.entries();
    for (std::size_t q = first_entry; q < end_entry; ++q) {
      const double* from = x + entries[q].index;
      double* to = values_.data() + (q - first_entry) * stride;
      for (std::size_t l = 0; l < stride; ++l) to[l] = l < used ? from[l * delay] : 0.0;
    }
  }
  // The copied coordinates of grid entry q (within the filled range).
  const double* of(std::size_t q) const { return values_.data() + (q - begin_) * stride_; }
  std::size_t begin() const { return begin_; }
  std::size_t stride() const { return stride_; }

 private:
  std::size_t begin_ = 0, stride_ = 0;
  std::vector<double> values_;
};

}  // namespace chatterlab::nonlinear
