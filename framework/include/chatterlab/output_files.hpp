#pragma once
// Writing a study's files. Everything a run writes goes through write_file_atomically, so a
// killed run never leaves half a file that a reader (or a resumed run) would take for complete.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

// Writes `content` to a temporary file next to `path` (creating the parent directories), flushes
// it to disk and renames it over `path`: readers see the old or the new file, never a partial
// one. Throws std::runtime_error naming the file.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// A CSV table: header line, then one line per row, numbers in shortest round-trip form (the
// same double always prints the same text), "\n" line ends. Every row must have header.size()
// cells (std::logic_error otherwise). Non-finite values print as nan/inf, so check first where
// they would be wrong.
std::string csv_text(const std::vector<std::string>& header,
                     const std::vector<std::vector<double>>& columns);

// Pretty JSON (2-space indent) with round-trip doubles, written atomically.
void write_json_file(const std::filesystem::path& path, const Json& value);

}  // namespace chatterlab
