#include "chatterlab/plot.hpp"

// Figures are drawn by gnuplot, not by hand: this file writes the data (<stem>.dat) and a
// self-contained script (<stem>.gp) that renders <stem>.png and <stem>.svg, then runs gnuplot on
// it. The script uses paths relative to out_dir (gnuplot runs there), so a user can edit and
// re-run it with `cd out_dir && gnuplot stem.gp`.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <numeric>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "chatterlab/errors.hpp"
#include "chatterlab/output_files.hpp"

extern char** environ;

namespace chatterlab::plot {
namespace {

namespace fs = std::filesystem;

constexpr int kWidthPx = 1000;
constexpr int kHeightPx = 750;
constexpr std::string_view kFont = "Sans,13";
constexpr std::string_view kTitleFont = ",16";
// Cells of failed points: a neutral grey that is neither a "stable" blue nor a "chatter" red, nor
// the near-white of the boundary.
constexpr std::string_view kFailedGrey = "#969696";
constexpr std::string_view kNeutralWhite = "#f7f7f7";

// A gnuplot double-quoted string. Not single-quoted: gnuplot 5.4 mis-parses the runs of doubled
// quotes that a title like "x'' + x = ..." becomes. Inside double quotes a backslash starts an
// escape, so backslashes and double quotes are escaped. Newlines would end the command, so they
// become spaces. Terminals run `noenhanced`, so '_' and '^' in labels (column names like
// growth_rate_per_s) print literally.
std::string gp_string(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n' || c == '\r') {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// Shortest round-trip text of a number. gnuplot reads "NaN" as an undefined value: a curve is
// broken there (a failed point is not bridged) and a heatmap cell is not drawn.
std::string number(double v) { return std::isfinite(v) ? fmt::format("{}", v) : "NaN"; }

void check_stem(const std::string& stem) {
  if (stem.empty() || stem.find('/') != std::string::npos || stem == "." || stem == "..")
    throw PlotError(fmt::format("plot file stem '{}' must be a plain file name", stem));
}

// Header shared by both figure kinds: provenance, title, axis labels, frame.
std::string script_preamble(const std::string& stem, std::string_view what,
                            const std::string& title, const std::string& x_label,
                            const std::string& y_label) {
  return fmt::format(
      "# {} written by chatterlab from {}.dat.\n"
      "# Re-render after editing: cd into this directory and run `gnuplot {}.gp`.\n"
      "# (chatterlab renders into temporary names, output_suffix, and renames the finished\n"
      "# images, so no reader ever sees half a PNG.)\n"
      "if (!exists(\"output_suffix\")) output_suffix = \"\"\n"
      "set encoding utf8\n"
      "set title {} font '{}'\n"
      "set xlabel {}\nset ylabel {}\n"
      "set border lw 1.2\nset tics out nomirror\n",
      what, stem, stem, gp_string(title), kTitleFont, gp_string(x_label), gp_string(y_label));
}

// A log axis over [low, high] (low > 0). gnuplot labels only powers of ten, which leaves a grid
// spanning less than a few decades (work speed 20..200 rpm) with one or no number on the axis;
// such axes get explicit 1-2-5 ticks (1..9 when even that gives fewer than three). Labels are
// plain numbers between 1e-3 and 1e5, else compact powers ("2e7", not "2e+07").
bool plain_labels(double low, double high) { return low >= 1e-3 && high < 1e5; }
std::string axis_format(bool log_axis, double low, double high) {
  if (!log_axis) return "% h";  // gnuplot's default
  return plain_labels(low, high) ? "%g" : "%.0le%L";
}
std::string log_axis(char axis, double low, double high) {
  const bool plain = plain_labels(low, high);
  std::string gp =
      fmt::format("set logscale {0}\nset format {0} '{1}'\n", axis, axis_format(true, low, high));
  if (!(low > 0) || !(high > low) || high / low > 1e3) return gp;
  auto ticks_with = [&](std::initializer_list<int> mantissas) {
    std::vector<std::string> ticks;
    for (int decade = static_cast<int>(std::floor(std::log10(low)));
         decade <= static_cast<int>(std::ceil(std::log10(high))); ++decade)
      for (int m : mantissas) {
        double tick = m * std::pow(10.0, decade);
        if (tick < low * (1 - 1e-12) || tick > high * (1 + 1e-12)) continue;
        std::string label = plain ? fmt::format("{:g}", tick) : fmt::format("{}e{}", m, decade);
        ticks.push_back(fmt::format("'{}' {:g}", label, tick));
      }
    return ticks;
  };
  std::vector<std::string> ticks = ticks_with({1, 2, 5});
  if (ticks.size() < 3) ticks = ticks_with({1, 2, 3, 4, 5, 6, 7, 8, 9});
  if (ticks.size() >= 2) gp += fmt::format("set {}tics ({})\n", axis, fmt::join(ticks, ", "));
  return gp;
}

// The PNG terminal is set before the `plot` command; script_svg_replot() then repeats that plot
// for the SVG. The SVG gets a white background so it reads the same as the PNG on dark pages.
std::string script_png_terminal(const std::string& stem) {
  return fmt::format(
      "set terminal pngcairo size {},{} noenhanced font '{}' linewidth 1.5\n"
      "set output {}.output_suffix\n",
      kWidthPx, kHeightPx, kFont, gp_string(stem + ".png"));
}
std::string script_svg_replot(const std::string& stem) {
  return fmt::format(
      "set terminal svg size {},{} noenhanced font '{}' linewidth 1.5 background rgb 'white'\n"
      "set output {}.output_suffix\nreplot\nunset output\n",
      kWidthPx, kHeightPx, kFont, gp_string(stem + ".svg"));
}

// Runs `gnuplot -e "output_suffix='<suffix>'" <script>` inside `dir` without a shell (file names
// never meet a command line parser), capturing its diagnostics. gnuplot exits non-zero on any
// script error.
void run_gnuplot(const fs::path& dir, const std::string& script, const std::string& suffix) {
  std::array<int, 2> pipe_fds{};
  if (pipe(pipe_fds.data()) != 0)
    throw PlotError(fmt::format("cannot run gnuplot: pipe: {}", std::strerror(errno)));

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addchdir_np(&actions, dir.c_str());
  // No terminal input: gnuplot must never wait for a keypress.
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[0]);
  posix_spawn_file_actions_addclose(&actions, pipe_fds[1]);

  std::string program = "gnuplot", option = "-e";
  std::string define = fmt::format("output_suffix='{}'", suffix);  // digits and dots only
  std::string script_arg = script;
  std::array<char*, 5> argv{program.data(), option.data(), define.data(), script_arg.data(),
                            nullptr};
  pid_t pid = 0;
  int spawn_error = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (spawn_error != 0) {
    close(pipe_fds[0]);
    throw PlotError(fmt::format(
        "cannot run gnuplot ({}); install it (Debian package gnuplot-nox) or re-render later "
        "with `gnuplot {}` in {}",
        std::strerror(spawn_error), script, dir.string()));
  }

  std::string diagnostics;
  std::array<char, 4096> buffer{};
  for (;;) {
    ssize_t n = read(pipe_fds[0], buffer.data(), buffer.size());
    if (n > 0)
      diagnostics.append(buffer.data(), static_cast<std::size_t>(n));
    else if (n == 0 || errno != EINTR)
      break;
  }
  close(pipe_fds[0]);

  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR)
      throw PlotError(fmt::format("waiting for gnuplot: {}", std::strerror(errno)));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string how = WIFEXITED(status) ? fmt::format("exit status {}", WEXITSTATUS(status))
                                        : fmt::format("killed by signal {}", WTERMSIG(status));
    throw PlotError(
        fmt::format("gnuplot failed on {} ({}):\n{}", (dir / script).string(), how, diagnostics));
  }
}

