// Study kit: a point's output files (chatterlab/kit/output.hpp).
#include "chatterlab/kit/output.hpp"

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

}  // namespace chatterlab::kit
