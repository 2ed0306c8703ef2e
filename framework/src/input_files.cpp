// Input files read once per run and fingerprinted (chatterlab/input_files.hpp).
#include "chatterlab/input_files.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include "chatterlab/errors.hpp"

namespace chatterlab {

namespace fs = std::filesystem;

// ------------------------------------------------------------------ SHA-256 (FIPS 180-4)
namespace {

class Sha256 {
 public:
  void update(std::string_view data) {
    for (unsigned char c : data) {
      block_[fill_++] = c;
      if (fill_ == 64) {
        compress();
        fill_ = 0;
      }
    }
    length_ += data.size();
  }

  std::string hex_digest() {
    const std::uint64_t bits = length_ * 8;
    block_[fill_++] = 0x80;
    if (fill_ > 56) {
      while (fill_ < 64) block_[fill_++] = 0;
      compress();
      fill_ = 0;
    }
    while (fill_ < 56) block_[fill_++] = 0;
    for (int i = 7; i >= 0; --i) block_[fill_++] = static_cast<unsigned char>(bits >> (8 * i));
    compress();
    std::string out;
    for (std::uint32_t word : state_) out += fmt::format("{:08x}", word);
    return out;
  }

 private:
  static std::uint32_t rotr(std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

  void compress() {
    static constexpr std::array<std::uint32_t, 64> k = {
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
        0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
        0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
        0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
        0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
        0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
        0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
        0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
        0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2};
    std::array<std::uint32_t, 64> w{};
    for (int i = 0; i < 16; ++i)
      w[i] = std::uint32_t{block_[4 * i]} << 24 | std::uint32_t{block_[4 * i + 1]} << 16 |
             std::uint32_t{block_[4 * i + 2]} << 8 | std::uint32_t{block_[4 * i + 3]};
    for (int i = 16; i < 64; ++i) {
      const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    auto [a, b, c, d, e, f, g, h] = state_;
    for (int i = 0; i < 64; ++i) {
      const std::uint32_t t1 =
          h + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const std::uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      h = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    const std::array<std::uint32_t, 8> add = {a, b, c, d, e, f, g, h};
    for (int i = 0; i < 8; ++i) state_[i] += add[i];
  }

  std::array<std::uint32_t, 8> state_ = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                         0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  std::array<unsigned char, 64> block_{};
  std::size_t fill_ = 0;
  std::uint64_t length_ = 0;
};

// Reads `file` block by block into `on_block`; false with errno set when it cannot be read. A
// directory is EISDIR (open(2) would succeed on it). `on_size` hears a regular file's size first.
template <class OnSize, class OnBlock>
bool read_file_blocks(const fs::path& file, struct stat* info, OnSize on_size, OnBlock on_block) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  auto fail = [fd](int error) {
    ::close(fd);
    errno = error;
    return false;
  };
  if (::fstat(fd, info) != 0) return fail(errno);
  if (S_ISDIR(info->st_mode)) return fail(EISDIR);
  if (S_ISREG(info->st_mode)) on_size(static_cast<std::size_t>(info->st_size));
  std::array<char, 1 << 16> buffer{};
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail(errno);
    if (n == 0) break;
    on_block(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
  }
  ::close(fd);
  return true;
}

// The whole file, or nullptr with errno set.
std::shared_ptr<std::string> read_whole_file(const fs::path& file, struct stat* info) {
  auto bytes = std::make_shared<std::string>();
  if (!read_file_blocks(
          file, info, [&](std::size_t size) { bytes->reserve(size); },
          [&](std::string_view block) { bytes->append(block); }))
    return nullptr;
  return bytes;
}

// The file's sha256 and size, hashed as it is read (a check of a 10^8-sample input must not hold
// a second copy of it); false with errno set.
bool hash_file(const fs::path& file, struct stat* info, std::string& sha256, std::size_t& bytes) {
  Sha256 hash;
  bytes = 0;
  if (!read_file_blocks(
          file, info, [](std::size_t) {},
          [&](std::string_view block) {
            hash.update(block);
            bytes += block.size();
          }))
    return false;
  sha256 = hash.hex_digest();
  return true;
}

bool same_stat(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino && a.st_size == b.st_size &&
         a.st_mtim.tv_sec == b.st_mtim.tv_sec && a.st_mtim.tv_nsec == b.st_mtim.tv_nsec &&
         a.st_ctim.tv_sec == b.st_ctim.tv_sec && a.st_ctim.tv_nsec == b.st_ctim.tv_nsec;
}

std::string short_hash(const std::string& sha256) { return sha256.substr(0, 12); }

std::mutex current_mutex;
std::shared_ptr<InputSnapshot> current;

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  Sha256 hash;
  hash.update(bytes);
  return hash.hex_digest();
}

const char* input_role_name(InputRole role) {
  switch (role) {
    case InputRole::study:
      return "study";
    case InputRole::plugin:
      return "plugin";
    case InputRole::data:
      break;
  }
  return "data";
}

fs::path input_key(const fs::path& file) { return fs::absolute(file).lexically_normal(); }

// ------------------------------------------------------------------ InputSnapshot
struct InputSnapshot::State {
  struct Entry {
    InputFileRecord record;
    std::shared_ptr<const std::string> bytes;
    struct stat seen {};  // the last stat() whose file had the recorded hash
    bool have_stat = false;
  };
  mutable std::mutex mutex;
  std::map<fs::path, Entry> entries;
  std::map<std::pair<fs::path, std::string>, std::shared_ptr<const void>> derived;

