#include "runner/resume.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <fstream>
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

namespace {
constexpr std::uint64_t from_nowhere = 0, from_results_h5 = 1;
constexpr int offset_bits = 48;
constexpr std::uint64_t offset_mask = (std::uint64_t{1} << offset_bits) - 1;
constexpr std::size_t read_block_bytes = std::size_t{1} << 20;
}  // namespace

// A journal read at the places pass one noted: a window of the file around the last line read,
// so lines that are nearly in grid order (as points finish) cost one read per window.
struct ResumedPoints::JournalCursor {
  static constexpr std::size_t window_bytes = 256 * 1024, look_back_bytes = 64 * 1024;
  fs::path file;
  std::ifstream in;
  std::string window;
  std::uint64_t window_start = 0;

  std::string_view line_at(std::uint64_t offset) {
    if (offset >= window_start && offset < window_start + window.size()) {
      const std::size_t begin = static_cast<std::size_t>(offset - window_start);
      const std::size_t end = window.find('\n', begin);
      if (end != std::string::npos) return std::string_view(window).substr(begin, end - begin);
    }
    if (!in.is_open()) in.open(file, std::ios::binary);
    window_start = offset > look_back_bytes ? offset - look_back_bytes : 0;
    window.clear();
    for (std::size_t size = window_bytes;; size *= 2) {  // a line longer than the window: grow
      in.clear();
      in.seekg(static_cast<std::streamoff>(window_start));
      window.resize(size);
      in.read(window.data(), static_cast<std::streamsize>(size));
      window.resize(static_cast<std::size_t>(in.gcount()));
      const std::size_t begin = static_cast<std::size_t>(offset - window_start);
      if (begin >= window.size())
        throw std::runtime_error(fmt::format("{} is shorter than when the resume began", file.string()));
      const std::size_t end = window.find('\n', begin);
      if (end != std::string::npos) return std::string_view(window).substr(begin, end - begin);
      if (window.size() < size)
        throw std::runtime_error(fmt::format("{} changed since the resume began", file.string()));
    }
  }
};

ResumedPoints::ResumedPoints(std::size_t points) : done_(points, false), ok_(points, false) {}
ResumedPoints::~ResumedPoints() = default;
ResumedPoints::ResumedPoints(ResumedPoints&&) noexcept = default;
ResumedPoints& ResumedPoints::operator=(ResumedPoints&&) noexcept = default;

PointResult ResumedPoints::take(std::size_t point) {
  if (point < next_ || !has(point))
    throw std::logic_error(fmt::format("runner: point {} taken out of order or not resumed", point));
  next_ = point + 1;
  const std::uint64_t location = location_.empty() ? from_results_h5 : location_[point];
  if (location == from_results_h5) {
    if (!h5_) h5_ = std::make_unique<Hdf5ResultsReader>(results_h5_);
    while (point >= h5_row_first_ + h5_row_.size()) {
      h5_row_ = h5_->next_chunk_row();
      if (h5_row_.empty())
        throw std::runtime_error(fmt::format("{} ends before point {}", results_h5_.string(), point));
      h5_row_first_ = h5_->position() - h5_row_.size();
    }
    h5_row_next_ = point - h5_row_first_ + 1;
    PointResult result = std::move(h5_row_[point - h5_row_first_]);
    if (outcome_of(result.status) == PointOutcome::timeout) {
      const auto found = std::lower_bound(h5_timeout_elapsed_s_.begin(), h5_timeout_elapsed_s_.end(),
                                          std::pair<std::size_t, double>(point, -1.0));
      if (found != h5_timeout_elapsed_s_.end() && found->first == point)
        result.elapsed_s = found->second;
    }
    return result;
  }
  JournalCursor& journal = *journals_.at(static_cast<std::size_t>((location >> offset_bits) - 1));
  std::pair<std::size_t, PointResult> record;
  if (!parse_journal_record(journal.line_at(location & offset_mask), done_.size(), columns_,
                            record) ||
      record.first != point)
    throw std::runtime_error(
        fmt::format("{} changed since the resume began (point {})", journal.file.string(), point));
  return std::move(record.second);
}

// Pass one of a resume: which record each point takes over, by the rules of read_journals.
class ResumeScan {
 public:
  ResumeScan(ResumedPoints& into, const fs::path& out_dir, const JournalHeader& expected,
             const Study& study)
      : r_(into), out_dir_(out_dir), expected_(expected), study_(study) {
    r_.columns_ = expected.columns.size();
  }