// True when `file` is a whole image: a PNG ends with its IEND chunk, an SVG with </svg>. A
// gnuplot that ran out of disk space may still exit 0 after writing part of one.
bool complete_image(const fs::path& file, bool png) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec || size < 12) return false;
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(size) - 12);
  std::string tail(12, '\0');
  if (!in.read(tail.data(), 12)) return false;
  if (png) return tail == std::string("\0\0\0\0IEND\xae\x42\x60\x82", 12);
  return tail.find("</svg>") != std::string::npos;
}

// Why no image came out: a disk that takes no more data (full, read-only, I/O errors) is an
// output failure (OutputError, exit 3); anything else (gnuplot missing, a script error) a plot
// failure that meta.json records. Judged by writing a probe of a typical image's size.
[[noreturn]] void image_failure(const fs::path& out_dir, const std::string& what) {
  try {
    const fs::path probe = out_dir / ".chatterlab-write-probe";
    write_file_atomically(probe, std::string(256 * 1024, '\0'));
    std::error_code ignored;
    fs::remove(probe, ignored);
  } catch (const OutputError& e) {
    throw OutputError(fmt::format("{} ({})", what, e.what()));
  }
  throw PlotError(what);
}

// Writes data and script (atomically), runs gnuplot into temporary image names, checks that both
// images are complete and renames them into place: readers never see a partial image, and a
// failure leaves no temporary file behind.
void produce(const fs::path& out_dir, const std::string& stem, const std::string& data,
             const std::string& script) {
  check_stem(stem);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    note_failed_output_write();
    throw OutputError(fmt::format("cannot create {}: {}", out_dir.string(), ec.message()));
  }
  write_file_atomically(out_dir / (stem + ".dat"), data);
  write_file_atomically(out_dir / (stem + ".gp"), script);
  const fs::path png = out_dir / (stem + ".png"), svg = out_dir / (stem + ".svg");
  const fs::path png_tmp = temporary_path_for(png);
  const std::string suffix = png_tmp.string().substr(png.string().size());
  const fs::path svg_tmp = svg.string() + suffix;
  auto remove_temporaries = [&] {
    std::error_code ignored;
    fs::remove(png_tmp, ignored);
    fs::remove(svg_tmp, ignored);
  };
  try {
    run_gnuplot(out_dir, stem + ".gp", suffix);
  } catch (const PlotError& e) {
    remove_temporaries();
    image_failure(out_dir, e.what());
  }
  for (const auto& [image, is_png] : {std::pair{&png_tmp, true}, std::pair{&svg_tmp, false}}) {
    if (!complete_image(*image, is_png)) {
      remove_temporaries();
      image_failure(out_dir, fmt::format("gnuplot reported success but wrote no complete {}",
                                         (is_png ? png : svg).string()));
    }
  }
  for (const auto& [from, to] : {std::pair{&png_tmp, &png}, std::pair{&svg_tmp, &svg}}) {
    fs::rename(*from, *to, ec);
    if (ec) {
      remove_temporaries();
      note_failed_output_write();
      throw OutputError(fmt::format("cannot replace {}: {}", to->string(), ec.message()));
    }
  }
}

