#pragma once
// --resume: which points an earlier run into the same directory finished (docs/studies.md,
// "--resume"), and why a resume is refused when they belong to another computation.
#include <cstddef>
#include <filesystem>
#include <utility>
#include <vector>

#include "chatterlab/study.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

struct ResumedPoints {
  std::vector<std::pair<std::size_t, PointResult>> records;  // one per point taken over
  std::size_t truncated_lines = 0;
  std::size_t invalid_lines = 0;
};

// Reads every journal in `out_dir`. Per point, an ok record wins over a failed one, else the
// latest session's; with `retry_failed`, failed and timed-out points are not taken over (they are
// computed again). Throws InputError naming the journal and what changed (an input file and its
// hashes, or the first study value that differs from the earlier run's meta.json) when a journal
// was written for another computation.
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
