// results.h5 (runner/results_hdf5.hpp), through the HDF5 C API and its high-level dimension scales.
#include "runner/results_hdf5.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/output_files.hpp"
#include "chatterlab/runner.hpp"
#include "study/messages.hpp"

namespace chatterlab::runner {

namespace fs = std::filesystem;

ResultsFormat results_format(const Study& study) {
  const Json output = study.document.value("output", Json::object());
  const std::string format = output.value("format", std::string("csv"));
  if (format == "hdf5") return ResultsFormat::hdf5;
  if (format == "auto" && study.point_count() > auto_hdf5_above_points) return ResultsFormat::hdf5;
  return ResultsFormat::csv;
}

bool keep_journal(const Study& study) {
  return study.document.value("output", Json::object()).value("keep_journal", false);
}

fs::path results_path(const fs::path& out_dir, ResultsFormat format) {
  return out_dir / (format == ResultsFormat::hdf5 ? "results.h5" : "results.csv");
}

namespace {

// An HDF5 identifier closed at scope exit.
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), close_(other.close_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, -1);
      close_ = other.close_;
    }
    return *this;
  }
  ~Handle() { reset(); }
  void reset() noexcept {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  hid_t get() const { return id_; }
  hid_t release() { return std::exchange(id_, -1); }  // the caller closes it
  explicit operator bool() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

// The innermost HDF5 error descriptions ("unable to write", "file write failed: ... errno = 28").
std::string hdf5_error_stack() {
  std::string text;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* entry, void* data) -> herr_t {
        auto& out = *static_cast<std::string*>(data);
        if (entry->desc && *entry->desc) out += (out.empty() ? "" : "; ") + std::string(entry->desc);
        return 0;
      },
      &text);
  H5Eclear2(H5E_DEFAULT);
  return text.empty() ? "HDF5 error" : text;
}

// Messages go into exceptions, not to stderr from inside the library.
void silence_hdf5_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// The chunk layout of a grid-shaped dataset: the trailing axes whole, one axis cut (row_axis,
// `row_values` of its values per chunk), the leading axes one value each. A "chunk row" (a run of
// consecutive points in grid order that fills whole chunks) is one hyperslab.
struct Layout {
  std::vector<hsize_t> dims, chunk;
  int row_axis = -1;        // -1: one chunk holds the whole grid
  std::size_t inner = 1;    // points per value of row_axis
  std::size_t row_values = 1;
  std::size_t points = 1;

  explicit Layout(std::vector<hsize_t> shape) : dims(std::move(shape)), chunk(dims.size(), 1) {
    for (hsize_t d : dims) points *= static_cast<std::size_t>(d);
    int axis = static_cast<int>(dims.size()) - 1;
    while (axis >= 0 && inner * dims[static_cast<std::size_t>(axis)] <= hdf5_chunk_points) {
      chunk[static_cast<std::size_t>(axis)] = dims[static_cast<std::size_t>(axis)];
      inner *= static_cast<std::size_t>(dims[static_cast<std::size_t>(axis)]);
      --axis;
    }
    row_axis = axis;
    if (axis >= 0) {
      row_values = std::max<std::size_t>(1, hdf5_chunk_points / inner);
      chunk[static_cast<std::size_t>(axis)] = row_values;
    }
  }

  // The end of the chunk row that starts at point `begin`.
  std::size_t row_end(std::size_t begin) const {
    if (row_axis < 0) return points;
    const std::size_t d = static_cast<std::size_t>(dims[static_cast<std::size_t>(row_axis)]);
    const std::size_t value = (begin / inner) % d;
    return begin + std::min(row_values - value % row_values, d - value) * inner;
  }

  // The file dataspace of `dataset` with the chunk row [begin, end) selected.
  Handle select(hid_t dataset, std::size_t begin, std::size_t end) const {
    Handle space(H5Dget_space(dataset), H5Sclose);
    std::vector<hsize_t> start(dims.size(), 0), count = dims;
    if (row_axis >= 0) {
      std::size_t rest = begin;
      for (std::size_t a = dims.size(); a-- > 0;) {
        start[a] = rest % dims[a];
        rest /= static_cast<std::size_t>(dims[a]);
      }
      for (std::size_t a = 0; a < static_cast<std::size_t>(row_axis); ++a) count[a] = 1;
      count[static_cast<std::size_t>(row_axis)] = (end - begin) / inner;
    }
    H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    return space;
  }
};

