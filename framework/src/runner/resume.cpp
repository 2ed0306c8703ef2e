#include "runner/resume.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <map>

#include "chatterlab/errors.hpp"
#include "runner/output_dir.hpp"
#include "runner/results_hdf5.hpp"
#include "study/messages.hpp"

namespace chatterlab::runner {

namespace fs = std::filesystem;

namespace {

// Why a journal does not fit this study, as precisely as the directory lets us say.
std::string mismatch(const fs::path& journal, const JournalHeader& found,
                     const JournalHeader& expected, const fs::path& out_dir, const Study& study) {
  const std::string start = fmt::format("cannot resume from {}: ", journal.string());
  const std::string end = "; run without --resume to start over";
  for (const auto& [file, sha] : expected.inputs.items()) {
    auto then = found.inputs.find(file);
    if (then == found.inputs.end())
      return start + fmt::format("input file {} was not an input of that run", file) + end;
    if (*then != sha)
      return start + fmt::format("input file {} changed since that run (sha256 {}... then, {}... now)",
                                 file, then->get<std::string>().substr(0, 12),
                                 sha.get<std::string>().substr(0, 12)) + end;
  }
  for (const auto& [file, sha] : found.inputs.items())
    if (!expected.inputs.contains(file))
      return start + fmt::format("that run also read {}, this study does not", file) + end;
  if (found.points != expected.points)
    return start + fmt::format("it was written for {} grid points, the study now has {}",
                               found.points, expected.points) + end;
  if (found.columns != expected.columns)
    return start + "the study's output columns changed" + end;
  // The earlier run's meta.json holds its resolved study: name the first value that differs.
  try {
    Json meta = Json::parse(read_file(out_dir / "meta.json"));
    std::string difference =
        first_difference(result_relevant(meta.at("study")), result_relevant(study.document));
    if (!difference.empty())
      return start + "the study changed since that run (" + difference + ")" + end;
  } catch (const std::exception&) {  // no readable meta.json: say it without the detail
  }
  return start + "it was written for a different study (the resolved study, its grid or the "
                 "output columns changed)" + end;
}

// journal/points-<session>-<rank>.jsonl -> (session, rank); names were checked by journal_files.
std::pair<int, int> session_and_rank(const fs::path& file) {
  const std::string name = file.filename().string();
  int session = 0, rank = 0;
  const char* p = name.data() + std::string_view("points-").size();
  auto [after_session, ec] = std::from_chars(p, name.data() + name.size(), session);
  std::from_chars(after_session + 1, name.data() + name.size(), rank);
  return {session, rank};
}

}  // namespace

std::string first_difference(const Json& then, const Json& now, const std::string& path) {
  const std::string here = path.empty() ? "(top level)" : path;
  if (then.is_object() && now.is_object()) {
    std::map<std::string, int> keys;
    for (const auto& [k, v] : then.items()) keys[k] |= 1;
    for (const auto& [k, v] : now.items()) keys[k] |= 2;
    for (const auto& [key, where] : keys) {
      const std::string child = path.empty() ? key : path + "." + key;
      if (where == 1) return fmt::format("{}: {} then, absent now", child, messages::show(then[key]));
      if (where == 2) return fmt::format("{}: absent then, {} now", child, messages::show(now[key]));
      if (std::string d = first_difference(then[key], now[key], child); !d.empty()) return d;
    }
    return {};
  }
  if (then.is_array() && now.is_array() && then.size() == now.size()) {
    for (std::size_t i = 0; i < then.size(); ++i)
      if (std::string d = first_difference(then[i], now[i], path + "." + std::to_string(i));
          !d.empty())
        return d;
    return {};
  }
  if (then == now) return {};
  return fmt::format("{}: {} then, {} now", here, messages::show(then), messages::show(now));
}

ResumedPoints read_journals(const fs::path& out_dir, const JournalHeader& expected,
                            const Study& study, bool retry_failed) {
  std::vector<fs::path> files = journal_files(out_dir);
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
    return session_and_rank(a) < session_and_rank(b);
  });
  ResumedPoints out;
  std::map<std::size_t, PointResult> chosen;
  for (const auto& file : files) {
    JournalContents journal = parse_journal(read_file(file));
    out.truncated_lines += journal.truncated_lines;
    out.invalid_lines += journal.invalid_lines;
    if (!journal.header_found) continue;  // killed before its first line was complete
    if (journal.header.study_fingerprint != expected.study_fingerprint ||
        journal.header.points != expected.points || journal.header.columns != expected.columns)
      throw InputError(mismatch(file, journal.header, expected, out_dir, study));
    for (auto& [point, record] : journal.records) {
      auto it = chosen.find(point);
      // A later session only computed a point the earlier ones had not finished well.
      if (it == chosen.end())
        chosen.emplace(point, std::move(record));
      else if (it->second.status != "ok")
        it->second = std::move(record);
    }
  }
  for (auto& [point, record] : chosen) {
    if (retry_failed && record.status != "ok") continue;
    out.records.emplace_back(point, std::move(record));
  }
  return out;
}

namespace {

// Every point of results.h5 (all of them, failed ones included).
std::vector<std::pair<std::size_t, PointResult>> points_of_results_h5(
    const fs::path& out_dir, const fs::path& results_h5, const JournalHeader& expected,
    const Study& study) {
  Hdf5Results results;
  try {
    results = read_hdf5_results(results_h5);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("cannot resume from {}: {}; run without --resume to start over",
                                 results_h5.string(), e.what()));
  }
  if (results.header.study_fingerprint != expected.study_fingerprint ||
      results.header.points != expected.points || results.header.columns != expected.columns)
    throw InputError(mismatch(results_h5, results.header, expected, out_dir, study));
  return std::move(results.records);
}

}  // namespace

ResumedPoints read_resumable_points(const fs::path& out_dir, const JournalHeader& expected,
                                    const Study& study, bool retry_failed) {
  const fs::path results_h5 = results_path(out_dir, ResultsFormat::hdf5);
  if (!fs::exists(results_h5)) return read_journals(out_dir, expected, study, retry_failed);
  std::map<std::size_t, PointResult> chosen;
  for (auto& [point, record] : points_of_results_h5(out_dir, results_h5, expected, study))
    chosen.emplace(point, std::move(record));
  ResumedPoints out = read_journals(out_dir, expected, study, /*retry_failed=*/false);
  for (auto& [point, record] : out.records) {  // later sessions: an ok record wins
    PointResult& earlier = chosen[point];
    if (!earlier.done || earlier.status != "ok" || record.status == "ok") earlier = std::move(record);
  }
  out.records.clear();
  for (auto& [point, record] : chosen) {
    if (retry_failed && record.status != "ok") continue;
    out.records.emplace_back(point, std::move(record));
  }
  return out;
}

}  // namespace chatterlab::runner
