// The cam_plan study kind (docs/planner.md, "Cams"): it takes any machine that declares the
// cam-grinding capability (Kinematics::cam_grinding()), not a machine name, and refuses the others
// at validation with the key, the value and the reason.
#include "study_kinds/cam_plan/cam_plan.hpp"

#include <gtest/gtest.h>

#include <string>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/study.hpp"
#include "unit/planner_test_support.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab::planner {
namespace {

using chatterlab::testing::TempDir;

std::string cam_study(const std::string& machine) {
  return "[study]\nkind = \"cam_plan\"\n" + machine +
         "[part]\nlift_table_file = \"" CHATTERLAB_SOURCE_DIR "/tests/data/planner/cam_lift_table.csv\"\n"
         "[plan]\nsegment_angle_deg = 1.0\n";
}

constexpr const char* xc_cam_machine =
    "[machine]\ntype = \"xc_cam\"\nwheel_radius_mm = 40.0\nc_deg_per_pulse = 0.001\nx_mm_per_pulse = 0.0001\n"
    "max_pulse_rate_hz = 500000.0\n";

TEST(CamPlanKind, TakesAMachineByItsCamGrindingCapability) {
  TempDir dir;
  const Study study = chatterlab::testing::load_text(dir, cam_study(xc_cam_machine));
  // The validated machine keeps the planner's rules beside the kinematics plugin's parameters.
  EXPECT_EQ(study.document["machine"]["cam_speed_rpm"], 60.0);
  // xc_cam declares the capability and reports its wheel.
  Json params = study.document["machine"];
  for (const char* key : {"type", "cam_speed_rpm", "max_relative_rate_change"}) params.erase(key);
  const auto machine = kinematics_registry().at("xc_cam").create(ParamValues(params));
  ASSERT_NE(machine->cam_grinding(), nullptr);
  EXPECT_EQ(machine->cam_grinding()->wheel_radius_mm(), 40.0);
  EXPECT_EQ(machine->motors().size(), 2u);
}

TEST(CamPlanKind, RefusesAMachineThatCannotGrindCams) {
  TempDir dir;
  const std::string machine =
      "[machine]\ntype = \"three_table_revolution\"\npivot_to_nut_mm = 300.0\nfixture_to_pivot_mm = 250.0\n"
      "screw_pitch_mm = 12.0\ngear_ratio = 10.0\nstep_angle_deg = 1.0\nmax_pulse_rate_hz = 100.0\n";
  const std::string message = chatterlab::testing::load_error(dir, cam_study(machine));
  EXPECT_NE(message.find("machine.type = \"three_table_revolution\""), std::string::npos) << message;
  EXPECT_NE(message.find("a machine that can grind cams"), std::string::npos) << message;
}

}  // namespace
}  // namespace chatterlab::planner
