#pragma once
// Plots through gnuplot (a maintained plotting tool, Debian package gnuplot-nox). Each call writes
// <stem>.png and <stem>.svg into out_dir, plus <stem>.gp and <stem>.dat so a user can restyle the
// figure by editing the script. Failures (gnuplot missing or erroring) throw PlotError; study runs
// record them in meta.json and still exit by the points' status.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace chatterlab::plot {

class PlotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Series {
  std::string label;
  std::vector<double> x, y;
  // lines, points, linespoints, impulses, steps, dashes (dashed lines), area / area_above (the
  // region between the curve and the bottom / top of the plot, filled translucent: put it first,
  // series are drawn in order)
  std::string style = "lines";
  bool right_axis = false;  // drawn against the right-hand y axis (Curves::y2_label)
};

// How a series is drawn beyond its style (Curves::looks, Heatmap::overlay_looks).
struct SeriesLook {
  std::string colour;       // "#rrggbb"; empty: the series' place in the palette
  double line_width = 0.0;  // 0: the style's default (2)
};

struct Curves {
  std::string title, x_label, y_label;
  // A second quantity on its own right-hand axis (e.g. a deviation in um beside a radius in mm):
  // its label; the series with right_axis = true are drawn against it.
  std::string y2_label;
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
  // looks[i] (when present) sets the colour and width of series[i].
  std::vector<SeriesLook> looks;
  // A fixed y range [low, high] instead of the data's (curves beyond it are clipped).
  std::optional<std::pair<double, double>> y_range;
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
  std::string missing_label = "failed point";  // key entry of the grey NaN cells
  std::vector<Series> overlays;  // curves drawn over the map (lines, points or dashes)
  std::vector<SeriesLook> overlay_looks;
};

void render(const Curves& figure, const std::filesystem::path& out_dir, const std::string& stem);
void render(const Heatmap& figure, const std::filesystem::path& out_dir, const std::string& stem);

}  // namespace chatterlab::plot
