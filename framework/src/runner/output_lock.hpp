#pragma once
// The lock that gives one run at a time an output directory (docs/studies.md, "Output
// directory"). An OS lock, flock(2) on DIR/.chatterlab-lock: the kernel releases it however the
// holder ends (exit, crash, kill -9), so a lock is never stale, and a killed run can be resumed
// at once. The file holds the holder's PID, host, start time and study, for the message a second
// run gets. The file itself stays (removing it would let two runs lock two different files).
#include <filesystem>
#include <memory>
#include <string>

namespace chatterlab::runner {

inline constexpr const char* output_lock_name = ".chatterlab-lock";

class OutputLock {
 public:
  // Locks `dir` (an existing directory), creating the lock file if needed. Throws InputError
  // naming the holder ("... is in use by another chatterlab run: PID 1234 on host x, running
  // /path/study.toml since ...") when another process holds it; then nothing was changed. On a
  // file system without locks it warns on stderr and goes on unlocked.
  OutputLock(const std::filesystem::path& dir, const std::string& study_file);
  ~OutputLock();  // releases the lock
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  int fd_ = -1;
};

// "PID 1234 on host x, running /path/study.toml since 2026-01-01T12:00:00Z", from a lock file's
// contents; "" when they are empty or unreadable.
std::string describe_lock_holder(const std::string& lock_file_text);

}  // namespace chatterlab::runner