// Boundaries of the cells around sorted grid values: midpoints between neighbours (in log10
// space on a log axis, so log-spaced grids get equal-looking cells), the outer cells mirrored.
struct Cell {
  double low, high;
};
std::vector<Cell> cell_edges(const std::vector<double>& sorted_values, bool log_axis) {
  auto to_axis = [&](double v) { return log_axis ? std::log10(v) : v; };
  auto from_axis = [&](double t) { return log_axis ? std::pow(10.0, t) : t; };
  std::vector<double> t(sorted_values.size());
  std::transform(sorted_values.begin(), sorted_values.end(), t.begin(), to_axis);
  std::vector<Cell> cells(t.size());
  if (t.size() == 1) {
    // A single row or column has no neighbour to measure against: a cell of 10 % of the value
    // (a tenth of a decade on log axes) keeps it visible.
    double half = log_axis ? 0.05 : (t[0] != 0.0 ? 0.05 * std::abs(t[0]) : 0.5);
    cells[0] = {from_axis(t[0] - half), from_axis(t[0] + half)};
    return cells;
  }
  // The outer cells end at the first and last grid values: a cell never claims values outside
  // the swept range (a map from 0 Hz would otherwise show cells at negative frequencies).
  for (std::size_t i = 0; i < t.size(); ++i) {
    double lo = i > 0 ? 0.5 * (t[i - 1] + t[i]) : t[0];
    double hi = i + 1 < t.size() ? 0.5 * (t[i] + t[i + 1]) : t[i];
    cells[i] = {from_axis(lo), from_axis(hi)};
  }
  return cells;
}

// Grid values may be written in any order ({ from = 2000, to = 1000 } or a list): the cells are
// built over the ascending order and z is read through the permutation.
std::vector<std::size_t> ascending_order(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  return order;
}

void check_axis(const std::vector<double>& values, bool log_axis, std::string_view name) {
  if (values.empty()) throw PlotError(fmt::format("heatmap has no {} values", name));
  for (double v : values) {
    if (!std::isfinite(v))
      throw PlotError(fmt::format("heatmap {} value {} is not finite", name, v));
    if (log_axis && v <= 0)
      throw PlotError(fmt::format("heatmap {} value {} cannot be shown on a log axis", name, v));
  }
}

// True when some pair of finite neighbours lies on opposite sides of `level`: only then is there
// a boundary to draw (gnuplot would otherwise plot an empty contour table and warn).
bool crosses_level(const Heatmap& f, double level) {
  std::size_t nx = f.x.size(), ny = f.y.size();
  auto side = [&](std::size_t ix, std::size_t iy) {
    double z = f.z[iy * nx + ix];
    return std::isfinite(z) ? (z >= level ? 1 : -1) : 0;
  };
  for (std::size_t iy = 0; iy < ny; ++iy) {
    for (std::size_t ix = 0; ix < nx; ++ix) {
      int s = side(ix, iy);
      if (s == 0) continue;
      if (ix + 1 < nx && side(ix + 1, iy) == -s) return true;
      if (iy + 1 < ny && side(ix, iy + 1) == -s) return true;
    }
  }
  return false;
}

