// The ProcessConditionsModel capability of the plunge models (chatterlab/process_conditions.hpp)
// reproduces, bit for bit, suppression_map's frozen conditions of a modulation level (wheel or work
// speed times the level; feed: kc and kg times 1 - eps/2 (level - 1)), and penetration damping
// follows G4. feed_risk maps its segments through the capability (its own tests check the G4
// stiffness laws; tests/regression that its shipped results did not move).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "chatterlab/kit/model.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/process_conditions.hpp"
#include "chatterlab/study.hpp"
#include "unit/g1_test_machines.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

// feed_risk's test model (one mode, wheel chain off) with both regenerations on.
Json model_table(const std::string& type, const std::string& extra = "") {
  testing::TempDir dir;
  const std::string text =
      "[study]\nkind = \"stability_map\"\n" + testing::model_table_toml(type, testing::g1_feed_risk_machine, extra);
  return load_study(dir.write("m.toml", text)).document["model"];
}

// The [model] table the capability gives: parameters_at plus the type.
Json model_at(const Json& table, const ProcessConditions& reference, const ProcessConditions& conditions,
              const ProcessScaling& scaling) {
  auto model = kit::build_model(table);
  const ProcessConditionsModel* process = model->process_conditions();
  EXPECT_NE(process, nullptr);
  Json out = Json{{"type", table.at("type")}};
  const Json parameters = process->parameters_at(reference, conditions, scaling);  // named: items() would dangle
  for (const auto& [key, value] : parameters.items()) out[key] = value;
  return out;
}

TEST(ProcessConditions, PlungeModelReproducesSuppressionFrozenConditions) {
  // suppression_map's GrowthTable::conditions(level): wheel speed target m[wheel] = level * n_g;
  // work speed target m[work] = level * n_w; feed target kc, kg = (1 - eps/2 (level - 1)) * k.
  const Json model = model_table("plunge_regenerative");
  auto built = kit::build_model(model);
  const ProcessConditions nominal = built->process_conditions()->nominal_conditions();
  EXPECT_EQ(nominal.wheel_speed_rpm, 1450.0);
  EXPECT_EQ(nominal.work_speed_rpm, 300.0);
  ProcessScaling frozen;
  frozen.speed_dependent_stiffness = false;
  for (const double level : {0.7, 0.93, 1.0, 1.001, 1.25}) {
    ProcessConditions wheel = nominal, work = nominal, feed = nominal;
    wheel.wheel_speed_rpm = level * 1450.0;
    work.work_speed_rpm = level * 300.0;
    feed.depth_of_cut_ratio = level;
    Json expected = model;
    expected["wheel_speed_rpm"] = level * 1450.0;
    EXPECT_EQ(model_at(model, nominal, wheel, frozen), expected) << level;
    expected = model;
    expected["work_speed_rpm"] = level * 300.0;
    EXPECT_EQ(model_at(model, nominal, work, frozen), expected) << level;
    for (const double eps : {0.0, 0.6, 1.3}) {
      frozen.thickness_exponent = eps;
      const double s = 1.0 - 0.5 * eps * (level - 1.0);
      expected = model;
      expected["contact_stiffness_n_per_m"] = s * 2.0e7;
      expected["wheel_wear_stiffness_n_per_m"] = s * 2.0e9;
      EXPECT_EQ(model_at(model, nominal, feed, frozen), expected) << level << " " << eps;
    }
    frozen.thickness_exponent = 0.0;
  }
}