  // Every point of results.h5 (failed ones included), read one chunk row at a time.
  void results_h5(const fs::path& file) {
    try {
      Hdf5ResultsReader reader(file);
      if (reader.header().study_fingerprint != expected_.study_fingerprint ||
          reader.header().points != expected_.points ||
          reader.header().columns != expected_.columns)
        throw InputError(mismatch(file, reader.header(), expected_, out_dir_, study_));
      for (auto row = reader.next_chunk_row(true); !row.empty(); row = reader.next_chunk_row(true)) {
        const std::size_t first = reader.position() - row.size();
        for (std::size_t k = 0; k < row.size(); ++k) {
          r_.done_[first + k] = true;
          r_.ok_[first + k] = row[k].status == "ok";
        }
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(fmt::format("cannot resume from {}: {}; run without --resume to start over",
                                   file.string(), e.what()));
    }
    r_.results_h5_ = file;
    r_.h5_timeout_elapsed_s_ = timeouts_in_meta();
  }

  // The elapsed times of the timeouts the completed run's meta.json lists. results.h5 is
  // renamed into place before meta.json is written, so a meta.json that cannot be read (a kill
  // between the two) leaves the times at 0 s, as results.h5 alone would.
  std::vector<std::pair<std::size_t, double>> timeouts_in_meta() const {
    std::vector<std::pair<std::size_t, double>> elapsed;
    try {
      const Json meta = Json::parse(read_file(out_dir_ / "meta.json"));
      if (meta.value("study_fingerprint", std::string()) != expected_.study_fingerprint) return {};
      for (const Json& entry : meta.at("failed_points"))
        if (entry.value("status", std::string()) == "timeout" && entry.contains("elapsed_s"))
          elapsed.emplace_back(entry.at("point").get<std::size_t>(),
                               entry.at("elapsed_s").get<double>());
    } catch (const std::exception&) {
      return {};
    }
    std::sort(elapsed.begin(), elapsed.end());
    return elapsed;
  }

  // Every journal, oldest session first, one line at a time.
  void journals() {
    std::vector<fs::path> files = journal_files(out_dir_);
    std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
      return session_and_rank(a) < session_and_rank(b);
    });
    for (const auto& file : files) journal(file);
  }

  void finish(bool retry_failed) {
    r_.count_ = 0;
    for (std::size_t p = 0; p < r_.done_.size(); ++p) {
      if (retry_failed && r_.done_[p] && !r_.ok_[p]) r_.done_[p] = false;
      r_.count_ += r_.done_[p] ? 1 : 0;
    }
  }

 private:
  void journal(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(fmt::format("cannot resume: cannot read {}", file.string()));
    const std::size_t index = r_.journals_.size();
    std::string text;         // unprocessed bytes, starting at file offset `text_start`
    std::uint64_t text_start = 0;
    bool header_done = false, usable = false;
    std::vector<char> block(read_block_bytes);
    for (;;) {
      in.read(block.data(), static_cast<std::streamsize>(block.size()));
      const std::size_t got = static_cast<std::size_t>(in.gcount());
      if (got == 0) break;
      text.append(block.data(), got);
      std::size_t begin = 0;
      for (std::size_t end; (end = text.find('\n', begin)) != std::string::npos; begin = end + 1) {
        const std::string_view line = std::string_view(text).substr(begin, end - begin + 1);
        if (!header_done) {
          header_done = true;
          usable = header(file, line);
          if (!usable) return;  // an unreadable header: nothing of this file is used
          continue;
        }
        record(line.substr(0, line.size() - 1), index, text_start + begin);
      }
      text.erase(0, begin);
      text_start += begin;
    }
    if (!text.empty()) ++r_.truncated_lines;  // cut by a kill (or a header cut short)
    if (usable) {
      auto cursor = std::make_unique<ResumedPoints::JournalCursor>();
      cursor->file = file;
      r_.journals_.push_back(std::move(cursor));
    }
  }

  // The header line (with its '\n'): false when unusable; InputError when it is another study's.
  bool header(const fs::path& file, std::string_view line) {
    JournalContents contents = parse_journal(line);
    r_.invalid_lines += contents.invalid_lines;
    if (!contents.header_found) return false;
    const JournalHeader& found = contents.header;
    if (found.study_fingerprint != expected_.study_fingerprint ||
        found.points != expected_.points || found.columns != expected_.columns)
      throw InputError(mismatch(file, found, expected_, out_dir_, study_));
    return true;
  }

  void record(std::string_view line, std::size_t journal, std::uint64_t offset) {
    if (line.empty() || (line.size() == 1 && line[0] == '\r')) return;
    std::pair<std::size_t, PointResult> parsed;
    if (!parse_journal_record(line, expected_.points, expected_.columns.size(), parsed)) {
      ++r_.invalid_lines;
      return;
    }
    if (offset > offset_mask || journal + 1 >= (std::uint64_t{1} << (64 - offset_bits)))
      throw InputError("cannot resume: a journal is too large to index");
    const std::size_t p = parsed.first;
    const bool ok = parsed.second.status == "ok";
    if (r_.location_.empty()) {  // the first journal record: place the points of results.h5
      r_.location_.assign(r_.done_.size(), from_nowhere);
      for (std::size_t q = 0; q < r_.done_.size(); ++q)
        if (r_.done_[q]) r_.location_[q] = from_results_h5;
    }
    const std::uint64_t current = r_.location_[p];
    // A later session only computed a point the earlier ones had not finished well; over
    // results.h5 (an interrupted --retry-failed after it), an ok record wins, and any record
    // replaces a failed one.
    const bool replace = current == from_nowhere ||
                         (current == from_results_h5 ? !r_.ok_[p] || ok : !r_.ok_[p]);
    if (!replace) return;
    r_.location_[p] = (static_cast<std::uint64_t>(journal + 1) << offset_bits) | offset;
    r_.done_[p] = true;
    r_.ok_[p] = ok;
  }

  ResumedPoints& r_;
  const fs::path& out_dir_;
  const JournalHeader& expected_;
  const Study& study_;
};

ResumedPoints read_journals(const fs::path& out_dir, const JournalHeader& expected,
                            const Study& study, bool retry_failed) {
  ResumedPoints out(expected.points);
  ResumeScan scan(out, out_dir, expected, study);
  scan.journals();
  scan.finish(retry_failed);
  return out;
}

ResumedPoints read_resumable_points(const fs::path& out_dir, const JournalHeader& expected,
                                    const Study& study, bool retry_failed) {
  const fs::path results_h5 = results_path(out_dir, ResultsFormat::hdf5);
  if (!fs::exists(results_h5)) return read_journals(out_dir, expected, study, retry_failed);
  ResumedPoints out(expected.points);
  ResumeScan scan(out, out_dir, expected, study);
  scan.results_h5(results_h5);
  scan.journals();
  scan.finish(retry_failed);
  return out;
}

}  // namespace chatterlab::runner
