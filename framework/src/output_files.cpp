// Study files written atomically (chatterlab/output_files.hpp).
#include "chatterlab/output_files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "runner/results_io.hpp"

namespace chatterlab {

namespace {
thread_local std::size_t failed_writes = 0;
}  // namespace

std::size_t failed_output_writes_on_this_thread() { return failed_writes; }
void note_failed_output_write() { ++failed_writes; }

// Unique per process and call: two threads writing files in one directory never share a
// temporary name.
std::filesystem::path temporary_path_for(const std::filesystem::path& path) {
  static std::atomic<unsigned long> counter{0};
  std::filesystem::path tmp = path;
  tmp += fmt::format(".tmp{}.{}", static_cast<long>(::getpid()), counter.fetch_add(1));
  return tmp;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  const std::filesystem::path tmp = temporary_path_for(path);
  if (path.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    if (ec) {
      note_failed_output_write();
      throw OutputError(fmt::format("cannot create directory {}: {}",
                                    path.parent_path().string(), ec.message()));
    }
  }
  auto fail = [&](const char* what) {
    int err = errno;
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    note_failed_output_write();
    throw OutputError(fmt::format("cannot {} {}: {}", what, path.string(), std::strerror(err)));
  };
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("create");
  std::size_t written = 0;
  while (written < content.size()) {
    ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      int err = errno;
      ::close(fd);
      errno = err;
      fail("write");
    }
    written += static_cast<std::size_t>(n);
  }
  // fsync before rename: after a crash the new name never points at unwritten blocks.
  bool synced = ::fsync(fd) == 0;
  int err = errno;
  if (::close(fd) != 0 && synced) {
    synced = false;
    err = errno;
  }
  if (!synced) {
    errno = err;
    fail("write");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) fail("replace");
}

std::string csv_text(const std::vector<std::string>& header,
                     const std::vector<std::vector<double>>& columns) {
  if (columns.size() != header.size())
    throw std::logic_error(fmt::format("csv_text: {} columns for {} header names", columns.size(),
                                       header.size()));
  const std::size_t rows = columns.empty() ? 0 : columns.front().size();
  for (const auto& column : columns)
    if (column.size() != rows) throw std::logic_error("csv_text: columns of different lengths");
  std::string text;
  text.reserve(rows * header.size() * 14 + 64);
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (c) text += ',';
    text += runner::csv_field(header[c]);
  }
  text += '\n';
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c) text += ',';
      fmt::format_to(std::back_inserter(text), "{}", columns[c][r]);
    }
    text += '\n';
  }
  return text;
}

void write_json_file(const std::filesystem::path& path, const Json& value) {
  write_file_atomically(path, runner::json_text(value, 2) + "\n");
}

}  // namespace chatterlab