TEST(ProcessConditions, PenetrationDampingModelFollowsG1AndScalesKdByG4) {
  // The G1 part as plunge_regenerative's; kd = ks sqrt(de u0)/v_w (G4 2-77/2-78) follows the
  // removal stiffness kw, the contact length and 1/v_w.
  const Json g1 = model_table("plunge_regenerative");
  const Json pd = model_table("plunge_with_penetration_damping",
                              "penetration_damping_n_s_per_m = 1.0e4\nwork_diameter_mm = 200.0\n"
                              "wheel_diameter_mm = 400.0\ndepth_of_cut_mm = 0.01\n");
  const ProcessConditions reference{1450.0, 300.0, 10.0, 100.0, 400.0};
  const ProcessConditions at{1450.0, 420.0, 14.0, 60.0, 400.0, 1.5};
  const ProcessScaling scaling;
  const Json a = model_at(g1, reference, at, scaling), b = model_at(pd, reference, at, scaling);
  for (const char* key : {"wheel_speed_rpm", "work_speed_rpm", "contact_stiffness_n_per_m",
                          "wheel_wear_stiffness_n_per_m", "work_removal_stiffness_n_per_m", "modes"})
    EXPECT_EQ(b.at(key), a.at(key)) << key;
  // By hand: de = dw ds/(dw + ds) [mm], v_w = pi dw n_w/60, u0 ~ depth_of_cut_ratio.
  const double de_ref = 200.0 * 400.0 / 600.0, de = 120.0 * 400.0 / 520.0;
  const double vw_ref = std::numbers::pi * 0.2 * 300.0 / 60.0, vw = std::numbers::pi * 0.12 * 420.0 / 60.0;
  const double kw_ratio = a.at("work_removal_stiffness_n_per_m").get<double>() / 1.6e6;
  const double expected_kd = 1.0e4 * kw_ratio * std::sqrt(de / de_ref * 1.5) * vw_ref / vw;
  EXPECT_NEAR(b.at("penetration_damping_n_s_per_m").get<double>(), expected_kd, 1e-12 * expected_kd);
  // The geometry of the indicators follows: work diameter 2 r, depth u0 times the ratio.
  EXPECT_EQ(b.at("work_diameter_mm").get<double>(), 120.0);
  EXPECT_EQ(b.at("wheel_diameter_mm").get<double>(), 400.0);
  EXPECT_NEAR(b.at("depth_of_cut_mm").get<double>(), 0.015, 1e-17);
  // The table builds a model (what a study kind does with it).
  Json built = b;
  EXPECT_NE(kit::build_model(built)->characteristic(), nullptr);
}

// The default parameter_values_at flattens parameters_at's table; it must tell every two different
// tables apart (feed_risk groups segments by these vectors and runs one root search per group).
class TableAsGiven final : public ProcessConditionsModel {
 public:
  explicit TableAsGiven(Json table) : table_(std::move(table)) {}
  ProcessConditions nominal_conditions() const override { return {}; }
  Json parameters_at(const ProcessConditions&, const ProcessConditions&, const ProcessScaling&) const override {
    return table_;
  }

 private:
  Json table_;
};

std::vector<double> flattened(const Json& table) {
  std::vector<double> values;
  TableAsGiven(table).parameter_values_at({}, {}, {}, values);
  return values;
}

bool bitwise_equal(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

TEST(ProcessConditions, DefaultParameterValuesTellEveryTwoTablesApart) {
  const Json a = Json::parse(R"({"k": 1.5, "law": "linear", "on": true, "modes": [[1, 2], [3]]})");
  EXPECT_TRUE(bitwise_equal(flattened(a), flattened(a)));
  // Texts are compared in full, not by a hash: these differ only in their last byte.
  Json b = a;
  b["law"] = "lineas";
  EXPECT_FALSE(bitwise_equal(flattened(a), flattened(b)));
  b["law"] = "linear ";
  EXPECT_FALSE(bitwise_equal(flattened(a), flattened(b)));
  // The same leaves in another nesting are another table.
  b = a;
  b["modes"] = Json::parse("[[1], [2, 3]]");
  EXPECT_FALSE(bitwise_equal(flattened(a), flattened(b)));
  b = a;
  b["on"] = false;
  EXPECT_FALSE(bitwise_equal(flattened(a), flattened(b)));
  // A long text (more than one six-byte chunk) differing in its first byte.
  Json c = a, d = a;
  c["law"] = std::string(40, 'x');
  d["law"] = "y" + std::string(39, 'x');
  EXPECT_FALSE(bitwise_equal(flattened(c), flattened(d)));
  // Structure and text are NaNs: a study grouping numbers within a tolerance (feed_risk's log
  // cells) compares these by their bits, so nearby texts or sizes never share a group.
  for (double v : flattened(Json::parse(R"({"law": "a text longer than six bytes", "modes": [[], [[]]]})")))
    EXPECT_TRUE(std::isnan(v));
}

}  // namespace
}  // namespace chatterlab
