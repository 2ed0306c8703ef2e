#pragma once
// Fixed-radius neighbour search on a box grid over the first one or two delay coordinates, for
// pair loops that need every neighbour within a radius (kantz_scan walks its rows): cheaper than
// a k-d tree when all neighbours within one radius are wanted.
#include <algorithm>
#include <span>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace chatterlab::nonlinear {

// A box grid over the first `axes` (1 or 2) delay coordinates of x (vectors 0..points-1),
// boxes at least `radius` wide, so the neighbours of a point lie in its own and the adjacent
// boxes. Points are stored box by box as their time indices (4 bytes a point: the coordinates
// are read from x, which must outlive the grid; a copy of them beside each index took 24).
class BoxGrid {
 public:
  BoxGrid(std::span<const double> x, int delay, int axes, std::size_t points, double radius)
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
    std::vector<std::uint32_t> cell_of(points);  // cells <= 2^20
    for (std::size_t j = 0; j < points; ++j) {
      cell_of[j] = std::uint32_t(cell(x[j], axes == 2 ? x[j + delay_] : 0.0));
      ++start_[cell_of[j] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    entries_.resize(points);
    std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t j = 0; j < points; ++j) entries_[fill[cell_of[j]]++] = std::uint32_t(j);
  }
  // Box of a point (its order in the grid's storage).
  std::size_t cell(double a, double b) const {
    return axes_ == 2 ? axis_box(a) * per_axis_ + axis_box(b) : axis_box(a);
  }
  // The time indices of the points, box by box (within a box in time order).
  const std::uint32_t* entries() const { return entries_.data(); }
  // Sorts the points of each row by key[j] (ties by time j): a row is then one stretch along
  // that coordinate, whatever its boxes along the second axis.
  void sort_rows_by(const double* key) {
    for (std::size_t u = 0; u < per_axis_; ++u)
      std::sort(entries_.begin() + std::ptrdiff_t(row_begin(u)),
                entries_.begin() + std::ptrdiff_t(row_begin(u + 1)),
                [key](std::uint32_t a, std::uint32_t b) {
                  return key[a] < key[b] || (key[a] == key[b] && a < b);
                });
  }
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
  std::vector<std::uint32_t> entries_;
};

}  // namespace chatterlab::nonlinear
