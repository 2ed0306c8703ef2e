#include "runner/output_dir.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>

#include "chatterlab/errors.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view journal_prefix = "points-";
constexpr std::string_view journal_suffix = ".jsonl";

constexpr const char* marker_text =
    "This directory holds the output of a chatterlab study run (results.csv, meta.json, plots,\n"
    "journal/). Running a study into it again without --resume replaces its contents.\n";

[[noreturn]] void unusable(const fs::path& dir, const std::string& why) {
  throw InputError(fmt::format("output directory {}: {}", dir.string(), why));
}

// Session number of a journal file name, or -1 for other names.
int journal_session(const std::string& name) {
  if (name.size() <= journal_prefix.size() + journal_suffix.size() ||
      name.compare(0, journal_prefix.size(), journal_prefix) != 0 ||
      name.compare(name.size() - journal_suffix.size(), journal_suffix.size(), journal_suffix) != 0)
    return -1;
  int session = -1;
  const char* begin = name.data() + journal_prefix.size();
  auto [end, ec] = std::from_chars(begin, name.data() + name.size(), session);
  if (ec != std::errc() || *end != '-') return -1;
  return session;
}

}  // namespace

std::unique_ptr<OutputLock> prepare_output_dir(const fs::path& dir, bool resume,
                                               const std::string& study_file) {
  std::error_code ec;
  fs::file_status status = fs::status(dir, ec);
  if (fs::exists(status) && !fs::is_directory(status))
    unusable(dir, "exists and is not a directory");
  if (!fs::exists(status)) {
    fs::create_directories(dir, ec);
    if (ec) unusable(dir, "cannot be created: " + ec.message());
  }
  // chatterlab's own hidden files (the lock, the marker being written under a temporary name)
  // do not make a directory someone else's: a run that starts at the same instant may have
  // created them a moment ago, and must then hear about that run, not about foreign files. The
  // marker is looked for after the listing: a run writes it before any other file, so whatever
  // the listing saw of that run, its marker is there by now.
  bool empty = true;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().filename().string().rfind(".chatterlab-", 0) != 0) empty = false;
  if (ec) unusable(dir, "cannot be read: " + ec.message());
  const fs::path marker = dir / output_marker_name;
  const bool ours = fs::exists(marker, ec);
  if (!ours && !empty)
    unusable(dir, fmt::format("is not empty and was not written by chatterlab (no {} file); "
                              "choose a new or empty directory with --out",
                              output_marker_name));
  // Before anything is changed: a second run into a directory in use must leave it untouched.
  auto lock = std::make_unique<OutputLock>(dir, study_file);
  // Writing the marker is the writability probe: it happens before any computation and before a
  // previous run is deleted.
  try {
    write_file_atomically(marker, marker_text);
  } catch (const std::exception& e) {
    unusable(dir, std::string("is not writable: ") + e.what());
  }
  if (resume) return lock;
  std::vector<fs::path> previous;  // listed first: removing while iterating is unspecified
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().filename() != output_marker_name &&
        entry.path().filename() != output_lock_name)
      previous.push_back(entry.path());
  if (ec) unusable(dir, "cannot be listed: " + ec.message());
  for (const auto& path : previous) {
    fs::remove_all(path, ec);
    if (ec)
      unusable(dir, fmt::format("cannot remove the previous run's {}: {}", path.filename().string(),
                                ec.message()));
  }
  return lock;
}

fs::path journal_dir(const fs::path& out_dir) { return out_dir / "journal"; }

fs::path point_artifact_dir(const fs::path& out_dir, std::size_t point, std::size_t point_count) {
  if (point_count <= 1) return out_dir;
  return out_dir / "points" / fmt::format("{:06}", point);
}

fs::path journal_file(const fs::path& out_dir, int session, int rank) {
  return journal_dir(out_dir) /
         fmt::format("{}{}-{}{}", journal_prefix, session, rank, journal_suffix);
}

std::vector<fs::path> journal_files(const fs::path& out_dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(journal_dir(out_dir), ec))
    if (entry.is_regular_file() && journal_session(entry.path().filename().string()) >= 0)
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

int next_journal_session(const fs::path& out_dir) {
  int last = 0;
  for (const auto& file : journal_files(out_dir))
    last = std::max(last, journal_session(file.filename().string()));
  return last + 1;
}

}  // namespace chatterlab::runner
