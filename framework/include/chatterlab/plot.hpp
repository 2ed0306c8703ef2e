#pragma once
// Plots through gnuplot (a maintained plotting tool, Debian package gnuplot-nox). Each call writes
// <stem>.png and <stem>.svg into out_dir, plus <stem>.gp and <stem>.dat so a user can restyle the
// figure by editing the script. Failures (gnuplot missing or erroring) throw PlotError; study runs
// record them in meta.json and still exit by the points' status.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace chatterlab::plot {

class PlotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Series {
  std::string label;
  std::vector<double> x, y;
  std::string style = "lines";  // lines, points, linespoints, impulses, steps, dashes (dashed lines)
};

struct Curves {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  bool log_x = false, log_y = false;
  std::optional<double> reference_y;  // e.g. 0 = stability limit, drawn dashed
  std::string reference_label;        // key entry of that line; empty: "y = <reference_y>"
  // One unit of x as long as one unit of y (gnuplot `set size ratio -1`): polar plots, where a
  // round part must look round. Not with log axes (PlotError).
  bool equal_aspect = false;
  // x is an index (exponent number, embedding dimension): ticks on whole numbers only, and half
  // a unit of margin so the end points are not drawn on the frame. Linear x only (PlotError).
  bool integer_x = false;
};

// A 2-D map of z over a rectangular grid (z[iy * x.size() + ix]; NaN = failed point, drawn as a
// grey "failed point" cell: blank would read as "at the boundary" in a diverging palette). Each
// value fills the cell between the midpoints to its neighbours (in log space on log axes), so
// non-uniform and log-spaced grids are drawn at their true positions.
struct Heatmap {
  std::string title, x_label, y_label, z_label;
  std::vector<double> x, y, z;
  bool log_x = false, log_y = false;
  std::optional<double> contour_level;  // e.g. 0 = stability boundary, drawn as a black line
  bool diverging = false;               // palette centred on contour_level (blue stable, red not)
  bool symmetric = false;               // diverging colour bar over equal distances either side
  std::string contour_label;  // key entry of the contour line; empty: "<z_label> = <level>"
  // Words at the low and high ends of the colour bar, e.g. "stable" / "chatter", so the meaning
  // of the colours needs no caption; a map entirely on one side of contour_level says so in the
  // picture with them ("every point > 0: chatter"). Empty: none.
  std::string low_label, high_label;
};

void render(const Curves& figure, const std::filesystem::path& out_dir, const std::string& stem);
void render(const Heatmap& figure, const std::filesystem::path& out_dir, const std::string& stem);

}  // namespace chatterlab::plot
