#pragma once
// Study kit: the files a grid point writes into its artefact directory (PointContext): tables and
// the summary. Nothing is written when the context has no directory (unit tests, benchmarks).
#include <filesystem>
#include <string>
#include <vector>

#include "chatterlab/output_files.hpp"
#include "chatterlab/params.hpp"
#include "chatterlab/study_kind.hpp"

namespace chatterlab::kit {

// <artifact_dir>/<name>: a CSV table of numeric columns (csv_text), written atomically.
void write_table(const PointContext& context, const std::string& name,
                 const std::vector<std::string>& header,
                 const std::vector<std::vector<double>>& columns);

// <artifact_dir>/summary.json, written atomically.
void write_summary(const PointContext& context, const Json& summary);

}  // namespace chatterlab::kit
