// plot.hpp through the real gnuplot: the figures are rendered into the build tree
// (<build>/tests/plot_test/) so they can be looked at after a test run.
#include "chatterlab/plot.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using chatterlab::plot::Curves;
using chatterlab::plot::Heatmap;
using chatterlab::plot::PlotError;
using chatterlab::plot::render;
using chatterlab::plot::Series;

Series series(std::string label, std::vector<double> x, std::vector<double> y,
              std::string style = "lines") {
  Series s;
  s.label = std::move(label);
  s.x = std::move(x);
  s.y = std::move(y);
  s.style = std::move(style);
  return s;
}

fs::path output_dir(const std::string& test) {
  fs::path dir = fs::path(CHATTERLAB_TEST_BINARY_DIR) / "plot_test" / test;
  fs::remove_all(dir);
  return dir;
}

// The PlotError message of rendering `figure` (and a test failure if nothing is thrown).
template <class Figure>
std::string plot_error(const Figure& figure, const fs::path& dir, const std::string& stem) {
  try {
    render(figure, dir, stem);
  } catch (const PlotError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected PlotError for plot '" << stem << "'";
  return {};
}

std::string read_all(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A real PNG (signature) of the requested size (IHDR width/height, big-endian) with content: an
// empty 1000x750 canvas compresses to a few kB, a coloured map to far more.
void expect_png(const fs::path& file, std::size_t min_bytes) {
  std::string png = read_all(file);
  ASSERT_GE(png.size(), 24u) << file;
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << file;
  auto be32 = [&](std::size_t at) {
    return (unsigned(static_cast<unsigned char>(png[at])) << 24) |
           (unsigned(static_cast<unsigned char>(png[at + 1])) << 16) |
           (unsigned(static_cast<unsigned char>(png[at + 2])) << 8) |
           unsigned(static_cast<unsigned char>(png[at + 3]));
  };
  EXPECT_EQ(be32(16), 1000u) << file;
  EXPECT_EQ(be32(20), 750u) << file;
  EXPECT_GE(png.size(), min_bytes) << file;
}

// A stability-map-like field: growth rate over wheel speed x work speed with chatter islands, the
// boundary at 0, and two failed points.
Heatmap growth_rate_map(bool log_y) {
  Heatmap map;
  map.title = "Plunge grinding stability map (operator's test)";
  map.x_label = "wheel_speed_rpm";
  map.y_label = "work_speed_rpm";
  map.z_label = "growth rate [1/s]";
  map.contour_level = 0.0;
  map.contour_label = "stability boundary";
  map.diverging = true;
  map.low_label = "stable";
  map.high_label = "chatter";
  map.log_y = log_y;
  for (int i = 0; i < 41; ++i) map.x.push_back(1000.0 + 25.0 * i);
  for (int j = 0; j < 31; ++j)
    map.y.push_back(log_y ? 20.0 * std::pow(10.0, j / 30.0) : 20.0 + 6.0 * j);
  for (double y : map.y)
    for (double x : map.x)
      map.z.push_back(40.0 * std::sin(x / 90.0) * std::cos(y / 25.0) - 25.0 + 0.01 * (x - 1000.0));
  map.z[5 * map.x.size() + 7] = std::numeric_limits<double>::quiet_NaN();
  map.z[5 * map.x.size() + 8] = std::numeric_limits<double>::quiet_NaN();
  return map;
}

TEST(Plot, HeatmapWritesPngSvgScriptAndData) {
  fs::path dir = output_dir("heatmap");
  render(growth_rate_map(false), dir, "stability_map");
  expect_png(dir / "stability_map.png", 30000);
  std::string svg = read_all(dir / "stability_map.svg");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  EXPECT_NE(svg.find("stability boundary"), std::string::npos);
  EXPECT_NE(svg.find("failed point"), std::string::npos);
  EXPECT_NE(svg.find("chatter"), std::string::npos);
  // The two failed cells and their key sample are grey, not painted with a palette colour.
  std::size_t grey_boxes = 0;
  for (std::size_t at = 0; (at = svg.find("fill = 'rgb(150, 150, 150)'", at)) != std::string::npos;
       ++at)
    ++grey_boxes;
  EXPECT_EQ(grey_boxes, 3u);
  std::string gp = read_all(dir / "stability_map.gp");
  // The contour is drawn at the requested level, and the palette jumps there from a clearly blue
  // to a clearly red shade (weak chatter never looks like the near-white of "stable").
  EXPECT_NE(gp.find("set cntrparam levels discrete 0\n"), std::string::npos) << gp;
  EXPECT_NE(gp.find("0 '#92c5de', 0 '#f4a582'"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("#f7f7f7"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("every point"), std::string::npos) << gp;  // it has a boundary
  // The title goes into a double-quoted gnuplot string; a single quote needs no escaping there.
  EXPECT_NE(gp.find("\"Plunge grinding stability map (operator's test)\""), std::string::npos);
  std::string dat = read_all(dir / "stability_map.dat");
  EXPECT_NE(dat.find(" NaN "), std::string::npos);
}

TEST(Plot, HeatmapOnLogAxisAndWithoutCrossingSkipsContour) {
  fs::path dir = output_dir("heatmap_log");
  Heatmap map = growth_rate_map(true);
  render(map, dir, "log_map");
  expect_png(dir / "log_map.png", 30000);
  std::string gp = read_all(dir / "log_map.gp");
  EXPECT_NE(gp.find("set logscale y"), std::string::npos);
  // One decade of work speed: gnuplot alone would label only "100".
  EXPECT_NE(gp.find("set ytics ('20' 20, '50' 50, '100' 100, '200' 200)\n"), std::string::npos)
      << gp;

  // Entirely stable: no boundary exists, so no contour pass and no key entry for it.
  for (double& z : map.z) z = -std::abs(z) - 1.0;
  render(map, dir, "all_stable");
  expect_png(dir / "all_stable.png", 20000);
  EXPECT_EQ(read_all(dir / "all_stable.gp").find("set contour"), std::string::npos);
  EXPECT_EQ(read_all(dir / "all_stable.svg").find("stability boundary"), std::string::npos);
  // ... and the picture says that every point is on one side, in blues only: the palette's stops
  // span just the colour bar's range (gnuplot stretches the stops over it).
  EXPECT_NE(read_all(dir / "all_stable.svg").find("every point &lt; 0: stable"), std::string::npos);
  EXPECT_EQ(read_all(dir / "all_stable.gp").find("#f4a582"), std::string::npos);
  for (double& z : map.z) z = std::abs(z) + 1.0;
  render(map, dir, "all_chatter");
  EXPECT_EQ(read_all(dir / "all_chatter.gp").find("#92c5de"), std::string::npos);
  EXPECT_NE(read_all(dir / "all_chatter.svg").find("every point > 0: chatter"), std::string::npos);

  // A ratio map centred on 1 with a symmetric colour bar: 0.5 and 1.5 are as far from 1.
  Heatmap ratio;
  ratio.title = "amplitude ratio";
  ratio.x = {0.0, 1.0};
  ratio.y = {1.0, 2.0};
  ratio.z = {0.5, 1.2, 0.9, 1.1};
  ratio.contour_level = 1.0;
  ratio.diverging = true;
  ratio.symmetric = true;
  render(ratio, dir, "ratio");
  EXPECT_NE(read_all(dir / "ratio.gp").find("set cbrange [0.5:1.5]"), std::string::npos)
      << read_all(dir / "ratio.gp");
  // A cell exactly at the level (no effect) is neither blue nor red.
  ratio.z[3] = 1.0;
  render(ratio, dir, "ratio_exact");
  EXPECT_NE(read_all(dir / "ratio_exact.svg").find("exactly 1"), std::string::npos);
  EXPECT_EQ(read_all(dir / "ratio.svg").find("exactly 1"), std::string::npos);
}

// Runs the contour pass of a written heatmap script on its own and returns the boundary points
// gnuplot computed ("x y" per line).
std::vector<std::pair<double, double>> boundary_points(const fs::path& dir,
                                                       const std::string& stem) {
  std::string gp = read_all(dir / (stem + ".gp"));
  std::size_t end = gp.find("unset table\n");
  if (end == std::string::npos) return {};
  std::ofstream(dir / "boundary.gp") << gp.substr(0, end) << "unset table\n"
                                     << "set print 'boundary.txt'\nprint $boundary\n";
  std::string command = "cd '" + dir.string() + "' && gnuplot boundary.gp";
  if (std::system(command.c_str()) != 0) return {};
  std::ifstream in(dir / "boundary.txt");
  std::vector<std::pair<double, double>> points;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    double x = 0, y = 0;
    if (line.empty() || line[0] == '#' || !(fields >> x >> y)) continue;
    points.emplace_back(x, y);
  }
  return points;
}

TEST(Plot, BoundaryIsComputedAtFullPrecisionOnLogAxes) {
  // z = x - 1.5e7 over a log x axis labelled "1e7", "2e7", ...: the boundary is the vertical line
  // x = 1.5e7 and must not snap to a tick label.
  fs::path dir = output_dir("boundary");
  Heatmap map;
  map.title = "boundary precision";
  map.z_label = "z";
  map.log_x = true;
  map.contour_level = 0.0;
  for (int i = 0; i <= 20; ++i) map.x.push_back(1e7 * std::pow(100.0, i / 20.0));
  map.y = {1.0, 2.0, 3.0};
  for (std::size_t j = 0; j < map.y.size(); ++j)
    for (double x : map.x) map.z.push_back(x - 1.5e7);
  render(map, dir, "boundary");
  auto points = boundary_points(dir, "boundary");
  ASSERT_GE(points.size(), 2u);
  for (const auto& [x, y] : points) {
    EXPECT_NEAR(x, 1.5e7, 1.5e7 * 1e-9) << "at y = " << y;
    EXPECT_GE(y, 1.0);
    EXPECT_LE(y, 3.0);
  }
}

TEST(Plot, HeatmapWithEveryPointFailedStillRenders) {
  fs::path dir = output_dir("heatmap_failed");
  Heatmap map = growth_rate_map(false);
  for (double& z : map.z) z = std::numeric_limits<double>::quiet_NaN();
  render(map, dir, "failed");
  expect_png(dir / "failed.png", 10000);
  std::string svg = read_all(dir / "failed.svg");
  EXPECT_NE(svg.find("no point succeeded"), std::string::npos);
  EXPECT_NE(svg.find("failed point"), std::string::npos);
}

TEST(Plot, HeatmapCellsFollowDescendingAndNonUniformGrids) {
  fs::path dir = output_dir("heatmap_order");
  Heatmap map;
  map.title = "descending x";
  map.x = {3.0, 2.0, 0.0};  // as a grid { from = 3, to = 0 } or a list might give them
  map.y = {1.0, 2.0};
  map.z = {30, 20, 0, 31, 21, 1};
  map.z_label = "z";
  render(map, dir, "order");
  std::string dat = read_all(dir / "order.dat");
  // Ascending x with its own z; cell edges at the midpoints 1 and 2.5, outer cells ending at the
  // first and last values (never outside the swept range).
  EXPECT_NE(dat.find("0 1 0 0 1 1 1.5\n2 1 20 1 2.5 1 1.5\n3 1 30 2.5 3 1 1.5\n"),
            std::string::npos)
      << dat;
}

TEST(Plot, CurvesWithReferenceLine) {
  fs::path dir = output_dir("curves");
  Curves curves;
  curves.title = "Growth rate along wheel speed";
  curves.x_label = "wheel_speed_rpm";
  curves.y_label = "growth rate [1/s]";
  curves.reference_y = 0.0;
  curves.reference_label = "stability limit";
  for (int k = 0; k < 3; ++k) {
    Series s = series("work speed " + std::to_string(40 + 10 * k) + " rpm", {}, {},
                      k == 0 ? "linespoints" : k == 1 ? "lines" : "dashes");
    for (int i = 0; i < 60; ++i) {
      double x = 1000.0 + 20.0 * i;
      s.x.push_back(x);
      s.y.push_back(30.0 * std::sin(x / (80.0 + 10.0 * k)) - 10.0 * k);
    }
    curves.series.push_back(s);
  }
  curves.series[1].y[10] = std::numeric_limits<double>::quiet_NaN();  // a failed point: a gap
  render(curves, dir, "growth_rate");
  expect_png(dir / "growth_rate.png", 20000);
  std::string svg = read_all(dir / "growth_rate.svg");
  for (const char* text : {"work speed 40 rpm", "work speed 60 rpm", "stability limit"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  std::string dat = read_all(dir / "growth_rate.dat");
  EXPECT_NE(dat.find("# series 2: work speed 60 rpm"), std::string::npos);
  // "dashes" is gnuplot's lines with a dash pattern.
  const std::string gp = read_all(dir / "growth_rate.gp");
  EXPECT_NE(gp.find("index 2 using 1:2 with lines ls 3 dt 2"), std::string::npos) << gp;
  EXPECT_NE(gp.find("index 1 using 1:2 with lines ls 2"), std::string::npos) << gp;
}

// A second quantity on its own right-hand axis (a deviation in um beside a radius in mm): its
// series are drawn against y2, the axis is labelled and spans its own data with 5 % headroom.
TEST(Plot, RightAxisCarriesItsOwnQuantity) {
  fs::path dir = output_dir("right_axis");
  Curves curves;
  curves.title = "part and deviation";
  curves.x_label = "x [mm]";
  curves.y_label = "radius [mm]";
  curves.y2_label = "deviation [um]";
  Series radius = series("radius (left)", {0, 1, 2, 3}, {130, 129, 128, 130});
  Series deviation = series("deviation (right)", {0, 1, 2, 3}, {-2, 18, 1, 0});
  deviation.right_axis = true;
  curves.series = {radius, deviation};
  render(curves, dir, "right_axis");
  expect_png(dir / "right_axis.png", 10000);
  const std::string gp = read_all(dir / "right_axis.gp");
  EXPECT_NE(gp.find("set y2label \"deviation [um]\""), std::string::npos) << gp;
  EXPECT_NE(gp.find("set y2tics"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set y2range [-3:19]"), std::string::npos) << gp;
  EXPECT_NE(gp.find("index 1 using 1:2 axes x1y2 with lines"), std::string::npos) << gp;
  EXPECT_EQ(gp.find("index 0 using 1:2 axes"), std::string::npos) << gp;
  EXPECT_NE(read_all(dir / "right_axis.svg").find("deviation [um]"), std::string::npos);
  // A right axis and an equal aspect (or log y) do not go together.
  curves.equal_aspect = true;
  EXPECT_THROW(render(curves, dir, "right_axis_aspect"), PlotError);
}

TEST(Plot, IntegerXAxisTicksWholeNumbersWithMargins) {
  // Two Lyapunov exponents: gnuplot alone would tick 1, 1.2, ..., 2 and draw both end points on
  // the frame.
  const fs::path dir = output_dir("integer_x");
  Curves curves;
  curves.integer_x = true;
  curves.reference_y = 0.0;
  curves.series = {series("lambda_i", {1, 2}, {0.42, -1.62}, "linespoints")};
  render(curves, dir, "spectrum");
  expect_png(dir / "spectrum.png", 10000);
  const std::string gp = read_all(dir / "spectrum.gp");
  EXPECT_NE(gp.find("set offsets 0.5, 0.5,"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set xtics 1\n"), std::string::npos) << gp;
  // The y = 0 line crosses the margins too, not only the data's x range, and keeps its key.
  EXPECT_NE(gp.find("set arrow from graph 0, first 0 to graph 1, first 0 nohead"),
            std::string::npos)
      << gp;
  const std::string svg = read_all(dir / "spectrum.svg");
  EXPECT_NE(svg.find("y = 0"), std::string::npos);
  // Tick labels are "<text> 1</text>" in gnuplot's SVG; without integer_x: 1, 1.2, ..., 2.
  EXPECT_NE(svg.find("<text> 1</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("<text> 2</text>"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("<text> 1.2</text>"), std::string::npos) << "fractional tick on an index axis";

  // All data below the reference: the y range still reaches up to it.
  curves.series = {series("lambda_i", {1, 2, 3}, {-0.2, -0.9, -14.5}, "linespoints")};
  render(curves, dir, "negative");
  EXPECT_NE(read_all(dir / "negative.gp").find("set yrange [*<0:0<*]"), std::string::npos);
  expect_png(dir / "negative.png", 10000);

  curves.log_x = true;
  EXPECT_EQ(plot_error(curves, dir, "log"), "plot 'log': an integer x axis must be linear");
}

TEST(Plot, LogCurvesDropAReferenceLineTheAxisCannotShow) {
  fs::path dir = output_dir("log_curves");
  Curves curves;
  curves.title = "amplitude ratio per revolution";
  curves.log_y = true;
  curves.reference_y = 0.0;  // not on a log axis: left out instead of failing the plot
  curves.reference_label = "zero line";
  curves.series.push_back(series("ratio", {1, 2, 3, 4}, {0.5, 2.0, 30.0, 400.0}, "linespoints"));
  render(curves, dir, "log");
  expect_png(dir / "log.png", 10000);
  EXPECT_EQ(read_all(dir / "log.svg").find("zero line"), std::string::npos);
  // Four decades: gnuplot's own power-of-ten ticks, printed plainly.
  EXPECT_NE(read_all(dir / "log.gp").find("set logscale y\nset format y '%g'\n"),
            std::string::npos);
}

// Width / height of the first series as drawn in the SVG: the first path of gnuplot's group
// "gnuplot_plot_1", whose first sub-path is the key's sample line and the rest the data.
double drawn_aspect(const std::string& svg) {
  const std::size_t begin = svg.find("d='", svg.find("<g id=\"gnuplot_plot_1\""));
  if (begin == std::string::npos) return 0.0;
  const std::size_t end = svg.find('\'', begin + 3);
  const std::string group = svg.substr(begin + 3, end - begin - 3);
  double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
  int moves = 0;
  for (std::size_t at = 0; at < group.size(); ++at) {
    const char c = group[at];
    if (c != 'M' && c != 'L') continue;
    moves += c == 'M' ? 1 : 0;
    double x = 0, y = 0;
    if (std::sscanf(group.c_str() + at + 1, "%lf,%lf", &x, &y) != 2 || moves < 2) continue;
    x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
  }
  return (x_hi - x_lo) / (y_hi - y_lo);
}

TEST(Plot, EqualAspectDrawsACircleRound) {
  fs::path dir = output_dir("equal_aspect");
  Curves curves;
  curves.title = "unit circle";
  curves.x_label = "x [um]";
  curves.y_label = "y [um]";
  Series circle = series("circle", {}, {});
  for (int k = 0; k <= 60; ++k) {
    circle.x.push_back(std::cos(k * 2 * std::numbers::pi / 60));
    circle.y.push_back(std::sin(k * 2 * std::numbers::pi / 60));
  }
  curves.series.push_back(circle);
  render(curves, dir, "stretched");
  curves.equal_aspect = true;
  render(curves, dir, "round");
  expect_png(dir / "round.png", 10000);
  EXPECT_NE(read_all(dir / "round.gp").find("set size ratio -1\n"), std::string::npos);
  EXPECT_EQ(read_all(dir / "stretched.gp").find("set size ratio"), std::string::npos);
  // The default frame fills the 4:3 canvas, so the circle comes out an ellipse; with equal
  // aspect its drawn width and height agree (to the 2-decimal SVG coordinates).
  EXPECT_GT(std::abs(drawn_aspect(read_all(dir / "stretched.svg")) - 1.0), 0.1);
  EXPECT_NEAR(drawn_aspect(read_all(dir / "round.svg")), 1.0, 0.01);

  curves.log_y = true;
  EXPECT_EQ(plot_error(curves, dir, "log"), "plot 'log': equal aspect needs linear axes");
}

TEST(Plot, TitlesWithQuotesAndBackslashesRender) {
  // A study name quoting a DDE ("x'' + 2 zeta x' = ...") once made gnuplot fail on the run of
  // doubled single quotes; backslashes and double quotes must not start escapes either.
  fs::path dir = output_dir("quoted_title");
  Curves curves;
  curves.title = "x'' + 2 zeta x' + x = -K (x - x(t - tau)) \"DDE-BIFTOOL\" C:\\runs";
  curves.x_label = "delay tau";
  curves.y_label = "Re s";
  curves.series.push_back(series("rightmost root", {1, 2, 3}, {0.1, -0.2, 0.05}));
  render(curves, dir, "quoted");
  expect_png(dir / "quoted.png", 10000);
  EXPECT_NE(read_all(dir / "quoted.svg").find("x'' + 2 zeta x'"), std::string::npos);
}

TEST(Plot, BadFiguresAreRejectedWithTheReason) {
  fs::path dir = output_dir("bad");
  Heatmap map;
  map.x = {1, 2};
  map.y = {1, 2};
  map.z = {1, 2, 3};
  EXPECT_EQ(plot_error(map, dir, "m"), "heatmap 'm' has 3 z values for a 2 x 2 grid");
  map.z.push_back(4);
  map.log_x = true;
  map.x[0] = 0;
  EXPECT_EQ(plot_error(map, dir, "m"), "heatmap x value 0 cannot be shown on a log axis");

  Curves curves;
  curves.series.push_back(series("a", {1, 2}, {1, 2}, "lines; !rm"));
  EXPECT_EQ(plot_error(curves, dir, "c"),
            "series 'a': unknown style 'lines; !rm' (valid: lines, points, linespoints, "
            "impulses, steps, dashes, area, area_above)");
  EXPECT_FALSE(fs::exists(dir / "c.gp"));  // rejected before anything is written
}

TEST(Plot, GnuplotErrorsCarryItsMessage) {
  fs::path dir = output_dir("gnuplot_error");
  Curves curves;
  curves.title = "negative values on a log axis";
  curves.log_y = true;  // every y <= 0: gnuplot has nothing to draw and fails
  curves.series.push_back(series("a", {1, 2}, {-1, -2}));
  const std::string what = plot_error(curves, dir, "c");
  EXPECT_NE(what.find("gnuplot failed on " + (dir / "c.gp").string() + " (exit status 1)"),
            std::string::npos)
      << what;
  EXPECT_NE(what.find("all points y value undefined"), std::string::npos) << what;
}

TEST(Plot, MissingGnuplotIsReported) {
  fs::path dir = output_dir("no_gnuplot");
  const char* old_path = std::getenv("PATH");
  std::string saved = old_path ? old_path : "";
  ::setenv("PATH", dir.c_str(), 1);  // a directory without gnuplot
  Curves curves;
  curves.series.push_back(series("a", {1, 2}, {1, 2}));
  const std::string what = plot_error(curves, dir, "c");
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(what.find("cannot run gnuplot (No such file or directory); install it (Debian "
                      "package gnuplot-nox)"),
            std::string::npos)
      << what;
  // The script is still there for a later `gnuplot c.gp`.
  EXPECT_TRUE(fs::exists(dir / "c.gp"));
}

}  // namespace
