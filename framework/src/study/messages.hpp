#pragma once
// Pieces of InputError messages shared by parameter validation and study loading, so that every
// message spells values, lists and suggestions the same way.
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab::messages {

// A value as messages show it: nan/inf spelled out (JSON would print null), long values cut.
std::string show(const Json& value);

// "a, b, c" sorted; "(none)" when empty.
std::string sorted_list(std::vector<std::string> names);

// " (did you mean 'damping_ratio'?)" when one of `valid` is a likely misspelling of `wrong`,
// otherwise "".
std::string did_you_mean(std::string_view wrong, const std::vector<std::string>& valid);

// The keys of a JSON object.
std::vector<std::string> keys_of(const Json& object);

}  // namespace chatterlab::messages