  // "" when the file on disk still has the recorded hash, else what changed. Updates `now`.
  static std::string change_of(const Entry& entry, struct stat* now) {
    const InputFileRecord& r = entry.record;
    std::string hash;
    std::size_t bytes = 0;
    if (!hash_file(r.path, now, hash, bytes))
      return fmt::format("{}: can no longer be read ({}) since the run read it", r.path.string(),
                         std::strerror(errno));
    if (hash == r.sha256) return {};
    return fmt::format(
        "{}: changed since the run read it (sha256 {}... then, {}... now; {} bytes then, {} now)",
        r.path.string(), short_hash(r.sha256), short_hash(hash), r.bytes, bytes);
  }
};

InputSnapshot::InputSnapshot() : state_(std::make_unique<State>()) {}
InputSnapshot::~InputSnapshot() = default;

std::shared_ptr<const std::string> InputSnapshot::read(const fs::path& file, InputRole role,
                                                       bool keep_bytes) {
  const fs::path key = input_key(file);
  {
    std::lock_guard lock(state_->mutex);
    auto it = state_->entries.find(key);
    if (it != state_->entries.end() && (it->second.bytes || !keep_bytes)) {
      // A file used in two roles (a data file that is also a plugin?) keeps the stronger one.
      if (role != InputRole::study) it->second.record.role = role;
      return it->second.bytes ? it->second.bytes : std::make_shared<const std::string>();
    }
  }
  // Read outside the lock (files can be large); two threads reading the same new file both hash
  // it and the first to come back wins, so every caller sees the same bytes.
  State::Entry entry;
  std::shared_ptr<std::string> bytes = read_whole_file(key, &entry.seen);
  if (!bytes) return nullptr;
  entry.have_stat = true;
  entry.record = {key, role, bytes->size(), sha256_hex(*bytes)};
  if (keep_bytes) entry.bytes = std::move(bytes);
  std::lock_guard lock(state_->mutex);
  auto [it, inserted] = state_->entries.try_emplace(key, std::move(entry));
  if (!inserted && !it->second.bytes && keep_bytes) it->second = std::move(entry);
  return it->second.bytes ? it->second.bytes : std::make_shared<const std::string>();
}

std::shared_ptr<const void> InputSnapshot::derived(
    const fs::path& file, const std::string& parser,
    const std::function<std::shared_ptr<const void>()>& make) {
  const auto key = std::make_pair(input_key(file), parser);
  {
    std::lock_guard lock(state_->mutex);
    auto it = state_->derived.find(key);
    if (it != state_->derived.end()) return it->second;
  }
  std::shared_ptr<const void> value = make();
  std::lock_guard lock(state_->mutex);
  return state_->derived.try_emplace(key, std::move(value)).first->second;
}

std::vector<InputFileRecord> InputSnapshot::files() const {
  std::lock_guard lock(state_->mutex);
  std::vector<InputFileRecord> out;
  for (const auto& [key, entry] : state_->entries) out.push_back(entry.record);
  return out;
}

std::shared_ptr<const std::string> InputSnapshot::bytes_of(const fs::path& file) const {
  std::lock_guard lock(state_->mutex);
  auto it = state_->entries.find(input_key(file));
  return it == state_->entries.end() ? nullptr : it->second.bytes;
}

void InputSnapshot::add(const InputFileRecord& record, std::shared_ptr<const std::string> bytes) {
  if (bytes && sha256_hex(*bytes) != record.sha256)
    throw std::invalid_argument(
        fmt::format("input snapshot: the bytes given for {} do not match their sha256",
                    record.path.string()));
  State::Entry entry;
  entry.record = record;
  entry.record.path = input_key(record.path);
  entry.bytes = std::move(bytes);
  std::lock_guard lock(state_->mutex);
  state_->entries[entry.record.path] = std::move(entry);
}

std::vector<std::string> InputSnapshot::changes() const {
  std::vector<std::string> out;
  for (const InputFileRecord& record : files()) {
    if (record.role == InputRole::study) continue;
    State::Entry entry;
    entry.record = record;
    struct stat now {};
    if (std::string change = State::change_of(entry, &now); !change.empty())
      out.push_back(std::move(change));
  }
  return out;
}

std::vector<std::string> InputSnapshot::poll_changes() {
  std::vector<std::string> out;
  std::lock_guard lock(state_->mutex);  // held while hashing: only the run's monitor calls this
  for (auto& [key, entry] : state_->entries) {
    if (entry.record.role == InputRole::study) continue;
    struct stat now {};
    if (entry.have_stat && ::stat(key.c_str(), &now) == 0 && same_stat(now, entry.seen)) continue;
    if (std::string change = State::change_of(entry, &now); !change.empty()) {
      out.push_back(std::move(change));
    } else {  // touched or rewritten with the same bytes: remember the new stat
      entry.seen = now;
      entry.have_stat = true;
    }
  }
  return out;
}

// ------------------------------------------------------------------ current snapshot
std::shared_ptr<InputSnapshot> current_input_snapshot() {
  std::lock_guard lock(current_mutex);
  return current;
}

InputScope::InputScope(std::shared_ptr<InputSnapshot> snapshot) {
  std::lock_guard lock(current_mutex);
  previous_ = std::exchange(current, std::move(snapshot));
}

InputScope::~InputScope() {
  std::lock_guard lock(current_mutex);
  current = std::move(previous_);
}

std::shared_ptr<const std::string> try_read_input_file(const fs::path& file, InputRole role) {
  if (std::shared_ptr<InputSnapshot> snapshot = current_input_snapshot())
    return snapshot->read(file, role);
  struct stat info {};
  return read_whole_file(file, &info);
}

std::shared_ptr<const std::string> read_input_file(const fs::path& file, InputRole role) {
  std::shared_ptr<const std::string> bytes = try_read_input_file(file, role);
  if (bytes) return bytes;
  const int error = errno;
  if (error == ENOENT) throw InputError(fmt::format("{}: no such file", file.string()));
  if (error == EISDIR)
    throw InputError(fmt::format("{}: is a directory, not a data file", file.string()));
  throw InputError(fmt::format("{}: cannot be opened for reading ({})", file.string(),
                               std::strerror(error)));
}

InputFileStream::InputFileStream(const fs::path& file, InputRole role) {
  std::shared_ptr<const std::string> bytes = try_read_input_file(file, role);
  if (bytes)
    str(*bytes);
  else
    setstate(std::ios::failbit);
}

}  // namespace chatterlab