// The colour scale. Diverging: ColorBrewer RdBu split at the centre level: blues below it, reds
// above it, with a jump between a clearly blue and a clearly red shade exactly at the level, so a
// value just above it (weak chatter) is never drawn in the near-white a reader takes for the
// other side. Each side is stretched over its own data range (so a small chatter region next to a
// deep stable one is still clearly red) unless `symmetric`, where the colour bar runs over the
// same distance either side (ratio maps: a factor of 2 up and down look alike). Otherwise:
// viridis (perceptually uniform, readable in grey print).
std::string palette_commands(const Heatmap& f, double z_min, double z_max) {
  if (!f.diverging) {
    if (z_min == z_max) {
      z_min -= 1;
      z_max += 1;
    }
    return fmt::format(
        "set palette defined (0 '#440154', 0.25 '#3b528b', 0.5 '#21908d', 0.75 '#5dc863', "
        "1 '#fde725')\nset cbrange [{}:{}]\n",
        number(z_min), number(z_max));
  }
  const double centre = f.contour_level.value_or(0.0);
  double lo = std::min(z_min, centre), hi = std::max(z_max, centre);
  if (f.symmetric) {
    const double reach = std::max(centre - lo, hi - centre);
    lo = centre - reach;
    hi = centre + reach;
  }
  if (lo == hi) {
    lo = centre - 1;
    hi = centre + 1;
  }
  constexpr std::array<std::string_view, 3> blues{"#2166ac", "#4393c3", "#92c5de"};
  constexpr std::array<std::string_view, 3> reds{"#f4a582", "#d6604d", "#b2182b"};
  std::vector<std::string> stops;
  // Below the level: dark blue far from it, light blue at it; above: light red at it, dark red
  // far from it. Two stops at the level itself make the jump. gnuplot stretches the stops' span
  // over the colour bar's range, so only a side the range covers gets stops.
  if (lo < centre)
    for (std::size_t k = 0; k < blues.size(); ++k)
      stops.push_back(fmt::format("{} '{}'", number(lo + (centre - lo) * double(k) / 2.0), blues[k]));
  if (hi > centre)
    for (std::size_t k = 0; k < reds.size(); ++k)
      stops.push_back(fmt::format("{} '{}'", number(centre + (hi - centre) * double(k) / 2.0), reds[k]));
  return fmt::format("set palette defined ({})\nset cbrange [{}:{}]\n", fmt::join(stops, ", "),
                     number(lo), number(hi));
}

}  // namespace

// Line styles 1-8: the Okabe-Ito colours, distinguishable with the common colour-vision
// deficiencies.
std::string line_styles() {
  constexpr std::array<std::string_view, 8> kColours{"#0072b2", "#d55e00", "#009e73", "#cc79a7",
                                                     "#e69f00", "#56b4e9", "#000000", "#f0e442"};
  std::string gp;
  for (std::size_t i = 0; i < kColours.size(); ++i)
    gp += fmt::format("set style line {} lc rgb '{}' lw 2 pt 7 ps 0.9\n", i + 1, kColours[i]);
  return gp;
}

// The plot command's style of a series: the style word, its line style (palette place, or its own
// colour and width) and, for an area, a translucent fill down to the bottom of the plot.
std::string series_style(const Series& s, const SeriesLook& look, std::size_t index) {
  const bool dashes = s.style == "dashes", area = s.style == "area" || s.style == "area_above";
  const std::string word = dashes ? "lines" : s.style == "area" ? "filledcurves x1" : s.style == "area_above" ? "filledcurves x2" : s.style;
  std::string style = fmt::format("with {} ls {}", word, index % 8 + 1);
  if (!look.colour.empty()) style += fmt::format(" lc rgb '{}'", look.colour);
  if (look.line_width > 0.0) style += fmt::format(" lw {}", number(look.line_width));
  // "dashes": a dash pattern (after the line style, which would reset it), for a curve drawn over
  // another that may hide it.
  if (dashes) style += " dt 2";
  if (area) style += " fs transparent solid 0.25 noborder";
  return style;
}

