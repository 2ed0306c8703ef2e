#include "runner/shards.hpp"

#include <fmt/format.h>

#include <charconv>
#include <map>

#include "chatterlab/detail/mpi_env.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/shards.hpp"
#include "runner/output_dir.hpp"
#include "runner/resume.hpp"

namespace chatterlab {

namespace fs = std::filesystem;

namespace runner {

bool in_shard(std::size_t point, const ShardSpec& shard) {
  return point % shard.count == shard.index - 1;
}

std::size_t shard_point_count(std::size_t points, const ShardSpec& shard) {
  return points / shard.count + (points % shard.count >= shard.index ? 1 : 0);
}

std::vector<std::size_t> points_to_compute(const std::string& done,
                                           const std::optional<ShardSpec>& shard) {
  std::vector<std::size_t> todo;
  for (std::size_t p = 0; p < done.size(); ++p)
    if (done[p] == '0' && (!shard || in_shard(p, *shard))) todo.push_back(p);
  return todo;
}

void check_shard(const ShardSpec& shard, std::size_t points, const std::string& study_file) {
  if (shard.count > points)
    throw InputError(fmt::format(
        "--shard {}/{}: {} has {} grid point(s), so at most {} shard(s) (each shard must hold a "
        "point)",
        shard.index, shard.count, study_file, points, points));
}

ShardOutcome write_shard_meta(const MetaInputs& in, const std::vector<PointResult>& results,
                              const ShardRun& run) {
  const ShardSpec& shard = *in.options.shard;
  ShardOutcome outcome;
  outcome.output_error = run.output_error;
  Json failed = Json::array();
  for (std::size_t p = 0; p < results.size(); ++p) {
    if (!in_shard(p, shard) || !results[p].done) continue;
    const PointOutcome o = outcome_of(results[p].status);
    if (o == PointOutcome::ok) continue;
    ++outcome.failed;
    if (o == PointOutcome::timeout) ++outcome.timed_out;
    failed.push_back({{"point", p},
                      {"status", o == PointOutcome::timeout ? "timeout" : "failed"},
                      {"reason", std::string(reason_of(results[p].status))}});
  }
  Json meta = meta_header(in);
  meta["state"] = outcome.output_error.empty() ? state_shard_complete : state_output_failed;
  if (!outcome.output_error.empty()) meta["output_error"] = outcome.output_error;
  meta["shard"] = {{"index", shard.index},
                   {"count", shard.count},
                   {"points", shard_point_count(results.size(), shard)}};
  meta["points_failed"] = outcome.failed;
  meta["points_timed_out"] = outcome.timed_out;
  meta["failed_points"] = std::move(failed);
  Json description = run_description(in);
  description["journal_session"] = run.session;
  description["points_resumed"] = run.resumed;
  description["points_computed"] = run.computed;
  if (!run.journal_errors.empty()) description["journal_errors"] = run.journal_errors;
  meta["run"] = std::move(description);
  meta["timings"] = {{"wall_s", run.wall_s}, {"compute_s", run.compute_s}};
  std::error_code ignored;
  fs::remove(in.options.out_dir / output_reserve_name, ignored);
  try {
    write_file_atomically(in.options.out_dir / "meta.json", json_text(meta, 2) + "\n");
  } catch (const std::exception& e) {
    if (outcome.output_error.empty()) outcome.output_error = e.what();
  }
  return outcome;
}

}  // namespace runner

ShardSpec parse_shard(std::string_view text) {
  const auto fail = [&](const std::string& why) -> ShardSpec {
    throw InputError(fmt::format("--shard {}: {}", text, why));
  };
  const std::size_t slash = text.find('/');
  const auto number = [](std::string_view digits, std::size_t& value) {
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string_view::npos)
      return false;
    auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    return ec == std::errc() && end == digits.data() + digits.size();
  };
  ShardSpec shard;
  if (slash == std::string_view::npos || !number(text.substr(0, slash), shard.index) ||
      !number(text.substr(slash + 1), shard.count))
    return fail("expected I/N, two whole numbers with 1 <= I <= N (e.g. --shard 3/8 for the third "
                "of eight shards)");
  if (shard.count < 1) return fail("the number of shards N must be at least 1");
  if (shard.index < 1 || shard.index > shard.count)
    return fail(fmt::format("the shard number I must be between 1 and N = {}", shard.count));
  return shard;
}

