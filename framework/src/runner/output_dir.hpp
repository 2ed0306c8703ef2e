#pragma once
// The study output directory: who owns it, how a new run replaces an old one, where journals go.
//
// Policy (docs/studies.md, "Output directory"): chatterlab marks every directory it writes with a
// `.chatterlab-output` file. A run without --resume into a marked directory deletes the previous
// run's files first (a clean replacement: no stale plots or journals from another grid survive).
// A non-empty directory WITHOUT the mark is refused (InputError), so a mistyped --out can never
// wipe a user's own files. With --resume the directory is kept and its journals are read. One
// run at a time: the run holds an OutputLock on the directory from before it changes anything
// until its last file is written.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "runner/output_lock.hpp"

namespace chatterlab::runner {

inline constexpr const char* output_marker_name = ".chatterlab-output";
// Space set aside while a run goes, given back to write meta.json when the disk fills up.
inline constexpr const char* output_reserve_name = ".chatterlab-reserve";

// Creates or checks `dir`, locks it (the returned lock must live until the run's last write) and
// proves it writable by writing the marker; without `resume` removes a previous run. Throws
// InputError with the directory and the reason; touches nothing when the directory is unusable,
// not ours, or locked by another run.
std::unique_ptr<OutputLock> prepare_output_dir(const std::filesystem::path& dir, bool resume,
                                               const std::string& study_file);

std::filesystem::path journal_dir(const std::filesystem::path& out_dir);

// PointContext::artifact_dir: out_dir itself for a one-point study, else out_dir/points/NNNNNN.
std::filesystem::path point_artifact_dir(const std::filesystem::path& out_dir, std::size_t point,
                                         std::size_t point_count);

// Journal files of earlier sessions, sorted by name: journal/points-<session>-<rank>.jsonl.
// Every run (and every resume) writes new files, so an old file cut by a kill is never appended to.
std::vector<std::filesystem::path> journal_files(const std::filesystem::path& out_dir);
std::filesystem::path journal_file(const std::filesystem::path& out_dir, int session, int rank);
int next_journal_session(const std::filesystem::path& out_dir);

}  // namespace chatterlab::runner
