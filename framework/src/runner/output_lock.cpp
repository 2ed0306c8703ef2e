#include "runner/output_lock.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <iostream>
#include <thread>

#include "chatterlab/errors.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

namespace fs = std::filesystem;

namespace {

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

std::string read_fd(int fd) {
  std::string text;
  char buffer[4096];
  for (off_t offset = 0;;) {
    ssize_t n = ::pread(fd, buffer, sizeof buffer, offset);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    offset += n;
  }
  return text;
}

}  // namespace

std::string describe_lock_holder(const std::string& text) {
  Json j = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object() || !j.contains("pid")) return {};
  return fmt::format("PID {} on host {}, running {} since {}", j.value("pid", 0),
                     j.value("host", std::string("?")), j.value("study_file", std::string("?")),
                     j.value("started_utc", std::string("?")));
}

OutputLock::OutputLock(const fs::path& dir, const std::string& study_file) {
  const fs::path file = dir / output_lock_name;
  // O_CLOEXEC: gnuplot and worker processes (exec'd) never inherit the lock.
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw InputError(fmt::format("output directory {}: cannot create its lock file: {}",
                                 dir.string(), std::strerror(errno)));
  int rc;
  do rc = ::flock(fd_, LOCK_EX | LOCK_NB);
  while (rc != 0 && errno == EINTR);
  if (rc != 0) {
    const int error = errno;
    if (error != EWOULDBLOCK) {
      // A file system without locks (some network and FUSE mounts): run, but say what is lost.
      std::cerr << fmt::format(
          "chatterlab: warning: output directory {}: cannot lock {} ({}): a second run into "
          "this directory at the same time would not be stopped\n",
          dir.string(), file.string(), std::strerror(error));
      return;
    }
    // Held. A holder that has only just taken the lock may not have written its details yet:
    // wait up to a second for them.
    std::string holder;
    for (int attempt = 0; attempt < 20 && holder.empty(); ++attempt) {
      holder = describe_lock_holder(read_fd(fd_));
      if (holder.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ::close(fd_);
    throw InputError(fmt::format(
        "output directory {} is in use by another chatterlab run ({}); nothing was changed: wait "
        "for that run to end (or stop it) and run again, or choose another --out",
        dir.string(), holder.empty() ? "it has not written its PID yet" : holder));
  }
  const std::string details =
      json_text(Json{{"pid", static_cast<long>(::getpid())},
                     {"host", host_name()},
                     {"started_utc", utc_now()},
                     {"study_file", fs::absolute(study_file).string()}}) +
      "\n";
  // Best effort: the lock is what excludes others; the details only make the message useful.
  if (::ftruncate(fd_, 0) == 0) {
    ssize_t written = ::pwrite(fd_, details.data(), details.size(), 0);
    (void)written;
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the only descriptor releases the flock
}

}  // namespace chatterlab::runner
