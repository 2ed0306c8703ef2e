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

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path)
    : path_(std::move(path)), tmp_(temporary_path_for(path_)) {
  if (path_.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(path_.parent_path(), ec);
    if (ec) {
      note_failed_output_write();
      throw OutputError(fmt::format("cannot create directory {}: {}",
                                    path_.parent_path().string(), ec.message()));
    }
  }
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) fail("create", errno);
}

AtomicFileWriter::~AtomicFileWriter() { abandon(); }

void AtomicFileWriter::abandon() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!tmp_.empty()) {
    std::error_code ignored;
    std::filesystem::remove(tmp_, ignored);
    tmp_.clear();
  }
}

void AtomicFileWriter::fail(const char* what, int err) {
  abandon();
  note_failed_output_write();
  throw OutputError(fmt::format("cannot {} {}: {}", what, path_.string(), std::strerror(err)));
}

void AtomicFileWriter::write(std::string_view content) {
  if (fd_ < 0) throw std::logic_error("AtomicFileWriter: write after commit or failure");
  std::size_t written = 0;
  while (written < content.size()) {
    ssize_t n = ::write(fd_, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail("write", errno);
    written += static_cast<std::size_t>(n);
  }
}

void AtomicFileWriter::commit() {
  if (fd_ < 0) throw std::logic_error("AtomicFileWriter: commit after commit or failure");
  // fsync before rename: after a crash the new name never points at unwritten blocks.
  bool synced = ::fsync(fd_) == 0;
  int err = errno;
  if (::close(fd_) != 0 && synced) {
    synced = false;
    err = errno;
  }
  fd_ = -1;
  if (!synced) fail("write", err);
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) fail("replace", errno);
  tmp_.clear();
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFileWriter file(path);
  file.write(content);
  file.commit();
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
