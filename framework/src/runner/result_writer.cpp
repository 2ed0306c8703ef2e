// GridOrderWriter: results.csv streamed in grid order, plus the bounded plot table
// (runner/result_writer.hpp).
#include "runner/result_writer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "runner/run_meta.hpp"

namespace chatterlab::runner {

namespace {
// Rows go to the file in blocks of about this many bytes (one write call per block).
constexpr std::size_t write_block_bytes = std::size_t{1} << 20;

std::size_t thinned(std::size_t values, std::size_t stride) { return (values + stride - 1) / stride; }
}  // namespace

std::vector<std::size_t> plot_strides(const Study& study, std::size_t max_rows) {
  std::vector<std::size_t> strides(study.grid.size(), 1);
  auto rows = [&] {
    std::size_t product = 1;
    for (std::size_t a = 0; a < strides.size(); ++a)
      product *= thinned(study.grid[a].values.size(), strides[a]);
    return product;
  };
  while (rows() > std::max<std::size_t>(max_rows, 1)) {
    std::size_t longest = 0;
    for (std::size_t a = 1; a < strides.size(); ++a)
      if (thinned(study.grid[a].values.size(), strides[a]) >
          thinned(study.grid[longest].values.size(), strides[longest]))
        longest = a;
    ++strides[longest];
  }
  return strides;
}

Study decimated_study(const Study& study, const std::vector<std::size_t>& strides) {
  Study thin = study;
  for (std::size_t a = 0; a < thin.grid.size(); ++a) {
    std::vector<Json> values;
    for (std::size_t i = 0; i < study.grid[a].values.size(); i += strides[a])
      values.push_back(study.grid[a].values[i]);
    thin.grid[a].values = std::move(values);
  }
  return thin;
}

GridOrderWriter::GridOrderWriter(const Study& study, std::vector<std::string> output_columns,
                                 const std::filesystem::path& file, ResultsFormat format,
                                 const Json& provenance, std::size_t plot_rows)
    : study_(study), columns_(std::move(output_columns)) {
  if (auto it = std::find(columns_.begin(), columns_.end(), "notice"); it != columns_.end())
    notice_column_ = it - columns_.begin();
  for (const auto& axis : study.grid) plot_table_.grid_columns.push_back(axis.key);
  plot_table_.output_columns = columns_;
  const std::vector<std::size_t> strides = plot_strides(study, plot_rows);
  if (std::any_of(strides.begin(), strides.end(), [](std::size_t s) { return s > 1; })) {
    strides_ = strides;
    plot_study_ = std::make_unique<Study>(decimated_study(study, strides_));
    plot_table_.strides = strides_;
    plot_table_.full_point_count = study.point_count();
  } else {
    plot_study_ = std::make_unique<Study>(study);
  }
  plot_table_.rows.resize(plot_study_->point_count());
  plot_table_.status.resize(plot_study_->point_count());

  if (format == ResultsFormat::hdf5) {
    hdf5_ = std::make_unique<Hdf5ResultsWriter>(study, columns_, file, provenance);
    temporary_path_ = hdf5_->temporary_path();
    return;
  }
  file_ = std::make_unique<AtomicFileWriter>(file);
  temporary_path_ = file_->temporary_path();
  std::string header;
  for (const auto& c : plot_table_.grid_columns) header += csv_field(c) + ',';
  for (const auto& c : columns_) header += csv_field(c) + ',';
  header += "status\n";
  buffer_ = std::move(header);
}

std::string GridOrderWriter::format_row(std::size_t point, const PointResult& result) const {
  std::string line;
  const std::vector<std::size_t> index = study_.point_indices(point);
  for (std::size_t a = 0; a < study_.grid.size(); ++a) {
    line += format_cell(study_.grid[a].values[index[a]]);
    line += ',';
  }
  for (const Json& cell : result.outputs) {
    line += format_cell(cell);
    line += ',';
  }
  line += csv_field(result.status);
  line += '\n';
  return line;
}

GridOrderWriter::Early GridOrderWriter::prepare_row(std::size_t point, PointResult&& result) const {
  if (!result.done || result.outputs.size() != columns_.size() || point >= study_.point_count())
    throw std::logic_error(fmt::format("runner: point {} has no complete result", point));
  Early row;
  if (file_) row.line = format_row(point, result);
  row.failure = failed_point(study_, point, result.status, result.elapsed_s);
  if (notice_column_ >= 0) {
    const Json& cell = result.outputs[static_cast<std::size_t>(notice_column_)];
    if (cell.is_string() && !cell.get_ref<const std::string&>().empty()) row.notice = cell;
  }
  // The plot row of a point on the lattice: its index in the thinned grid (row-major).
  std::ptrdiff_t plot_row = static_cast<std::ptrdiff_t>(point);
  if (!strides_.empty()) {
    const std::vector<std::size_t> index = study_.point_indices(point);
    std::size_t r = 0;
    for (std::size_t a = 0; a < index.size() && plot_row >= 0; ++a) {
      if (index[a] % strides_[a] != 0) plot_row = -1;
      r = r * plot_study_->grid[a].values.size() + index[a] / strides_[a];
    }
    if (plot_row >= 0) plot_row = static_cast<std::ptrdiff_t>(r);
  }
  row.plot_row = plot_row;
  if (plot_row >= 0) {
    const std::vector<std::size_t> index = study_.point_indices(point);
    for (std::size_t a = 0; a < study_.grid.size(); ++a)
      row.plot_cells.push_back(study_.grid[a].values[index[a]]);
    for (Json& output : result.outputs)
      if (hdf5_)
        row.plot_cells.push_back(output);
      else
        row.plot_cells.push_back(std::move(output));
    row.plot_status = result.status;
  }
  if (hdf5_) row.result = std::move(result);
  return row;
}

void GridOrderWriter::add(std::size_t point, PointResult&& result) {
  // Formatting (most of a row's cost) happens outside the lock, on the computing thread.
  Early row = prepare_row(point, std::move(result));
  std::lock_guard lock(mutex_);
  if (point != next_) {
    early_.emplace(point, std::move(row));
    return;
  }
  append(std::move(row));
  write_ready();
}

void GridOrderWriter::take_resumed_points(ResumedPoints* resumed) {
  std::lock_guard lock(mutex_);
  resumed_ = resumed;
  write_ready();
}

void GridOrderWriter::append(Early&& row) {
  const std::size_t point = next_++;
  if (!row.failure.is_null()) failed_.emplace(point, std::move(row.failure));
  if (!row.notice.is_null()) notices_.emplace(point, std::move(row.notice));
  if (row.plot_row >= 0) {
    plot_table_.rows[static_cast<std::size_t>(row.plot_row)] = std::move(row.plot_cells);
    plot_table_.status[static_cast<std::size_t>(row.plot_row)] = std::move(row.plot_status);
  }
  if (!hdf5_) {
    buffer_ += row.line;
    return;
  }
  if (!error_.empty()) return;
  try {
    hdf5_->append(std::move(row.result));  // writes whole chunks as they fill
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

void GridOrderWriter::write_ready() {
  const std::size_t points = study_.point_count();
  while (next_ < points) {
    if (auto it = early_.begin(); it != early_.end() && it->first == next_) {
      append(std::move(it->second));
      early_.erase(it);
    } else if (resumed_ && resumed_->has(next_)) {
      // An earlier session's point, read back now that its row is due.
      PointResult result;
      try {
        result = resumed_->take(next_);
      } catch (const std::runtime_error& e) {
        if (error_.empty()) error_ = std::string("cannot read an earlier session's result: ") + e.what();
        result = {true, std::vector<Json>(columns_.size()), failure_status(e.what()), 0.0};
      }
      append(prepare_row(next_, std::move(result)));
    } else {
      break;
    }
    // Inside the loop: a resume takes a whole grid of rows in one call.
    if (buffer_.size() >= write_block_bytes) write_buffer();
  }
  if (next_ == points) write_buffer();
}

void GridOrderWriter::write_buffer() {
  if (hdf5_) return;
  if (error_.empty() && file_) {
    try {
      file_->write(buffer_);
    } catch (const std::exception& e) {
      error_ = e.what();
    }
  }
  buffer_.clear();
}

void GridOrderWriter::commit() {
  std::lock_guard lock(mutex_);
  write_ready();  // the resumed points after the last computed one
  if (next_ != study_.point_count())
    throw std::logic_error(fmt::format("runner: results.csv has {} of {} rows", next_,
                                       study_.point_count()));
  if (error_.empty() && hdf5_) {
    try {
      hdf5_->commit();
    } catch (const std::exception& e) {
      error_ = e.what();
    }
  }
  if (!error_.empty()) {
    file_.reset();
    hdf5_.reset();
    throw OutputError(error_);
  }
  if (file_) file_->commit();
}

void GridOrderWriter::abandon() noexcept {
  std::lock_guard lock(mutex_);
  if (file_) file_->abandon();
  if (hdf5_) hdf5_->abandon();
}

Json GridOrderWriter::failed_points() const {
  std::lock_guard lock(mutex_);
  Json out = Json::array();
  for (const auto& [point, entry] : failed_) out.push_back(entry);
  return out;
}

Json GridOrderWriter::notices() const {
  std::lock_guard lock(mutex_);
  Json out = Json::array();
  for (const auto& [point, notice] : notices_) out.push_back({{"point", point}, {"notice", notice}});
  return out;
}

ResultTable GridOrderWriter::take_plot_table() { return std::move(plot_table_); }

}  // namespace chatterlab::runner
