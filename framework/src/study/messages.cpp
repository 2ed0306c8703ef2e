#include "study/messages.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

namespace chatterlab::messages {

std::string show(const Json& value) {
  if (value.is_number_float()) {
    double d = value.get<double>();
    if (std::isnan(d)) return "nan";
    if (std::isinf(d)) return d > 0 ? "inf" : "-inf";
    return fmt::format("{}", d);
  }
  std::string text = value.dump();
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

std::string sorted_list(std::vector<std::string> names) {
  if (names.empty()) return "(none)";
  std::sort(names.begin(), names.end());
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

namespace {
// Case-insensitive Levenshtein distance; keys are short, so the O(n m) table is fine.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), std::size_t{0});
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      std::size_t above = row[j];
      bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                  std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (same ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}
}  // namespace

std::string did_you_mean(std::string_view wrong, const std::vector<std::string>& valid) {
  const std::string* best = nullptr;
  std::size_t best_distance = 0;
  for (const auto& candidate : valid) {
    std::size_t d = edit_distance(wrong, candidate);
    // A third of the longer name catches typos without suggesting unrelated short keys; a
    // prefix catches a dropped unit suffix ("stiffness" for "stiffness_n_per_m").
    std::size_t tolerance = std::max<std::size_t>(2, std::max(wrong.size(), candidate.size()) / 3);
    std::string_view shorter = wrong.size() < candidate.size() ? wrong : std::string_view(candidate);
    std::string_view longer = wrong.size() < candidate.size() ? std::string_view(candidate) : wrong;
    bool prefix = shorter.size() >= 4 && longer.substr(0, shorter.size()) == shorter;
    if (d == 0 || (d > tolerance && !prefix)) continue;
    if (best == nullptr || d < best_distance) best = &candidate, best_distance = d;
  }
  return best == nullptr ? std::string() : fmt::format(" (did you mean '{}'?)", *best);
}

std::vector<std::string> keys_of(const Json& object) {
  std::vector<std::string> keys;
  if (object.is_object())
    for (const auto& item : object.items()) keys.push_back(item.key());
  return keys;
}

}  // namespace chatterlab::messages