namespace {

struct ShardDir {
  fs::path dir;
  Json meta;
  ShardSpec spec;
};

ShardDir read_shard(const fs::path& dir) {
  ShardDir shard{dir, {}, {}};
  const fs::path meta_file = dir / "meta.json";
  if (!fs::exists(meta_file))
    throw InputError(fmt::format("shard {}: no meta.json (not the output directory of a "
                                 "`chatterlab run --shard` that has started)",
                                 dir.string()));
  try {
    shard.meta = Json::parse(runner::read_file(meta_file));
  } catch (const std::exception& e) {
    throw InputError(fmt::format("shard {}: meta.json cannot be read: {}", dir.string(), e.what()));
  }
  const std::string state = shard.meta.value("state", "");
  if (!shard.meta.contains("shard") || !shard.meta["shard"].is_object())
    throw InputError(fmt::format("shard {}: meta.json has no \"shard\" field (state {}): the "
                                 "directory holds a whole run, not a shard (run with --shard I/N)",
                                 dir.string(), state));
  shard.spec.index = shard.meta["shard"].value("index", std::size_t{0});
  shard.spec.count = shard.meta["shard"].value("count", std::size_t{0});
  if (state != runner::state_shard_complete)
    throw InputError(fmt::format(
        "shard {} (shard {}/{}): meta.json says state \"{}\", not \"{}\": complete it first "
        "(chatterlab run STUDY --shard {}/{} --out {} --resume)",
        dir.string(), shard.spec.index, shard.spec.count, state, runner::state_shard_complete,
        shard.spec.index, shard.spec.count, dir.string()));
  return shard;
}

// The meta.json fields that must agree between the shards of one study.
void check_same_study(const ShardDir& first, const ShardDir& other) {
  for (const char* field : {"study_fingerprint", "kind", "points", "grid", "output_columns",
                            "inputs", "build"}) {
    const Json a = first.meta.value(field, Json()), b = other.meta.value(field, Json());
    if (a == b) continue;
    std::string detail = runner::first_difference(a, b, field);
    throw InputError(fmt::format(
        "shard {} does not belong with shard {}: meta.json field {} differs ({}; the first value "
        "is {}'s). Shards must come from the same study file, inputs and chatterlab build",
        other.dir.string(), first.dir.string(), field, detail, first.dir.string()));
  }
  if (other.spec.count != first.spec.count)
    throw InputError(fmt::format(
        "shard {} is shard {}/{}, shard {} is shard {}/{}: they split the grid into different "
        "numbers of shards (meta.json field shard.count)",
        other.dir.string(), other.spec.index, other.spec.count, first.dir.string(),
        first.spec.index, first.spec.count));
}

// The shard's journals hold every point of its slice, and no other point.
std::vector<fs::path> check_points(const ShardDir& shard) {
  const std::size_t points = shard.meta["points"].get<std::size_t>();
  const std::string fingerprint = shard.meta["study_fingerprint"].get<std::string>();
  std::vector<char> seen(points, 0);
  std::vector<fs::path> journals = runner::journal_files(shard.dir);
  for (const fs::path& file : journals) {
    runner::JournalContents journal = runner::parse_journal(runner::read_file(file));
    if (!journal.header_found) continue;
    if (journal.header.study_fingerprint != fingerprint)
      throw InputError(fmt::format("shard {}: journal {} was written for another study than its "
                                   "meta.json (study_fingerprint differs)",
                                   shard.dir.string(), file.string()));
    for (const auto& [point, record] : journal.records) {
      if (!runner::in_shard(point, shard.spec))
        throw InputError(fmt::format(
            "shard {} (shard {}/{}) holds point {}, which belongs to shard {}/{}: the shards "
            "overlap (was the directory reused for another shard?)",
            shard.dir.string(), shard.spec.index, shard.spec.count, point,
            point % shard.spec.count + 1, shard.spec.count));
      seen[point] = 1;
    }
  }
  std::size_t missing = 0, first_missing = points;
  for (std::size_t p = shard.spec.index - 1; p < points; p += shard.spec.count)
    if (!seen[p]) {
      ++missing;
      first_missing = std::min(first_missing, p);
    }
  if (missing > 0)
    throw InputError(fmt::format(
        "shard {} (shard {}/{}) lacks {} of its {} points (first: point {}) in its journal",
        shard.dir.string(), shard.spec.index, shard.spec.count, missing,
        runner::shard_point_count(points, shard.spec), first_missing));
  return journals;
}

bool same_directory(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

}  // namespace

RunSummary merge_shards(const fs::path& out_dir, const std::vector<fs::path>& shard_dirs,
                        RunOptions options) {
  if (mpi_size() > 1)
    throw InputError("merge runs in one process: start it without mpirun");
  if (shard_dirs.empty()) throw InputError("merge: no shard directories given");
  std::vector<ShardDir> shards;
  std::map<std::size_t, fs::path> by_index;
  for (const fs::path& dir : shard_dirs) {
    if (same_directory(dir, out_dir))
      throw InputError(fmt::format("merge: the output directory {} is also given as a shard; "
                                   "merge into a new directory",
                                   out_dir.string()));
    ShardDir shard = read_shard(dir);
    if (!shards.empty()) check_same_study(shards.front(), shard);
    if (auto [it, fresh] = by_index.emplace(shard.spec.index, dir); !fresh)
      throw InputError(fmt::format("shards {} and {} are both shard {}/{}: each shard must be "
                                   "given once",
                                   it->second.string(), dir.string(), shard.spec.index,
                                   shard.spec.count));
    shards.push_back(std::move(shard));
  }
  const std::size_t count = shards.front().spec.count;
  std::vector<std::string> missing;
  for (std::size_t i = 1; i <= count; ++i)
    if (!by_index.count(i)) missing.push_back(fmt::format("{}/{}", i, count));
  if (!missing.empty())
    throw InputError(fmt::format("merge: shard(s) {} missing ({} of {} shard directories given)",
                                 fmt::join(missing, ", "), shards.size(), count));
  std::vector<std::vector<fs::path>> journals;
  for (const ShardDir& shard : shards) journals.push_back(check_points(shard));

  // The study as the shards ran it: the file must still say the same.
  const fs::path study_file = shards.front().meta["study_file"].get<std::string>();
  Study study = load_study(study_file, {.allow_large = true});
  if (std::string difference =
          runner::first_difference(runner::result_relevant(shards.front().meta["study"]),
                                   runner::result_relevant(study.document));
      !difference.empty())
    throw InputError(fmt::format("merge: {} changed since the shards ran ({})",
                                 study_file.string(), difference));

  {  // OUT gets every shard's journal (session = shard number) and per-point files.
    auto lock = runner::prepare_output_dir(out_dir, false, study_file.string());
    fs::create_directories(runner::journal_dir(out_dir));
    for (std::size_t s = 0; s < shards.size(); ++s) {
      const int session = static_cast<int>(shards[s].spec.index);
      for (std::size_t j = 0; j < journals[s].size(); ++j)
        fs::copy_file(journals[s][j],
                      runner::journal_file(out_dir, session, static_cast<int>(j)));
      if (fs::is_directory(shards[s].dir / "points"))
        fs::copy(shards[s].dir / "points", out_dir / "points",
                 fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    }
  }
  // The run, resumed with every point finished: results.csv, plots and meta.json exactly as a
  // single run writes them.
  options.out_dir = out_dir;
  options.resume = true;
  options.retry_failed = false;
  options.shard.reset();
  RunSummary summary = run_study(study, options);

  const fs::path meta_file = out_dir / "meta.json";
  Json meta = Json::parse(runner::read_file(meta_file));
  Json merged = Json::array();
  for (const ShardDir& shard : shards)
    merged.push_back({{"dir", fs::absolute(shard.dir).string()},
                      {"shard", shard.meta["shard"]},
                      {"run", shard.meta.value("run", Json())},
                      {"timings", shard.meta.value("timings", Json())}});
  meta["merged_from"] = std::move(merged);
  write_file_atomically(meta_file, runner::json_text(meta, 2) + "\n");
  return summary;
}

}  // namespace chatterlab
