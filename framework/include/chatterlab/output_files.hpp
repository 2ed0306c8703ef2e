#pragma once
// Writing a study's files. Everything a run writes goes through write_file_atomically, so a
// killed run never leaves half a file that a reader (or a resumed run) would take for complete.
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

// Writes `content` to a temporary file next to `path` (creating the parent directories), flushes
// it to disk and renames it over `path`: readers see the old or the new file, never a partial
// one, and a failed write (disk full) leaves no temporary file behind. Throws OutputError
// (chatterlab/errors.hpp) naming the file and the reason.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// write_file_atomically for a file written piece by piece (results.csv of a large grid, streamed
// in grid order): the pieces go to a temporary file, commit() flushes it to disk and renames it
// over `path`. Destroyed or abandoned without commit(), it removes the temporary file and leaves
// `path` as it was. Failures throw OutputError (and count as failed output writes).
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  void write(std::string_view content);
  void commit();
  void abandon() noexcept;
  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& temporary_path() const { return tmp_; }

 private:
  [[noreturn]] void fail(const char* what, int err);
  std::filesystem::path path_, tmp_;
  int fd_ = -1;
};

// A temporary name next to `path`, unique per process and call ("<path>.tmp<pid>.<n>"): for
// files written by another program (gnuplot) and renamed into place.
std::filesystem::path temporary_path_for(const std::filesystem::path& path);

// How many output writes have failed on the calling thread so far. The runner compares it before
// and after a grid point or the plots, so an output failure is recognised (exit 3) even when a
// study kind catches the OutputError and rethrows it as something else.
std::size_t failed_output_writes_on_this_thread();
// Counts a failed output write on the calling thread (for writers other than
// write_file_atomically, e.g. the plot service when gnuplot could not write an image).
void note_failed_output_write();

// A CSV table: header line, then one line per row, numbers in shortest round-trip form (the
// same double always prints the same text), "\n" line ends. Every row must have header.size()
// cells (std::logic_error otherwise). Non-finite values print as nan/inf, so check first where
// they would be wrong.
std::string csv_text(const std::vector<std::string>& header,
                     const std::vector<std::vector<double>>& columns);

// Pretty JSON (2-space indent) with round-trip doubles, written atomically.
void write_json_file(const std::filesystem::path& path, const Json& value);

}  // namespace chatterlab