std::vector<hsize_t> grid_shape(const Study& study) {
  std::vector<hsize_t> shape;
  for (const auto& axis : study.grid) shape.push_back(axis.values.size());
  if (shape.empty()) shape.push_back(1);
  return shape;
}

Handle text_type(std::size_t width) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(width, 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

Handle boolean_type() {
  Handle type(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose);
  std::int8_t value = 0;
  H5Tenum_insert(type.get(), "FALSE", &value);
  value = 1;
  H5Tenum_insert(type.get(), "TRUE", &value);
  return type;
}

Handle variable_text_type() {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  return type;
}

bool write_text_attribute(hid_t object, const char* name, const std::string& value) {
  Handle type = variable_text_type();
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attribute(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   H5Aclose);
  const char* text = value.c_str();
  return attribute && H5Awrite(attribute.get(), type.get(), &text) >= 0;
}

std::string read_text_attribute(hid_t object, const char* name) {
  if (H5Aexists(object, name) <= 0) return {};
  Handle attribute(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
  Handle type = variable_text_type();
  char* text = nullptr;
  if (!attribute || H5Aread(attribute.get(), type.get(), &text) < 0 || !text) return {};
  std::string out(text);
  H5free_memory(text);
  return out;
}

// A grid key or column name as an HDF5 link name ('/' separates groups there).
std::string link_name(std::string name) {
  std::replace(name.begin(), name.end(), '/', '|');
  return name == "." || name.empty() ? "_" + name : name;
}

// A cell as text: strings as they are, anything else as results.csv prints it.
std::string text_of(const Json& cell) {
  if (cell.is_string()) return cell.get<std::string>();
  if (cell.is_null()) return {};
  return format_cell(cell);
}

std::size_t text_width_for(std::size_t length) {
  std::size_t width = 8;
  while (width < length) width *= 2;
  return width;
}

enum class CellType { undecided, number, boolean, text };

// A chunked, compressed (shuffle + deflate) dataset of the grid's shape.
Handle create_dataset(hid_t parent, const std::string& name, hid_t type, const Layout& layout,
                      const void* fill) {
  Handle space(H5Screate_simple(static_cast<int>(layout.dims.size()), layout.dims.data(), nullptr),
               H5Sclose);
  Handle create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(create.get(), static_cast<int>(layout.chunk.size()), layout.chunk.data());
  H5Pset_shuffle(create.get());
  H5Pset_deflate(create.get(), 4);
  H5Pset_fill_value(create.get(), type, fill);
  // Whole chunks are written once: no chunk cache (its memory would be per dataset).
  Handle access(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
  H5Pset_chunk_cache(access.get(), 0, 0, 1.0);
  return Handle(H5Dcreate2(parent, name.c_str(), type, space.get(), H5P_DEFAULT, create.get(),
                           access.get()),
                H5Dclose);
}

}  // namespace

struct Hdf5ResultsWriter::Impl {
  struct Column {
    std::string name, link;
    CellType type = CellType::undecided;
    std::size_t width = 0;  // text: bytes per value
    Handle dataset;
    std::vector<Json> cells;  // the current chunk row
  };

  const Study& study;
  fs::path path, tmp;
  Layout layout;
  Handle file;
  std::vector<Column> columns;  // the outputs, then status
  std::size_t next = 0, row_begin = 0, row_end = 0;
  bool committed = false;

  Impl(const Study& s, fs::path p) : study(s), path(std::move(p)), tmp(temporary_path_for(path)),
                                     layout(grid_shape(s)) {}

  [[noreturn]] void fail(const std::string& what) const {
    note_failed_output_write();
    throw OutputError(fmt::format("cannot write {}: {}: {}", path.string(), what, hdf5_error_stack()));
  }

  void create_column_dataset(Column& column) {
    if (column.type == CellType::number) {
      const double nan = std::numeric_limits<double>::quiet_NaN();
      column.dataset = create_dataset(file.get(), column.link, H5T_IEEE_F64LE, layout, &nan);
    } else if (column.type == CellType::boolean) {
      const std::int8_t no = 0;
      Handle type = boolean_type();
      column.dataset = create_dataset(file.get(), column.link, type.get(), layout, &no);
    } else {
      Handle type = text_type(column.width);
      const std::string empty(column.width, '\0');
      column.dataset = create_dataset(file.get(), column.link, type.get(), layout, empty.data());
    }
    if (!column.dataset) fail("dataset " + column.link);
    if (!write_text_attribute(column.dataset.get(), "column", column.name))
      fail("attribute of " + column.link);
  }

  // A longer text than the column's width: the column is copied into a wider dataset (the width
  // doubles, so this happens a few times at most).
  void widen(Column& column, std::size_t length) {
    const std::size_t width = std::max(text_width_for(length), 2 * column.width);
    Column wider;
    wider.name = column.name;
    wider.link = column.link + " (widening)";
    wider.type = CellType::text;
    wider.width = width;
    create_column_dataset(wider);
    Handle type = text_type(width);
    std::vector<char> buffer;
    for (std::size_t begin = 0; begin < row_begin;) {
      const std::size_t end = layout.row_end(begin);
      buffer.assign((end - begin) * width, '\0');
      const hsize_t count = end - begin;
      Handle memory(H5Screate_simple(1, &count, nullptr), H5Sclose);
      Handle from = layout.select(column.dataset.get(), begin, end);
      Handle to = layout.select(wider.dataset.get(), begin, end);
      if (H5Dread(column.dataset.get(), type.get(), memory.get(), from.get(), H5P_DEFAULT,
                  buffer.data()) < 0 ||
          H5Dwrite(wider.dataset.get(), type.get(), memory.get(), to.get(), H5P_DEFAULT,
                   buffer.data()) < 0)
        fail("widening " + column.link);
      begin = end;
    }
    column.dataset.reset();
    wider.dataset.reset();
    if (H5Ldelete(file.get(), column.link.c_str(), H5P_DEFAULT) < 0 ||
        H5Lmove(file.get(), wider.link.c_str(), file.get(), column.link.c_str(), H5P_DEFAULT,
                H5P_DEFAULT) < 0)
      fail("widening " + column.link);
    Handle access(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
    H5Pset_chunk_cache(access.get(), 0, 0, 1.0);
    column.dataset = Handle(H5Dopen2(file.get(), column.link.c_str(), access.get()), H5Dclose);
    column.width = width;
    if (!column.dataset) fail("widening " + column.link);
  }

  [[noreturn]] void conflict(const Column& column, std::size_t offset) const {
    throw OutputError(fmt::format(
        "cannot write {}: column {} holds {} at point {}, in a column of {}: a results.h5 column "
        "has one type. Write CSV instead ([output] format = \"csv\", then chatterlab run --resume "
        "takes the computed points from the journal)",
        path.string(), column.name, messages::show(column.cells[offset]), row_begin + offset,
        column.type == CellType::number ? "numbers" : "booleans"));
  }

  void write_column(Column& column) {
    if (column.type == CellType::undecided) {
      auto first = std::find_if(column.cells.begin(), column.cells.end(),
                                [](const Json& c) { return !c.is_null(); });
      if (first == column.cells.end()) return;  // all null so far: the fill value stands
      column.type = first->is_boolean() ? CellType::boolean
                    : first->is_number() ? CellType::number
                                         : CellType::text;
      if (column.type == CellType::text) {
        std::size_t longest = 0;
        for (const Json& c : column.cells) longest = std::max(longest, text_of(c).size());
        column.width = text_width_for(longest);
      }
      create_column_dataset(column);
    }
    const std::size_t count = column.cells.size();
    const hsize_t memory_count = count;
    Handle memory(H5Screate_simple(1, &memory_count, nullptr), H5Sclose);
    Handle selection = layout.select(column.dataset.get(), row_begin, row_end);
    herr_t written = -1;
    if (column.type == CellType::number) {
      std::vector<double> values(count, std::numeric_limits<double>::quiet_NaN());
      for (std::size_t i = 0; i < count; ++i) {
        const Json& c = column.cells[i];
        if (c.is_number()) values[i] = c.get<double>();
        else if (c.is_boolean()) values[i] = c.get<bool>() ? 1.0 : 0.0;
        else if (!c.is_null()) conflict(column, i);
      }
      written = H5Dwrite(column.dataset.get(), H5T_NATIVE_DOUBLE, memory.get(), selection.get(),
                         H5P_DEFAULT, values.data());
    } else if (column.type == CellType::boolean) {
      std::vector<std::int8_t> values(count, 0);
      for (std::size_t i = 0; i < count; ++i) {
        const Json& c = column.cells[i];
        if (c.is_boolean()) values[i] = c.get<bool>() ? 1 : 0;
        else if (!c.is_null()) conflict(column, i);
      }
      Handle type = boolean_type();
      written = H5Dwrite(column.dataset.get(), type.get(), memory.get(), selection.get(),
                         H5P_DEFAULT, values.data());
    } else {
      std::vector<std::string> texts(count);
      std::size_t longest = 0;
      for (std::size_t i = 0; i < count; ++i) {
        texts[i] = text_of(column.cells[i]);
        longest = std::max(longest, texts[i].size());
      }
      if (longest > column.width) {
        widen(column, longest);
        selection = layout.select(column.dataset.get(), row_begin, row_end);
      }
      std::vector<char> buffer(count * column.width, '\0');
      for (std::size_t i = 0; i < count; ++i)
        std::memcpy(buffer.data() + i * column.width, texts[i].data(), texts[i].size());
      Handle type = text_type(column.width);
      written = H5Dwrite(column.dataset.get(), type.get(), memory.get(), selection.get(),
                         H5P_DEFAULT, buffer.data());
    }
    if (written < 0) fail("dataset " + column.link);
  }

  void flush_row() {
    for (Column& column : columns) {
      write_column(column);
      column.cells.clear();
    }
    row_begin = row_end;
    row_end = row_begin < layout.points ? layout.row_end(row_begin) : row_begin;
  }

  // The grid axes under /grid, as dimension scales of every column.
  void write_scales() {
    if (study.grid.empty()) return;
    Handle group(H5Gcreate2(file.get(), "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!group) fail("group grid");
    for (std::size_t a = 0; a < study.grid.size(); ++a) {
      const GridAxis& axis = study.grid[a];
      const Layout line({static_cast<hsize_t>(axis.values.size())});
      const bool numbers = std::all_of(axis.values.begin(), axis.values.end(),
                                       [](const Json& v) { return v.is_number(); });
      Handle scale;
      const hsize_t n = axis.values.size();
      Handle memory(H5Screate_simple(1, &n, nullptr), H5Sclose);
      herr_t written = -1;
      const std::string link = link_name(axis.key);
      if (numbers) {
        std::vector<double> values;
        for (const Json& v : axis.values) values.push_back(v.get<double>());
        const double nan = std::numeric_limits<double>::quiet_NaN();
        scale = create_dataset(group.get(), link, H5T_IEEE_F64LE, line, &nan);
        if (scale)
          written = H5Dwrite(scale.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                             values.data());
      } else {
        std::size_t longest = 0;
        for (const Json& v : axis.values) longest = std::max(longest, text_of(v).size());
        const std::size_t width = text_width_for(longest);
        std::vector<char> buffer(axis.values.size() * width, '\0');
        for (std::size_t i = 0; i < axis.values.size(); ++i) {
          const std::string text = text_of(axis.values[i]);
          std::memcpy(buffer.data() + i * width, text.data(), text.size());
        }
        Handle type = text_type(width);
        const std::string empty(width, '\0');
        scale = create_dataset(group.get(), link, type.get(), line, empty.data());
        if (scale)
          written = H5Dwrite(scale.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer.data());
      }
      if (written < 0 || H5DSset_scale(scale.get(), axis.key.c_str()) < 0 ||
          !write_text_attribute(scale.get(), "key", axis.key) ||
          !write_text_attribute(scale.get(), "path", axis.path))
        fail("grid axis " + axis.key);
      for (Column& column : columns)
        if (H5DSattach_scale(column.dataset.get(), scale.get(), static_cast<unsigned>(a)) < 0 ||
            H5DSset_label(column.dataset.get(), static_cast<unsigned>(a), axis.key.c_str()) < 0)
          fail("dimension scale " + axis.key + " of " + column.link);
    }
  }
};

Hdf5ResultsWriter::Hdf5ResultsWriter(const Study& study, std::vector<std::string> output_columns,
                                     fs::path path, const Json& provenance)
    : impl_(std::make_unique<Impl>(study, std::move(path))) {
  silence_hdf5_errors();
  Impl& w = *impl_;
  std::error_code ec;
  if (w.path.has_parent_path()) fs::create_directories(w.path.parent_path(), ec);
  // Version 1.8 object headers: attributes of any size (dense attribute storage), still readable
  // by every HDF5 since 1.8 (h5py, HDFView, pandas through h5py).
  Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_libver_bounds(access.get(), H5F_LIBVER_V18, H5F_LIBVER_V110);
  Handle create(H5Pcreate(H5P_FILE_CREATE), H5Pclose);
  H5Pset_attr_phase_change(create.get(), 0, 0);
  w.file = Handle(H5Fcreate(w.tmp.c_str(), H5F_ACC_EXCL, create.get(), access.get()), H5Fclose);
  if (!w.file) w.fail("cannot create " + w.tmp.string());

  for (auto& name : output_columns) {
    Impl::Column column;
    column.link = link_name(name);
    column.name = std::move(name);
    w.columns.push_back(std::move(column));
  }
  Impl::Column status;
  status.name = status.link = "status";
  w.columns.push_back(std::move(status));

  Json columns = Json::array(), keys = Json::array();
  for (std::size_t c = 0; c + 1 < w.columns.size(); ++c) columns.push_back(w.columns[c].name);
  for (const auto& axis : study.grid) keys.push_back(axis.key);
  std::string study_text;
  if (study.inputs)
    if (auto bytes = study.inputs->bytes_of(fs::absolute(study.file).lexically_normal())) study_text = *bytes;
  const std::pair<const char*, std::string> attributes[] = {
      {"chatterlab_results", "1"},
      {"study_fingerprint", provenance.value("study_fingerprint", std::string())},
      {"points", std::to_string(study.point_count())},
      {"columns", json_text(columns)},
      {"grid_keys", json_text(keys)},
      {"inputs", json_text(result_inputs(study))},  // {path: sha256}, as the journal's header
      {"study_file", study.file.string()},
      {"study_text", study_text},
      {"study", json_text(study.document, 2)},
      {"meta", json_text(provenance, 2)}};
  for (const auto& [name, value] : attributes)
    if (!write_text_attribute(w.file.get(), name, value)) w.fail(std::string("attribute ") + name);
  w.row_end = w.layout.row_end(0);
}

Hdf5ResultsWriter::~Hdf5ResultsWriter() { abandon(); }

void Hdf5ResultsWriter::append(PointResult&& result) {
  Impl& w = *impl_;
  if (!w.file || w.next >= w.layout.points || result.outputs.size() + 1 != w.columns.size())
    throw std::logic_error("Hdf5ResultsWriter: point out of order or after commit");
  for (std::size_t c = 0; c < result.outputs.size(); ++c)
    w.columns[c].cells.push_back(std::move(result.outputs[c]));
  w.columns.back().cells.emplace_back(std::move(result.status));
  if (++w.next == w.row_end) w.flush_row();
}

void Hdf5ResultsWriter::commit() {
  Impl& w = *impl_;
  if (!w.file || w.next != w.layout.points)
    throw std::logic_error(fmt::format("Hdf5ResultsWriter: {} of {} points at commit", w.next,
                                       w.layout.points));
  for (Impl::Column& column : w.columns)
    if (!column.dataset) {  // never a value (every point failed): numbers, all NaN
      column.type = CellType::number;
      w.create_column_dataset(column);
    }
  w.write_scales();
  for (Impl::Column& column : w.columns) column.dataset.reset();
  if (H5Fclose(w.file.release()) < 0) w.fail("closing");
  // On the device before it takes the final name, as write_file_atomically does.
  const int fd = ::open(w.tmp.c_str(), O_RDONLY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  const int error = errno;
  if (fd >= 0) ::close(fd);
  std::error_code ec;
  if (!synced || (fs::rename(w.tmp, w.path, ec), ec)) {
    note_failed_output_write();
    fs::remove(w.tmp, ec);
    throw OutputError(fmt::format("cannot write {}: {}", w.path.string(),
                                  synced ? ec.message() : std::strerror(error)));
  }
  w.committed = true;
}

void Hdf5ResultsWriter::abandon() noexcept {
  Impl& w = *impl_;
  if (w.committed) return;
  for (Impl::Column& column : w.columns) column.dataset.reset();
  w.file.reset();
  std::error_code ignored;
  fs::remove(w.tmp, ignored);
}

const fs::path& Hdf5ResultsWriter::temporary_path() const { return impl_->tmp; }

struct Hdf5ResultsReader::Impl {
  struct Source {
    Handle dataset;
    H5T_class_t type_class = H5T_NO_CLASS;
    std::size_t width = 0;
  };
  fs::path path;
  Handle file;
  JournalHeader header;
  std::vector<std::size_t> shape;
  std::unique_ptr<Layout> layout;
  std::vector<Source> sources;  // one per output column, then status
  std::vector<std::string> links;
  std::size_t next = 0;

  std::runtime_error fail(const std::string& what) const {
    return std::runtime_error(fmt::format("{}: {}", path.string(), what));
  }
};

Hdf5ResultsReader::Hdf5ResultsReader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  silence_hdf5_errors();
  Impl& in = *impl_;
  in.path = path;
  in.file = Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!in.file) throw in.fail("not an HDF5 file (" + hdf5_error_stack() + ")");
  const hid_t file = in.file.get();
  if (read_text_attribute(file, "chatterlab_results") != "1")
    throw in.fail("not a chatterlab results.h5 (no attribute chatterlab_results = 1)");
  in.header.study_fingerprint = read_text_attribute(file, "study_fingerprint");
  try {
    in.header.points = std::stoull(read_text_attribute(file, "points"));
    for (const Json& c : Json::parse(read_text_attribute(file, "columns")))
      in.header.columns.push_back(c.get<std::string>());
    in.header.inputs = Json::parse(read_text_attribute(file, "inputs"));
  } catch (const std::exception& e) {
    throw in.fail(std::string("unreadable attributes: ") + e.what());
  }
  for (const auto& name : in.header.columns) in.links.push_back(link_name(name));
  in.links.push_back("status");
  for (const auto& link : in.links) {
    Impl::Source source;
    source.dataset = Handle(H5Dopen2(file, link.c_str(), H5P_DEFAULT), H5Dclose);
    if (!source.dataset) throw in.fail("no dataset " + link);
    Handle type(H5Dget_type(source.dataset.get()), H5Tclose);
    source.type_class = H5Tget_class(type.get());
    source.width = H5Tget_size(type.get());
    in.sources.push_back(std::move(source));
  }
  if (in.sources.back().type_class != H5T_STRING) throw in.fail("status is not text");
  Handle space(H5Dget_space(in.sources.back().dataset.get()), H5Sclose);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  for (hsize_t d : dims) in.shape.push_back(static_cast<std::size_t>(d));
  in.layout = std::make_unique<Layout>(dims);
  if (in.layout->points != in.header.points) throw in.fail("status has another shape than the grid");
}

Hdf5ResultsReader::~Hdf5ResultsReader() = default;

const JournalHeader& Hdf5ResultsReader::header() const { return impl_->header; }
const std::vector<std::size_t>& Hdf5ResultsReader::shape() const { return impl_->shape; }
std::size_t Hdf5ResultsReader::position() const { return impl_->next; }

std::vector<PointResult> Hdf5ResultsReader::next_chunk_row(bool status_only) {
  Impl& in = *impl_;
  const Layout& layout = *in.layout;
  if (in.next >= layout.points) return {};
  const std::size_t begin = in.next, end = layout.row_end(begin), count = end - begin;
  const std::size_t columns = in.header.columns.size();
  std::vector<PointResult> rows(count);
  for (PointResult& r : rows) {
    r.done = true;
    r.outputs.resize(columns);
  }
  const hsize_t memory_count = count;
  Handle memory(H5Screate_simple(1, &memory_count, nullptr), H5Sclose);
  for (std::size_t c = status_only ? columns : 0; c < in.sources.size(); ++c) {
    Impl::Source& source = in.sources[c];
    Handle selection = layout.select(source.dataset.get(), begin, end);
    const bool is_status = c == columns;
    herr_t read = -1;
    if (source.type_class == H5T_FLOAT) {
      std::vector<double> values(count);
      read = H5Dread(source.dataset.get(), H5T_NATIVE_DOUBLE, memory.get(), selection.get(),
                     H5P_DEFAULT, values.data());
      for (std::size_t i = 0; i < count && read >= 0; ++i)
        if (!std::isnan(values[i])) rows[i].outputs[c] = values[i];
    } else if (source.type_class == H5T_ENUM) {
      std::vector<std::int8_t> values(count);
      Handle type = boolean_type();
      read = H5Dread(source.dataset.get(), type.get(), memory.get(), selection.get(), H5P_DEFAULT,
                     values.data());
      for (std::size_t i = 0; i < count && read >= 0; ++i) rows[i].outputs[c] = values[i] != 0;
    } else if (source.type_class == H5T_STRING) {
      std::vector<char> buffer(count * source.width);
      Handle type = text_type(source.width);
      read = H5Dread(source.dataset.get(), type.get(), memory.get(), selection.get(), H5P_DEFAULT,
                     buffer.data());
      for (std::size_t i = 0; i < count && read >= 0; ++i) {
        const char* text = buffer.data() + i * source.width;
        std::string value(text, strnlen(text, source.width));
        if (is_status)
          rows[i].status = std::move(value);
        else
          rows[i].outputs[c] = std::move(value);
      }
    }
    if (read < 0) throw in.fail("cannot read dataset " + in.links[c] + " (" + hdf5_error_stack() + ")");
  }
  in.next = end;
  return rows;
}

Hdf5Results read_hdf5_results(const fs::path& path) {
  Hdf5ResultsReader reader(path);
  Hdf5Results out;
  out.header = reader.header();
  out.shape = reader.shape();
  out.records.reserve(out.header.points);
  for (auto rows = reader.next_chunk_row(); !rows.empty(); rows = reader.next_chunk_row()) {
    const std::size_t first = reader.position() - rows.size();
    for (std::size_t i = 0; i < rows.size(); ++i) out.records.emplace_back(first + i, std::move(rows[i]));
  }
  return out;
}

}  // namespace chatterlab::runner

namespace chatterlab {

ResultTable read_results_h5(const Study& study, const std::filesystem::path& results_h5) {
  runner::Hdf5Results file;
  try {
    file = runner::read_hdf5_results(results_h5);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  const std::string fingerprint = runner::study_fingerprint(study, file.header.columns);
  if (file.header.study_fingerprint != fingerprint || file.header.points != study.point_count())
    throw InputError(fmt::format("{}: written by another study than {} ({} points, fingerprint {})",
                                 results_h5.string(), study.file.string(), file.header.points,
                                 file.header.study_fingerprint));
  std::vector<runner::PointResult> results(study.point_count());
  for (auto& [point, result] : file.records) {
    // results.h5 stores a failed point's cells as NaN, FALSE or "" (its status says why);
    // results.csv leaves them empty: null, as the runner had them.
    if (runner::outcome_of(result.status) != runner::PointOutcome::ok)
      for (Json& cell : result.outputs) cell = nullptr;
    results[point] = std::move(result);
  }
  return runner::assemble_results(study, file.header.columns, std::move(results));
}

}  // namespace chatterlab
