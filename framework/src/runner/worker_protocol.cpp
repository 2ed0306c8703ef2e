#include "runner/worker_protocol.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdint>

namespace chatterlab::runner::worker {

namespace {

bool send_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    // MSG_NOSIGNAL: a worker that died must be an error here, not a SIGPIPE that ends the runner.
    ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

bool receive_all(int fd, char* data, std::size_t size) {
  while (size > 0) {
    ssize_t n = ::read(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

bool write_frame(int fd, std::string_view payload) {
  if (payload.size() > UINT32_MAX) return false;
  const auto size = static_cast<std::uint32_t>(payload.size());
  const std::array<char, 4> header = {
      static_cast<char>(size & 0xff), static_cast<char>((size >> 8) & 0xff),
      static_cast<char>((size >> 16) & 0xff), static_cast<char>((size >> 24) & 0xff)};
  return send_all(fd, std::string_view(header.data(), header.size())) && send_all(fd, payload);
}

std::optional<std::string> read_frame(int fd) {
  std::array<unsigned char, 4> header{};
  if (!receive_all(fd, reinterpret_cast<char*>(header.data()), header.size())) return std::nullopt;
  const std::uint32_t size = std::uint32_t{header[0]} | std::uint32_t{header[1]} << 8 |
                             std::uint32_t{header[2]} << 16 | std::uint32_t{header[3]} << 24;
  std::string payload(size, '\0');
  if (!receive_all(fd, payload.data(), payload.size())) return std::nullopt;
  return payload;
}

Json study_to_json(const Study& study) {
  Json grid = Json::array();
  for (const GridAxis& axis : study.grid)
    grid.push_back({{"key", axis.key}, {"path", axis.path}, {"values", axis.values}});
  return {{"file", study.file.string()},
          {"kind", study.kind},
          {"document", study.document},
          {"grid", std::move(grid)},
          {"plugin_libraries", study.plugin_libraries}};
}

Study study_from_json(const Json& json) {
  Study study;
  study.file = json.at("file").get<std::string>();
  study.kind = json.at("kind").get<std::string>();
  study.document = json.at("document");
  for (const Json& axis : json.at("grid")) {
    GridAxis a;
    a.key = axis.at("key").get<std::string>();
    a.path = axis.at("path").get<std::string>();
    a.values.assign(axis.at("values").begin(), axis.at("values").end());
    study.grid.push_back(std::move(a));
  }
  study.plugin_libraries = json.at("plugin_libraries").get<std::vector<std::string>>();
  return study;
}

}  // namespace chatterlab::runner::worker
