#include "runner/run_meta.hpp"

#include <filesystem>

#include "chatterlab/detail/mpi_env.hpp"
#include "chatterlab/input_files.hpp"
#include "runner/build_info.hpp"
#include "runner/results_io.hpp"

namespace chatterlab::runner {

namespace fs = std::filesystem;

Json run_description(const MetaInputs& in) {
  Json run = Json::object();
  run["started_utc"] = in.started_utc;
  run["out_dir"] = fs::absolute(in.options.out_dir).string();
  run["resume"] = in.options.resume;
  if (in.options.resume) run["retry_failed"] = in.options.retry_failed;
  run["ranks"] = mpi_size();
  run["threads_per_rank"] = in.threads;
  if (in.serial) run["serial_reason"] = "a plugin of this study is serial-only";
  run["worker_processes"] = !in.isolation.empty();
  if (!in.isolation.empty()) run["worker_processes_reason"] = in.isolation;
  run["point_timeout_s"] = in.point_timeout_s ? Json(*in.point_timeout_s) : Json();
  return run;
}

Json meta_header(const MetaInputs& in) {
  Json meta = Json::object();
  meta["study_file"] = fs::absolute(in.study.file).string();
  meta["kind"] = in.study.kind;
  meta["study"] = in.study.document;
  Json grid = Json::array();
  for (const auto& axis : in.study.grid)
    grid.push_back({{"key", axis.key}, {"path", axis.path}, {"values", axis.values.size()}});
  meta["grid"] = std::move(grid);
  meta["output_columns"] = in.columns;
  meta["points"] = in.study.point_count();
  Json inputs = Json::array();
  if (in.study.inputs)
    for (const InputFileRecord& file : in.study.inputs->files())
      inputs.push_back({{"path", file.path.string()},
                        {"role", input_role_name(file.role)},
                        {"bytes", file.bytes},
                        {"sha256", file.sha256}});
  meta["inputs"] = std::move(inputs);
  meta["study_fingerprint"] = in.fingerprint;
  meta["build"] = build_info();
  return meta;
}

Json meta_with_state(const MetaInputs& in, const std::string& state) {
  Json meta = meta_header(in);
  meta["state"] = state;
  meta["run"] = run_description(in);
  return meta;
}

Json failed_point(const Study& study, std::size_t point, std::string_view status,
                  double elapsed_s) {
  const PointOutcome outcome = outcome_of(status);
  if (outcome == PointOutcome::ok) return nullptr;
  Json grid = Json::object();
  const std::vector<std::size_t> index = study.point_indices(point);
  for (std::size_t a = 0; a < study.grid.size(); ++a)
    grid[study.grid[a].key] = study.grid[a].values[index[a]];
  Json entry = {{"point", point},
                {"grid", std::move(grid)},
                {"status", outcome == PointOutcome::timeout ? "timeout" : "failed"},
                {"reason", std::string(reason_of(status))}};
  if (outcome == PointOutcome::timeout) entry["elapsed_s"] = elapsed_s;
  return entry;
}

}  // namespace chatterlab::runner
