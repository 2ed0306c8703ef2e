#pragma once
// Parallel sums whose rounding does not depend on the thread count or the schedule.
//
// Floating-point addition is not associative: a `reduction(+ : x)` clause, or per-thread sums
// merged under `critical`, add the threads' shares in whatever order the threads arrive, and the
// last bits of a result then differ from run to run (Cao's E1 of studies/signal_analysis_lorenz
// moved by 1e-15). Here the work is cut into units fixed by the data alone (never by the number
// of threads), each unit's partial result is computed by one thread in index order, and the
// partials are merged one at a time in unit order: the same additions in the same order
// whichever thread computed which unit.
#include <algorithm>
#include <cstddef>
#include <functional>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

namespace chatterlab::nonlinear {

// The merging side of an ordered reduction, shared by the threads of a parallel region:
//
//     OrderedMerge<Partial> merger(make, merge);
//     #pragma omp parallel        // per-thread scratch here
//     #pragma omp for schedule(dynamic)
//     for (std::size_t unit = 0; unit < units; ++unit) {
//       Partial partial = merger.take();
//       ... compute unit's share into partial ...
//       merger.give(unit, std::move(partial));
//     }
//
// give() parks a partial that is ahead of its predecessors and merges every partial whose
// predecessors are all merged, in unit order, by merge(partial); merge must fold it into the
// result and leave it as make() returns it, since take() hands it out again. Partials held at
// once: about one per thread plus those parked behind a slow unit, not one per unit. Every unit
// 0 .. units - 1 must be given exactly once; the last merge happens in the last give().
template <class Partial>
class OrderedMerge {
 public:
  template <class Make, class Merge>
  OrderedMerge(Make make, Merge merge) : make_(std::move(make)), merge_(std::move(merge)) {}

  Partial take() {
    {
      const std::lock_guard lock(mutex_);
      if (!spare_.empty()) {
        Partial p = std::move(spare_.back());
        spare_.pop_back();
        return p;
      }
    }
    return make_();
  }

  void give(std::size_t unit, Partial&& partial) {
    const std::lock_guard lock(mutex_);
    parked_.emplace(unit, std::move(partial));
    for (auto it = parked_.begin(); it != parked_.end() && it->first == next_;
         it = parked_.erase(it), ++next_) {
      merge_(it->second);
      spare_.push_back(std::move(it->second));
    }
  }

 private:
  std::function<Partial()> make_;
  std::function<void(Partial&)> merge_;
  std::mutex mutex_;
  std::map<std::size_t, Partial> parked_;  // finished ahead of an unfinished predecessor
  std::vector<Partial> spare_;              // merged and reset, ready for another unit
  std::size_t next_ = 0;                    // the next unit to merge
};

// Sum over i < count of what add(i, sum) adds into a Sum (Sum += Sum; `zero` its empty value):
// the indices in blocks of block_size (fixed by the caller, never by the thread count), each
// block summed in index order, the block sums added in block order. Dynamic schedule over the
// blocks. add must not throw (it runs inside an OpenMP loop).
template <class Sum, class Add>
Sum ordered_block_sum(std::size_t count, std::size_t block_size, const Add& add, const Sum& zero = Sum{}) {
  Sum total = zero;
  OrderedMerge<Sum> merger([&] { return zero; }, [&](Sum& s) {
    total += s;
    s = zero;
  });
  const std::size_t blocks = (count + block_size - 1) / block_size;
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t b = 0; b < blocks; ++b) {
    Sum sum = merger.take();
    const std::size_t end = std::min(count, (b + 1) * block_size);
    for (std::size_t i = b * block_size; i < end; ++i) add(i, sum);
    merger.give(b, std::move(sum));
  }
  return total;
}

}  // namespace chatterlab::nonlinear
