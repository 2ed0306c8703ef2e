#pragma once
// The input files of a study, read once per run and fingerprinted (docs/studies.md, "Inputs").
//
// Every file a study reads goes through this service: the study file, its plugin libraries, and
// every data file (read_data_table in chatterlab/signal_io.hpp, or read_input_file /
// InputFileStream below). While a study is loaded or run, an InputSnapshot is "current": the
// first read of a file takes its bytes from disk and records their SHA-256; every later read in
// the same run (each grid point, each thread, each worker process) gets exactly those bytes. A
// file replaced while the run goes can therefore never mix old and new data. The hashes go into
// meta.json and the resume fingerprint; the runner compares them with the files on disk while it
// runs (InputSnapshot::poll_changes) and at the end (InputSnapshot::changes), and a difference
// fails the run.
//
// Outside a scope (unit tests calling read_data_table directly) reads go straight to disk.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace chatterlab {

// What a file is to the study. Data files and plugin libraries decide the results: a change
// during the run fails it, and a change before --resume refuses the resume. The study file is
// recorded for provenance only: its resolved contents (not its bytes, which include comments and
// the [study] name) are what the resume fingerprint compares.
enum class InputRole { study, plugin, data };
const char* input_role_name(InputRole role);

struct InputFileRecord {
  std::filesystem::path path;  // absolute, lexically normal: the key of the file
  InputRole role = InputRole::data;
  std::uint64_t bytes = 0;
  std::string sha256;  // 64 lowercase hex digits, as `sha256sum` prints them
};

class InputSnapshot {
 public:
  InputSnapshot();
  ~InputSnapshot();
  InputSnapshot(const InputSnapshot&) = delete;
  InputSnapshot& operator=(const InputSnapshot&) = delete;

  // The file's bytes as this snapshot first read them (reading and hashing them now if this is
  // the first time). nullptr when the file cannot be read, with errno set (nothing is recorded).
  // `keep_bytes` false records the hash only (plugin libraries: the dynamic loader maps them).
  std::shared_ptr<const std::string> read(const std::filesystem::path& file, InputRole role,
                                          bool keep_bytes = true);

  // A value derived from a file's bytes (a parsed table), computed once per snapshot: `parser`
  // names the kind of value. `make` runs outside the lock; if it throws nothing is cached.
  std::shared_ptr<const void> derived(const std::filesystem::path& file, const std::string& parser,
                                      const std::function<std::shared_ptr<const void>()>& make);

  // Every file read so far, sorted by path.
  std::vector<InputFileRecord> files() const;
  // The bytes kept for a file (nullptr for hash-only records and unknown files).
  std::shared_ptr<const std::string> bytes_of(const std::filesystem::path& file) const;

  // Adds a file with known bytes without touching the disk (a worker process receives its
  // parent's snapshot). Throws std::invalid_argument if `bytes` do not hash to record.sha256.
  void add(const InputFileRecord& record, std::shared_ptr<const std::string> bytes);

  // Files (plugin libraries and data; not the study file) whose contents on disk now differ from
  // what the run read, one message each: "<file>: changed since the run read it (sha256 ... then,
  // ... now)" or "<file>: removed ...". Re-reads every file: for the end of a run.
  std::vector<std::string> changes() const;
  // The same, cheap enough to call every second during a run: a file is re-hashed only when its
  // stat (inode, size, modification or change time) differs from the last look.
  std::vector<std::string> poll_changes();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The snapshot reads go through (nullptr: none).
std::shared_ptr<InputSnapshot> current_input_snapshot();

// Makes `snapshot` current for its lifetime and restores the previous one after. One study is
// loaded or run at a time per process (load_study and run_study open these scopes).
class InputScope {
 public:
  explicit InputScope(std::shared_ptr<InputSnapshot> snapshot);
  ~InputScope();
  InputScope(const InputScope&) = delete;
  InputScope& operator=(const InputScope&) = delete;

 private:
  std::shared_ptr<InputSnapshot> previous_;
};

// The key of a file: absolute and lexically normal (symbolic links are not resolved).
std::filesystem::path input_key(const std::filesystem::path& file);

// A file's bytes through the current snapshot (or straight from disk without one); nullptr with
// errno set when it cannot be read.
std::shared_ptr<const std::string> try_read_input_file(const std::filesystem::path& file,
                                                       InputRole role = InputRole::data);

// The same, throwing InputError "<file>: no such file" / "<file>: is a directory, not a data
// file" / "<file>: cannot be opened for reading (<reason>)".
std::shared_ptr<const std::string> read_input_file(const std::filesystem::path& file,
                                                   InputRole role = InputRole::data);

// A value parsed from a data file, parsed once per run: every grid point gets the same object.
template <class T, class Parse>
std::shared_ptr<const T> read_input_parsed(const std::filesystem::path& file,
                                           const std::string& parser, Parse&& parse) {
  std::shared_ptr<const std::string> bytes = read_input_file(file);
  std::shared_ptr<InputSnapshot> snapshot = current_input_snapshot();
  if (!snapshot) return std::make_shared<const T>(parse(*bytes));
  return std::static_pointer_cast<const T>(snapshot->derived(file, parser, [&] {
    return std::static_pointer_cast<const void>(std::make_shared<const T>(parse(*bytes)));
  }));
}

// A drop-in replacement for std::ifstream on an input file: the snapshot's bytes as a stream;
// `!stream` (failbit) when the file cannot be read, as an ifstream would report it.
class InputFileStream : public std::istringstream {
 public:
  explicit InputFileStream(const std::filesystem::path& file, InputRole role = InputRole::data);
};

// SHA-256 of `bytes` as 64 lowercase hex digits (FIPS 180-4).
std::string sha256_hex(std::string_view bytes);

}  // namespace chatterlab
