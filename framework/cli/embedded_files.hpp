#pragma once
// Files compiled into the `chatterlab` command (cmake/embed_files.cmake): the plugin skeletons of
// `new-plugin` (framework/cli/skeletons/) and the completion scripts (framework/cli/completion/),
// so an installed command needs no data directory to find them.
#include <string_view>
#include <vector>

namespace chatterlab::cli {

struct EmbeddedFile {
  std::string_view path;  // relative to framework/cli, e.g. "skeletons/model/plugin.cpp.in"
  std::string_view content;
};

const std::vector<EmbeddedFile>& embedded_files();
std::string_view embedded_file(std::string_view path);  // logic_error if absent

}  // namespace chatterlab::cli
