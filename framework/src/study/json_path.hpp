#pragma once
// Dotted paths into a study document: "model.modes.0.damping_ratio" (object keys and list
// indices separated by dots).
#include <string>
#include <string_view>

#include "chatterlab/params.hpp"

namespace chatterlab {

// The value at `path`, or nullptr with `problem` saying which part does not exist and what does
// exist there ("model.modes has 1 entry (index 0); there is no index 5").
const Json* find_at_path(const Json& document, std::string_view path, std::string& problem);
Json* find_at_path(Json& document, std::string_view path, std::string& problem);

}  // namespace chatterlab
