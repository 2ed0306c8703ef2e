#include "runner/journal_writer.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace chatterlab::runner {

JournalWriter::JournalWriter(const std::filesystem::path& file, const std::string& header)
    : file_(file) {
  fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0 || !write_all(header) || ::fdatasync(fd_) != 0) {
    const int error = errno;
    if (fd_ >= 0) {  // no empty or half-written journal is left behind
      ::close(fd_);
      ::unlink(file.c_str());
    }
    throw std::runtime_error(
        fmt::format("cannot write {}: {}", file.string(), std::strerror(error)));
  }
  thread_ = std::thread([this] { run(); });
}

JournalWriter::~JournalWriter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
  ::close(fd_);
}

void JournalWriter::append(const std::string& line) {
  std::lock_guard lock(mutex_);
  pending_ += line;
}

void JournalWriter::flush() {
  std::unique_lock lock(mutex_);
  // The thread may be writing an earlier batch: wait for it, then write the rest here.
  written_.wait(lock, [this] { return !writing_; });
  write_pending(lock);
}

std::string JournalWriter::error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void JournalWriter::flush_before_dying() noexcept {
  if (!mutex_.try_lock()) return;  // left locked: nothing may run after this but the death
  if (error_.empty() && write_all(pending_)) ::fdatasync(fd_);
}

void JournalWriter::run() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    wake_.wait_for(lock, flush_interval, [this] { return stop_; });
    if (!writing_) write_pending(lock);
  }
  written_.wait(lock, [this] { return !writing_; });
  write_pending(lock);
}

// Called with the lock held; releases it during the system calls so appends go on meanwhile.
void JournalWriter::write_pending(std::unique_lock<std::mutex>& lock) {
  if (pending_.empty() || !error_.empty()) return;
  std::string batch;
  batch.swap(pending_);
  writing_ = true;
  lock.unlock();
  // fdatasync: on the device, not only in the page cache, so a power cut loses no more than a
  // crash of the process does.
  const bool ok = write_all(batch) && ::fdatasync(fd_) == 0;
  const int error = errno;
  lock.lock();
  writing_ = false;
  if (!ok && error_.empty())
    error_ = fmt::format("journal {} not written: {}", file_.string(), std::strerror(error));
  written_.notify_all();
}

bool JournalWriter::write_all(std::string_view text) {
  while (!text.empty()) {
    ssize_t n = ::write(fd_, text.data(), text.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

}  // namespace chatterlab::runner
