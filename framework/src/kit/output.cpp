// Study kit: a point's output files (chatterlab/kit/output.hpp).
#include "chatterlab/kit/output.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string_view>

namespace chatterlab::kit {

void write_table(const PointContext& context, const std::string& name,
                 const std::vector<std::string>& header,
                 const std::vector<std::vector<double>>& columns) {
  if (context.artifact_dir.empty()) return;
  write_file_atomically(context.artifact_dir / name, csv_text(header, columns));
}

void write_summary(const PointContext& context, const Json& summary) {
  if (context.artifact_dir.empty()) return;
  write_json_file(context.artifact_dir / "summary.json", summary);
}

void write_csv_streamed(const std::filesystem::path& path, const std::vector<std::string>& header,
                        std::size_t rows,
                        const std::function<void(std::size_t row, std::span<double> cells)>& fill_row) {
  // Each block goes through csv_text itself (its header line dropped after the first), so the
  // numbers print exactly as in a table written whole.
  constexpr std::size_t rows_per_block = 16384;
  AtomicFileWriter out(path);
  std::vector<std::vector<double>> columns(header.size());
  std::vector<double> cells(header.size());
  std::size_t begin = 0;
  do {
    const std::size_t end = std::min(rows, begin + rows_per_block);
    for (auto& column : columns) column.clear();
    for (std::size_t r = begin; r < end; ++r) {
      fill_row(r, cells);
      for (std::size_t c = 0; c < cells.size(); ++c) columns[c].push_back(cells[c]);
    }
    const std::string text = csv_text(header, columns);
    out.write(begin == 0 ? std::string_view(text) : std::string_view(text).substr(text.find('\n') + 1));
    begin = end;
  } while (begin < rows);
  out.commit();
}

ParamSpec OnRequestFile::spec() const {
  ParamSpec spec = param_spec(
      key, ValueKind::string, "1",
      fmt::format("write {}: auto (inputs of up to {} samples), always or never", contents, auto_samples));
  spec.default_value = "auto";
  spec.choices = {"auto", "always", "never"};
  return spec;
}

std::optional<std::string> OnRequestFile::skipped(const std::string& choice, std::size_t samples) const {
  if (choice == "always" || (choice == "auto" && samples <= auto_samples)) return std::nullopt;
  const std::string path = table + "." + key;
  return fmt::format("not written: {} samples{} ({} = \"always\" writes it)", samples,
                     choice == "never" ? fmt::format(", {} = \"never\"", path)
                                       : fmt::format(" > {} ({} = \"auto\")", auto_samples, path),
                     path);
}

}  // namespace chatterlab::kit
