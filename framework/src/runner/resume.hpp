#pragma once
// --resume: which points an earlier run into the same directory finished (docs/studies.md,
// "--resume"), and why a resume is refused when they belong to another computation.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <filesystem>
#include <utility>
#include <vector>

#include "chatterlab/study.hpp"
#include "runner/results_hdf5.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

// The points an earlier run finished, found without holding them: a bit per point (taken over
// or not, ok or not) and, for a record in a journal, its place there (8 bytes); the records
// themselves are read again, in grid order, when results are written (take()). So a --resume of
// a 10^6-point run holds about 1 MB where the points' results would take 500 MB.
class ResumedPoints {
 public:
  explicit ResumedPoints(std::size_t points = 0);
  ~ResumedPoints();
  ResumedPoints(ResumedPoints&&) noexcept;
  ResumedPoints& operator=(ResumedPoints&&) noexcept;

  std::size_t count() const { return count_; }  // points taken over
  bool has(std::size_t point) const { return point < done_.size() && done_[point]; }
  // The record of a point taken over, read from its journal or results.h5. Points must be
  // taken in increasing order, each once (std::logic_error otherwise: that is what lets the
  // reads stream). Throws std::runtime_error when the file cannot be read back.
  PointResult take(std::size_t point);
  // Records read ahead and not yet taken (at most one chunk row of results.h5).
  std::size_t buffered_records() const { return h5_row_.size() - h5_row_next_; }

  std::size_t truncated_lines = 0;  // journal lines cut by a kill
  std::size_t invalid_lines = 0;    // journal lines that are not a record (recomputed)

 private:
  friend class ResumeScan;
  struct JournalCursor;
  std::vector<bool> done_, ok_;
  // Per point, where its record is when some record comes from a journal (else empty): none,
  // results.h5, or (journal index + 1) << 48 | byte offset of its line.
  std::vector<std::uint64_t> location_;
  std::size_t count_ = 0;
  std::size_t columns_ = 0;
  std::filesystem::path results_h5_;  // empty: none
  std::vector<std::unique_ptr<JournalCursor>> journals_;
  std::unique_ptr<Hdf5ResultsReader> h5_;
  std::vector<PointResult> h5_row_;  // the chunk row of results.h5 being taken
  // results.h5 keeps a timeout's status, not how long it ran: the completed run's meta.json
  // (failed_points) does. Point -> elapsed_s, timeouts only (few: each took a whole limit).
  std::vector<std::pair<std::size_t, double>> h5_timeout_elapsed_s_;
  std::size_t h5_row_first_ = 0, h5_row_next_ = 0;
  std::size_t next_ = 0;  // the lowest point take() accepts
};

// Scans every journal in `out_dir` (streaming, one line at a time). Per point, an ok record
// wins over a failed one, else the latest session's; with `retry_failed`, failed and timed-out
// points are not taken over (they are computed again). Throws InputError naming the journal and
// what changed (an input file and its hashes, or the first study value that differs from the
// earlier run's meta.json) when a journal was written for another computation.
ResumedPoints read_journals(const std::filesystem::path& out_dir, const JournalHeader& expected,
                            const Study& study, bool retry_failed);

// What --resume takes over: the points of results.h5 when a complete HDF5 run left one (its
// journal was removed, [output] keep_journal = false), overlaid by the journals of the sessions
// since (a --retry-failed that was interrupted); else the journals alone. The same checks and
// `retry_failed` as read_journals.
ResumedPoints read_resumable_points(const std::filesystem::path& out_dir,
                                    const JournalHeader& expected, const Study& study,
                                    bool retry_failed);

// The first place where two JSON values differ, as "model.work_speed_rpm: 55 then, 60 now"
// ("" when equal). Keys are compared in sorted order.
std::string first_difference(const Json& then, const Json& now, const std::string& path = "");

}  // namespace chatterlab::runner
