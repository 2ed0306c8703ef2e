#pragma once
// One rank's journal file for one session (docs/studies.md, "Journal"): a dedicated thread
// writes the finished points' lines every `flush_interval` and fdatasync()s them, so a point is
// on disk within that interval of finishing, whatever the other points do. One point that runs
// for hours cannot hold back the records of the points that finished before it, and computing
// threads never wait for the disk (append() only queues the line).
//
// A write error (disk full) stops journaling but not the run: the results are still complete in
// memory; meta.json reports the error, and --resume will recompute what the journal lacks.
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

namespace chatterlab::runner {

class JournalWriter {
 public:
  // The documented bound on how long a finished point waits before it is written to disk.
  static constexpr std::chrono::milliseconds flush_interval{100};

  // Creates `file` (it must not exist) with `header` written and synced. Throws
  // std::runtime_error naming the file.
  JournalWriter(const std::filesystem::path& file, const std::string& header);
  ~JournalWriter();  // writes what is queued, then stops the thread
  JournalWriter(const JournalWriter&) = delete;
  JournalWriter& operator=(const JournalWriter&) = delete;

  void append(const std::string& line);  // thread-safe, never blocks on I/O
  void flush();                          // writes what is queued now (and waits for it)
  std::string error() const;             // "" while every write succeeded
  // From a fatal-signal handler only (the process is about to die): writes what is queued with
  // plain write(2) calls, unless a thread is appending at this very instant.
  void flush_before_dying() noexcept;

 private:
  void run();
  void write_pending(std::unique_lock<std::mutex>& lock);
  bool write_all(std::string_view text);

  std::filesystem::path file_;
  int fd_ = -1;
  std::string pending_;
  std::string error_;
  bool stop_ = false;
  bool writing_ = false;
  mutable std::mutex mutex_;
  std::condition_variable wake_, written_;
  std::thread thread_;
};

}  // namespace chatterlab::runner
