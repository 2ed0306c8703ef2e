#include "study/source_map.hpp"

namespace chatterlab {

SourceLocation LineSourceMap::locate(std::string_view dotted_path) const {
  std::string path(dotted_path);
  while (!path.empty()) {
    if (auto it = lines_.find(path); it != lines_.end()) return {file_, it->second};
    auto dot = path.rfind('.');
    path.resize(dot == std::string::npos ? 0 : dot);
  }
  return {file_, 0};
}

bool path_within(std::string_view path, std::string_view prefix) {
  return path.size() >= prefix.size() && path.substr(0, prefix.size()) == prefix &&
         (path.size() == prefix.size() || path[prefix.size()] == '.');
}

SourceLocation OverlaySourceMap::locate(std::string_view dotted_path) const {
  return path_within(dotted_path, path_) ? where_ : base_.locate(dotted_path);
}

}  // namespace chatterlab
