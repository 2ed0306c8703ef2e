// The feed_plan study kind (docs/planner.md): a plan written and read back, bad input named with
// its key, value and reason, a point-table generatrix.
#include "study_kinds/feed_plan/feed_plan.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "chatterlab/errors.hpp"
#include "chatterlab/planner/plan.hpp"
#include "chatterlab/study.hpp"
#include "chatterlab/study_kind.hpp"
#include "unit/planner_test_support.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::planner {
namespace {

namespace fs = std::filesystem;
using chatterlab::testing::TempDir;

using testing::replace;
constexpr const char* study_text = testing::problem2_study_text;

TEST(FeedPlanStudy, WritesAPlanThatReadsBack) {
  TempDir dir;
  const Study study = chatterlab::testing::load_text(
      dir, replace(study_text, "x_range_mm = [0.0, 600.0]", "x_range_mm = [0.0, 60.0]"));
  const auto& kind = study_kind_registry().at("feed_plan");
  auto instance = kind.create(ParamValues());
  PointContext context;
  context.artifact_dir = dir.path() / "out";
  context.plots = false;
  fs::create_directories(context.artifact_dir);
  const auto values = instance->run_point(study.document, context);
  EXPECT_NEAR(values[0].get<double>(), 300.0, 1e-6);  // 60 mm at 0.2 mm/s
  EXPECT_EQ(values.back(), Json(true));
  const SavedPlan saved = read_saved_plan(context.artifact_dir);
  ASSERT_EQ(saved.segments.size(), 300u);
  EXPECT_DOUBLE_EQ(saved.plan.spindle_speed_rpm, 300.0);
  EXPECT_EQ(saved.plan.segments[0].pulses, (std::vector<std::int64_t>{-27, 40, 55}));
  for (std::size_t k = 0; k < saved.segments.size(); k += 37) {
    EXPECT_NEAR(saved.segments[k].x_start_mm, 0.2 * static_cast<double>(k), 0.051);  // knots move
    EXPECT_NEAR(saved.segments[k].axial_speed_mm_per_s, 0.2, 0.02);
    EXPECT_NEAR(saved.segments[k].radius_mm, 130 + 30 * std::sin(0.25 * std::numbers::pi), 10.0);
  }
  // With a wear sweep the reader recovers the contact's place on the wheel as well.
  Json swept = study.document;
  swept["plan"]["wear_sweep"] = "triangle";
  swept["wheel"]["type"] = "cylindrical";  // a face sweep: the reader can also solve it alone
  swept["plan"]["wear_sweep_amplitude_mm"] = 5.0;
  swept["plan"]["wear_sweep_period_mm"] = 20.0;
  instance->run_point(swept, context);
  // The P6 triangle sweep written out: amplitude 5 mm, 20 mm of x per cycle, from 0 rising.
  auto sweep = [](double x) {
    const double phase = std::fmod(x / 20.0 + 0.25, 1.0);
    return 5.0 * (phase < 0.5 ? 4 * phase - 1 : 3 - 4 * phase);
  };
  for (bool with_segments_csv : {true, false}) {
    if (!with_segments_csv) fs::remove(context.artifact_dir / "segments.csv");
    const SavedPlan saved_swept = read_saved_plan(context.artifact_dir);
    for (std::size_t k = 0; k < saved_swept.segments.size(); k += 23) {
      const SegmentConditions& c = saved_swept.segments[k];
      EXPECT_NEAR(c.contact_on_wheel_mm, sweep(0.5 * (c.x_start_mm + c.x_end_mm)), 0.05) << k;
    }
  }
  // A tampered file is an input error naming the file and line.
  dir.write("out/pulses.csv", "segment,start_s,duration_s,lower_pulses,middle_pulses,upper_pulses\n0,0,1,1.5,2,3\n");
  const std::string message = chatterlab::testing::input_error_of([&] { read_saved_plan(context.artifact_dir); });
  EXPECT_NE(message.find("pulses.csv:2"), std::string::npos) << message;
  EXPECT_NE(message.find("integers"), std::string::npos) << message;
}

TEST(FeedPlanStudy, BadInputNamesKeyValueAndReason) {
  TempDir dir;
  auto error = [&](const std::string& text) { return chatterlab::testing::load_error(dir, text); };
  std::string m = error(replace(study_text, "pivot_to_nut_mm = 300.0", "pivot_to_nut_mm = -3.0"));
  EXPECT_NE(m.find("machine.pivot_to_nut_mm = -3"), std::string::npos) << m;
  m = error(replace(study_text, "x_range_mm = [0.0, 600.0]", "x_range_mm = [60.0, 0.0]"));
  EXPECT_NE(m.find("part.x_range_mm"), std::string::npos) << m;
  EXPECT_NE(m.find("a < b"), std::string::npos) << m;
  m = error(replace(study_text, "30*exp(-x/400)*sin((x + 25*_pi)/100) + 130", "log(x - 10)"));
  EXPECT_NE(m.find("part.generatrix"), std::string::npos) << m;
  EXPECT_NE(m.find("not finite"), std::string::npos) << m;
  m = error(replace(study_text, "30*exp(-x/400)*sin((x + 25*_pi)/100) + 130", "x < 30 ? 120 : 125"));
  EXPECT_NE(m.find("jumps by 5"), std::string::npos) << m;
  m = error(replace(study_text, "edge_radius_mm = 20.0", "edge_radius_mm = 2000.0"));
  EXPECT_NE(m.find("wheel.edge_radius_mm = 2000"), std::string::npos) << m;
  EXPECT_NE(m.find("too large for the part"), std::string::npos) << m;
  m = error(replace(study_text, "spindle_speed_rpm = { from = 250.0, to = 300.0 }",
                    "spindle_speed_rpm = { from = 350.0, to = 300.0 }"));
  EXPECT_NE(m.find("machine.spindle_speed_rpm"), std::string::npos) << m;
  m = error(replace(study_text, "max_relative_rate_change = 0.1", "max_relative_rate_change = 0.0"));
  EXPECT_NE(m.find("machine.max_relative_rate_change = 0"), std::string::npos) << m;
  m = error(replace(study_text, "type = \"profiled\"", "type = \"cylindrical\""));
  EXPECT_NE(m.find("flat face cuts"), std::string::npos) << m;
}

// [part] points_file: problem 1's parabola sampled every 10 mm; the natural spline through it
// plans like the expression (3000 s, certified) and a table with x not increasing is refused.
TEST(FeedPlanStudy, PointTableGeneratrix) {
  TempDir dir;
  std::string points = "x_mm,y_mm\n";
  for (int i = 0; i <= 60; ++i) {
    const double x = 10.0 * i;
    points += fmt::format("{},{}\n", x, -7.0 / 18000 * (600 - x) * (600 - x) + 0.45 * (600 - x));
  }
  dir.write("points.csv", points);
  std::string text = study_text;
  text = replace(text, "generatrix = \"30*exp(-x/400)*sin((x + 25*_pi)/100) + 130\"\nx_range_mm = [0.0, 600.0]",
                 "points_file = \"points.csv\"");
  text = replace(text, "type = \"profiled\"", "type = \"cylindrical\"");
  const Study study = chatterlab::testing::load_text(dir, text);
  auto kind = study_kind_registry().at("feed_plan").create(ParamValues());
  const auto values = kind->run_point(study.document, PointContext{0, 1, {}, false});
  EXPECT_NEAR(values[0].get<double>(), 3000.0, 1e-6);
  EXPECT_EQ(values.back(), Json(true));
  EXPECT_LT(values[4].get<double>(), 0.005);
  dir.write("points.csv", "x_mm,y_mm\n0,130\n10,131\n10,132\n20,133\n");
  const std::string message = chatterlab::testing::load_error(dir, text);
  EXPECT_NE(message.find("part.points_file"), std::string::npos) << message;
  EXPECT_NE(message.find("x must increase strictly"), std::string::npos) << message;
}

}  // namespace
}  // namespace chatterlab::planner