// The look of series i (defaults when the list is shorter), checked.
SeriesLook look_of(const std::vector<SeriesLook>& looks, std::size_t i, const Series& s) {
  const SeriesLook look = i < looks.size() ? looks[i] : SeriesLook{};
  const bool hex = look.colour.size() == 7 && look.colour[0] == '#' &&
                   std::all_of(look.colour.begin() + 1, look.colour.end(),
                               [](char c) { return std::isxdigit(static_cast<unsigned char>(c)); });
  if (!look.colour.empty() && !hex)
    throw PlotError(fmt::format("series '{}': colour '{}' is not #rrggbb", s.label, look.colour));
  if (!(look.line_width >= 0.0 && look.line_width <= 20.0))
    throw PlotError(fmt::format("series '{}': line width {} is not in [0, 20]", s.label, look.line_width));
  return look;
}

void render(const Curves& figure, const fs::path& out_dir, const std::string& stem) {
  static constexpr std::array<std::string_view, 8> kStyles{"lines", "points", "linespoints", "impulses",
                                                           "steps", "dashes", "area", "area_above"};
  if (figure.series.empty()) throw PlotError(fmt::format("plot '{}' has no series", stem));
  if (figure.equal_aspect && (figure.log_x || figure.log_y))
    throw PlotError(fmt::format("plot '{}': equal aspect needs linear axes", stem));
  if (figure.integer_x && figure.log_x)
    throw PlotError(fmt::format("plot '{}': an integer x axis must be linear", stem));

  std::string data =
      fmt::format("# {}: one block per series (gnuplot index), columns x y\n", figure.title);
  std::vector<std::string> plots;
  for (std::size_t i = 0; i < figure.series.size(); ++i) {
    const Series& s = figure.series[i];
    if (s.x.size() != s.y.size())
      throw PlotError(fmt::format("series '{}' has {} x values but {} y values", s.label,
                                  s.x.size(), s.y.size()));
    // The style is pasted into the script, so only known words are accepted.
    if (std::find(kStyles.begin(), kStyles.end(), s.style) == kStyles.end())
      throw PlotError(fmt::format("series '{}': unknown style '{}' (valid: {})", s.label, s.style,
                                  fmt::join(kStyles, ", ")));
    const SeriesLook look = look_of(figure.looks, i, s);
    data += fmt::format("{}# series {}: {}\n", i == 0 ? "" : "\n\n", i, s.label);
    for (std::size_t k = 0; k < s.x.size(); ++k)
      data += fmt::format("{} {}\n", number(s.x[k]), number(s.y[k]));
    plots.push_back(fmt::format("'{}.dat' index {} using 1:2{} {} title {}", stem, i, s.right_axis ? " axes x1y2" : "",
                                series_style(s, look, i), s.label.empty() ? "\"\"" : gp_string(s.label)));
  }
  // A reference at y <= 0 does not exist on a log y axis (gnuplot would fail on it).
  const bool reference = figure.reference_y && !(figure.log_y && *figure.reference_y <= 0);
  constexpr const char* reference_style = "dt 2 lw 1.5 lc rgb 'black'";
  if (reference) {
    std::string label = figure.reference_label.empty()
                            ? fmt::format("y = {}", number(*figure.reference_y))
                            : figure.reference_label;
    // A function is drawn over the data's x range only; on an integer axis, whose half-unit
    // margins lie outside it, the line is an arrow from frame to frame (set below) and the
    // function is NaN: only its key entry shows.
    plots.push_back(fmt::format("{} with lines {} title {}",
                                figure.integer_x ? "NaN" : number(*figure.reference_y),
                                reference_style, gp_string(label)));
  }

  std::string gp = script_preamble(stem, "Curves", figure.title, figure.x_label, figure.y_label);
  const bool right_axis = std::any_of(figure.series.begin(), figure.series.end(),
                                      [](const Series& s) { return s.right_axis; });
  if (right_axis) {
    if (figure.equal_aspect || figure.log_y)
      throw PlotError(fmt::format("plot '{}': a right-hand axis needs a linear, free y axis", stem));
    // The right axis spans its own data with the same 5 % headroom as the left one.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Series& s : figure.series)
      if (s.right_axis)
        for (double v : s.y)
          if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    const double pad = hi > lo ? 0.05 * (hi - lo) : (std::isfinite(lo) ? std::max(1.0, std::abs(lo)) * 0.05 : 1.0);
    gp += fmt::format("set y2label {}\nset y2tics out nomirror\nset ytics nomirror\n", gp_string(figure.y2_label));
    if (std::isfinite(lo)) gp += fmt::format("set y2range [{}:{}]\n", number(lo - pad), number(hi + pad));
  }
  if (figure.log_x || figure.log_y) {
    // Ticks are chosen over the positive data (gnuplot drops the rest on a log axis).
    auto positive_range = [&](auto member) {
      double lo = std::numeric_limits<double>::infinity(), hi = 0;
      for (const Series& s : figure.series)
        for (double v : s.*member)
          if (std::isfinite(v) && v > 0) lo = std::min(lo, v), hi = std::max(hi, v);
      return std::pair{lo, hi};
    };
    if (figure.log_x) {
      auto [lo, hi] = positive_range(&Series::x);
      gp += log_axis('x', lo, hi);
    }
    if (figure.log_y) {
      auto [lo, hi] = positive_range(&Series::y);
      gp += log_axis('y', lo, hi);
    }
  }
  gp += line_styles();
  // The key sits below the x label, two entries per row, with the bottom margin reserved for its
  // rows: beside the plot a long label ("stability limit (Re s = 0)") would squeeze the curves.
  const std::size_t key_rows = (plots.size() + 1) / 2;
  gp += fmt::format(
      "set key at screen 0.5, screen 0.015 center bottom horizontal maxcols 2 Left reverse\n"
      "set bmargin at screen {:.3f}\n",
      0.12 + 0.035 * static_cast<double>(key_rows));
  // Light grid; the axes span the data (not the next whole tick, which on a log axis can waste
  // most of a decade), y with 5 % headroom so extremes do not touch the frame.
  gp +=
      "set style line 100 lc rgb '#e0e0e0' lw 1 dt 1\nset grid ls 100\n"
      "set autoscale xfix\nset autoscale yfix\n";
  // Equal aspect: the same 5 % margin on all sides, so a circle centred in the data is centred
  // in the frame; gnuplot then shrinks one axis' box until the units match.
  gp += figure.equal_aspect ? "set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n"
                              "set size ratio -1\n"
                            : figure.integer_x
                                  ? "set offsets 0.5, 0.5, graph 0.05, graph 0.05\n"
                                  : "set offsets graph 0, graph 0, graph 0.05, graph 0.05\n";
  if (figure.y_range) {
    if (!(figure.y_range->first < figure.y_range->second) || (figure.log_y && !(figure.y_range->first > 0.0)))
      throw PlotError(fmt::format("plot '{}': y range [{}, {}] is empty or not positive on a log axis", stem,
                                  figure.y_range->first, figure.y_range->second));
    gp += fmt::format("set yrange [{}:{}]\n", number(figure.y_range->first), number(figure.y_range->second));
  }
  // Whole-number ticks: gnuplot would label an index axis 1, 1.2, 1.4, ... over a short range.
  if (figure.integer_x) gp += "set xtics 1\nset mxtics 1\n";
  // The integer axis' reference line; the y range still reaches it ("*<y": the autoscaled
  // minimum at most y, "y<*": the maximum at least y), as it would for the function.
  if (figure.integer_x && reference)
    gp += fmt::format(
        "set yrange [*<{0}:{0}<*]\nset arrow from graph 0, first {0} to graph 1, first {0} "
        "nohead {1}\n",
        number(*figure.reference_y), reference_style);
  gp += script_png_terminal(stem);
  gp += fmt::format("plot {}\n", fmt::join(plots, ", \\\n     "));
  gp += script_svg_replot(stem);
  produce(out_dir, stem, data, gp);
}

// Above this many cells a map is drawn as a raster image (gnuplot `with image`: one embedded
// picture in the SVG, whatever the cell count) instead of one box per cell; below it boxes keep
// exact cell edges on uneven axes. A uniform axis is needed for an image.
constexpr std::size_t kMaxBoxCells = 20000;

bool evenly_spaced(const std::vector<double>& sorted_values) {
  if (sorted_values.size() < 3) return true;
  const double step = (sorted_values.back() - sorted_values.front()) /
                      static_cast<double>(sorted_values.size() - 1);
  for (std::size_t i = 1; i < sorted_values.size(); ++i)
    if (std::abs(sorted_values[i] - sorted_values[i - 1] - step) > 1e-6 * std::abs(step)) return false;
  return true;
}

void render(const Heatmap& figure, const fs::path& out_dir, const std::string& stem) {
  check_axis(figure.x, figure.log_x, "x");
  check_axis(figure.y, figure.log_y, "y");
  const std::size_t nx = figure.x.size(), ny = figure.y.size();
  if (figure.z.size() != nx * ny)
    throw PlotError(fmt::format("heatmap '{}' has {} z values for a {} x {} grid", stem,
                                figure.z.size(), nx, ny));

  const auto x_order = ascending_order(figure.x), y_order = ascending_order(figure.y);
  std::vector<double> xs(nx), ys(ny);
  for (std::size_t i = 0; i < nx; ++i) xs[i] = figure.x[x_order[i]];
  for (std::size_t j = 0; j < ny; ++j) ys[j] = figure.y[y_order[j]];
  const auto x_cells = cell_edges(xs, figure.log_x), y_cells = cell_edges(ys, figure.log_y);
  const bool raster = nx * ny > kMaxBoxCells && !figure.log_x && !figure.log_y &&
                      evenly_spaced(xs) && evenly_spaced(ys);

  // One block per y row (blank line between), the layout gnuplot's splot needs for contouring.
  std::string data = fmt::format("# {}\n# x y z{}  (z: {}; NaN = failed)\n", figure.title,
                                 raster ? "" : " x_low x_high y_low y_high", figure.z_label);
  double z_min = std::numeric_limits<double>::infinity(), z_max = -z_min;
  bool any_failed = false;
  for (std::size_t j = 0; j < ny; ++j) {
    if (j > 0) data += '\n';
    for (std::size_t i = 0; i < nx; ++i) {
      double z = figure.z[y_order[j] * nx + x_order[i]];
      if (std::isfinite(z)) {
        z_min = std::min(z_min, z);
        z_max = std::max(z_max, z);
      } else {
        any_failed = true;
      }
      if (raster)
        data += fmt::format("{} {} {}\n", number(xs[i]), number(ys[j]), number(z));
      else
        data += fmt::format("{} {} {} {} {} {} {}\n", number(xs[i]), number(ys[j]), number(z),
                            number(x_cells[i].low), number(x_cells[i].high),
                            number(y_cells[j].low), number(y_cells[j].high));
    }
  }
  const bool any_finite = std::isfinite(z_min);
  if (!any_finite) z_min = z_max = figure.contour_level.value_or(0.0);

  std::string gp = script_preamble(stem, "Heatmap", figure.title, figure.x_label, figure.y_label);
  if (figure.log_x) gp += log_axis('x', x_cells.front().low, x_cells.back().high);
  if (figure.log_y) gp += log_axis('y', y_cells.front().low, y_cells.back().high);
  // Fixed layout: plot area, colour bar with its end labels, and the key below the x label never
  // collide, whatever the tick label widths.
  gp +=
      "set lmargin at screen 0.11\nset rmargin at screen 0.79\n"
      "set bmargin at screen 0.15\nset tmargin at screen 0.90\n"
      "set colorbox vertical user origin screen 0.835, screen 0.15 size screen 0.03, screen 0.75\n"
      "set key at screen 0.45, screen 0.025 center bottom horizontal samplen 3\n";
  gp += fmt::format("set xrange [{}:{}]\nset yrange [{}:{}]\n", number(x_cells.front().low),
                    number(x_cells.back().high), number(y_cells.front().low),
                    number(y_cells.back().high));
  gp += fmt::format("set cblabel {}\n", gp_string(figure.z_label));
  if (!figure.high_label.empty())
    gp += fmt::format("set label {} at screen 0.85, screen 0.92 center\n",
                      gp_string(figure.high_label));
  if (!figure.low_label.empty())
    gp += fmt::format("set label {} at screen 0.85, screen 0.12 center\n",
                      gp_string(figure.low_label));
  gp += palette_commands(figure, z_min, z_max);
  // Each cell is a box from its edges, coloured by z. The box border is drawn in the fill colour:
  // without it anti-aliasing leaves hairline seams between neighbouring cells. A failed cell
  // (z written as NaN) gets an undefined x and is skipped here (gnuplot would paint it with an
  // arbitrary palette colour), then drawn grey by its own plot.
  // A raster map paints the same cells as one image per layer: palette colours, then a layer
  // that is opaque only where a cell is failed (grey) or exactly at the level (neutral).
  auto rgb_layer = [&](std::string_view colour, const std::string& where, const std::string& title) {
    const unsigned rgb = static_cast<unsigned>(std::stoul(std::string(colour.substr(1)), nullptr, 16));
    const std::string alpha = fmt::format("({} ? 255 : 0)", where);
    return fmt::format("'{}.dat' using 1:2:({}):({}):({}):{} with rgbalpha title {}", stem,
                       rgb >> 16, (rgb >> 8) & 255u, rgb & 255u, alpha, title);
  };
  std::vector<std::string> plots{
      raster ? fmt::format("'{}.dat' using 1:2:3 with image notitle", stem)
             : fmt::format("'{}.dat' using (strcol(3) eq 'NaN' ? NaN : $1):2:4:5:6:7:3 with "
                           "boxxyerror lc palette lw 1 fillstyle solid 1.0 border notitle",
                           stem)};
  // A diverging palette jumps from blue to red at the level, so a value exactly at it (no effect,
  // e.g. a modulation of amplitude 0) would take one side's colour: such cells are drawn neutral.
  if (figure.diverging && figure.contour_level &&
      std::any_of(figure.z.begin(), figure.z.end(), [&](double z) { return z == *figure.contour_level; }))
    plots.push_back(
        raster ? rgb_layer(kNeutralWhite, fmt::format("$3 == {}", number(*figure.contour_level)),
                           gp_string(fmt::format("exactly {}", number(*figure.contour_level))))
               : fmt::format("'{}.dat' using ($3 == {} ? $1 : NaN):2:4:5:6:7 with boxxyerror lc "
                             "rgb '{}' lw 1 fillstyle solid 1.0 border title {}",
                             stem, number(*figure.contour_level), kNeutralWhite,
                             gp_string(fmt::format("exactly {}", number(*figure.contour_level)))));
  if (figure.contour_level && nx >= 2 && ny >= 2 && crosses_level(figure, *figure.contour_level)) {
    // gnuplot computes the contour itself (set table into a datablock), from the same data file.
    // The table is written with the axes' tick formats: full precision while it is computed, or
    // a "2e7" label format would snap the boundary to round numbers.
    gp += fmt::format(
        "# The boundary: gnuplot's contour of z at the level, tabulated into $boundary.\n"
        "set format x '%.17g'\nset format y '%.17g'\n"
        "set contour base\nset cntrparam levels discrete {}\nunset surface\n"
        "set table $boundary\nsplot '{}.dat' using 1:2:3 notitle\nunset table\n"
        "unset contour\nset surface\nset format x '{}'\nset format y '{}'\n",
        number(*figure.contour_level), stem,
        axis_format(figure.log_x, x_cells.front().low, x_cells.back().high),
        axis_format(figure.log_y, y_cells.front().low, y_cells.back().high));
    std::string label = figure.contour_label.empty()
                            ? fmt::format("{} = {}", figure.z_label, number(*figure.contour_level))
                            : figure.contour_label;
    plots.push_back(fmt::format("$boundary using 1:2 with lines lc rgb 'black' lw 2.5 title {}",
                                gp_string(label)));
  }
  if (any_failed)
    plots.push_back(
        raster ? rgb_layer(kFailedGrey, "strcol(3) eq 'NaN'", gp_string(figure.missing_label))
               : fmt::format("'{}.dat' using (strcol(3) eq 'NaN' ? $1 : NaN):2:4:5:6:7 with "
                             "boxxyerror lc rgb '{}' lw 1 fillstyle solid 1.0 border title {}",
                             stem, kFailedGrey, gp_string(figure.missing_label)));
  // Curves over the map, as inline data blocks (the map's data file is read whole).
  if (!figure.overlays.empty()) gp += line_styles();
  for (std::size_t i = 0; i < figure.overlays.size(); ++i) {
    const Series& o = figure.overlays[i];
    const SeriesLook look = look_of(figure.overlay_looks, i, o);
    if (o.x.size() != o.y.size() || (o.style != "lines" && o.style != "points" && o.style != "dashes"))
      throw PlotError(fmt::format("overlay '{}': needs as many x as y values and style lines, points or dashes", o.label));
    gp += fmt::format("$overlay{} << EOD\n", i);
    for (std::size_t k = 0; k < o.x.size(); ++k) gp += fmt::format("{} {}\n", number(o.x[k]), number(o.y[k]));
    gp += "EOD\n";
    plots.push_back(fmt::format("$overlay{} using 1:2 {} title {}", i, series_style(o, look, i + 6), gp_string(o.label)));
  }
  if (!any_finite) gp += "set label 'no point succeeded' at graph 0.5, graph 0.5 center front\n";
  // A map with a level to compare against but no point on one side of it has no boundary to
  // draw: say so in the picture, or a reader looks for a boundary that is not there.
  if (any_finite && figure.contour_level && (z_min > *figure.contour_level || z_max < *figure.contour_level)) {
    const bool above = z_min > *figure.contour_level;
    const std::string side = above ? figure.high_label : figure.low_label;
    gp += fmt::format(
        "set style textbox opaque border\nset label {} at graph 0.5, graph 0.5 center front boxed\n",
        gp_string(fmt::format("every point {} {}{}", above ? ">" : "<", number(*figure.contour_level),
                              side.empty() ? "" : ": " + side)));
  }
  gp += script_png_terminal(stem);
  gp += fmt::format("plot {}\n", fmt::join(plots, ", \\\n     "));
  gp += script_svg_replot(stem);
  produce(out_dir, stem, data, gp);
}

}  // namespace chatterlab::plot
