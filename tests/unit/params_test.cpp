// validate_params and ParamValues: every ValueKind, limits, defaults, and the message text.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "chatterlab/params.hpp"
#include "study_test_support.hpp"

namespace chatterlab::testing {
namespace {

// Every path on line 7 of "p.toml", except paths below "far", which are on line 40.
class FixedSourceMap final : public SourceMap {
 public:
  SourceLocation locate(std::string_view path) const override {
    return {"p.toml", path.rfind("far", 0) == 0 ? 40 : 7};
  }
};

ParamSpec real_spec(std::string key, double min, bool min_exclusive, double max, bool max_exclusive) {
  ParamSpec s = param_spec(std::move(key), ValueKind::real, "N/m", "contact stiffness");
  s.min = min, s.min_exclusive = min_exclusive, s.max = max, s.max_exclusive = max_exclusive;
  return s;
}

ParamSpec of_kind(const std::string& key, ValueKind kind) {
  return param_spec(key, kind, "1", key + " description");
}

const double inf = std::numeric_limits<double>::infinity();

std::string error_of(const Json& table, const std::vector<ParamSpec>& specs, std::string_view path = "model") {
  return input_error_of([&] { validate_params(table, specs, path, FixedSourceMap()); });
}

TEST(ValidateParams, FillsDefaultsInDeclarationOrderAndConvertsTypes) {
  auto a = real_spec("stiffness_n_per_m", 0, true, inf, false);
  auto b = of_kind("harmonics", ValueKind::integer);
  b.default_value = 3;
  auto c = of_kind("label", ValueKind::string);
  c.optional = true;
  Json out = validate_params(Json{{"harmonics", 2.0}, {"stiffness_n_per_m", 5}}, {a, b, c}, "model",
                             FixedSourceMap());
  EXPECT_EQ(out.dump(), R"({"stiffness_n_per_m":5.0,"harmonics":2,"label":null})");
  EXPECT_TRUE(out["harmonics"].is_number_integer());
  out = validate_params(Json{{"stiffness_n_per_m", 1e6}}, {a, b}, "model", FixedSourceMap());
  EXPECT_EQ(out["harmonics"], 3);
}

TEST(ValidateParams, LimitsNameTheKeyValueUnitAndBound) {
  auto positive = real_spec("stiffness_n_per_m", 0, true, inf, false);
  EXPECT_EQ(error_of(Json{{"stiffness_n_per_m", 0.0}}, {positive}),
            "p.toml:7: model.stiffness_n_per_m = 0 [N/m]: out of range, must be > 0 (contact stiffness)");
  EXPECT_EQ(error_of(Json{{"stiffness_n_per_m", -2.5}}, {positive}),
            "p.toml:7: model.stiffness_n_per_m = -2.5 [N/m]: out of range, must be > 0 (contact stiffness)");
  auto damping = real_spec("d", 0, false, 1, true);
  EXPECT_NE(error_of(Json{{"d", 1.0}}, {damping}).find("d = 1 [N/m]: out of range, must be >= 0 and < 1"),
            std::string::npos);
  EXPECT_NE(error_of(Json{{"d", -0.1}}, {damping}).find("must be >= 0 and < 1"), std::string::npos);
  EXPECT_NO_THROW(validate_params(Json{{"d", 0.0}}, {damping}, "model", FixedSourceMap()));
  auto at_most = real_spec("x", -inf, false, 5, false);
  EXPECT_NE(error_of(Json{{"x", 5.5}}, {at_most}).find("must be <= 5"), std::string::npos);
}

TEST(ValidateParams, RejectsNonFiniteValues) {
  auto any = real_spec("x", -inf, false, inf, false);
  EXPECT_EQ(error_of(Json{{"x", std::nan("")}}, {any}), "p.toml:7: model.x = nan: must be finite");
  EXPECT_EQ(error_of(Json{{"x", -inf}}, {any}), "p.toml:7: model.x = -inf: must be finite");
  auto list = of_kind("xs", ValueKind::real_list);
  EXPECT_EQ(error_of(Json{{"xs", Json::array({1.0, inf})}}, {list}), "p.toml:7: model.xs.1 = inf: must be finite");
}

TEST(ValidateParams, UnknownKeysListTheValidOnesAndSuggestTheClosest) {
  auto a = real_spec("stiffness_n_per_m", 0, true, inf, false);
  auto b = of_kind("mass_kg", ValueKind::real);
  EXPECT_EQ(error_of(Json{{"stiffness", 1.0}, {"mass_kg", 1.0}}, {a, b}),
            "p.toml:7: unknown key 'model.stiffness' (did you mean 'stiffness_n_per_m'?); valid keys: "
            "mass_kg, stiffness_n_per_m");
  EXPECT_EQ(error_of(Json{{"zzz", 1.0}}, {}), "p.toml:7: unknown key 'model.zzz'; valid keys: (none)");
}

TEST(ValidateParams, MissingRequiredKeyIsNamedWithItsDescriptionAndUnit) {
  auto a = real_spec("stiffness_n_per_m", 0, true, inf, false);
  EXPECT_EQ(error_of(Json::object(), {a}),
            "p.toml:7: missing required key 'model.stiffness_n_per_m' (contact stiffness [N/m])");
}

TEST(ValidateParams, WrongTypesSayWhatWasExpected) {
  EXPECT_EQ(error_of(Json{{"x", "fast"}}, {of_kind("x", ValueKind::real)}),
            "p.toml:7: model.x = \"fast\": expected a real number");
  EXPECT_EQ(error_of(Json{{"x", true}}, {of_kind("x", ValueKind::real)}),
            "p.toml:7: model.x = true: expected a real number");
  EXPECT_EQ(error_of(Json{{"n", 2.5}}, {of_kind("n", ValueKind::integer)}),
            "p.toml:7: model.n = 2.5: expected an integer");
  EXPECT_EQ(error_of(Json{{"n", 1e30}}, {of_kind("n", ValueKind::integer)}),
            "p.toml:7: model.n = 1e+30: expected an integer");
  EXPECT_EQ(error_of(Json{{"b", 1}}, {of_kind("b", ValueKind::boolean)}),
            "p.toml:7: model.b = 1: expected a boolean");
  EXPECT_EQ(error_of(Json{{"s", 3}}, {of_kind("s", ValueKind::string)}),
            "p.toml:7: model.s = 3: expected a string");
  EXPECT_EQ(error_of(Json{{"xs", 3.0}}, {of_kind("xs", ValueKind::real_list)}),
            "p.toml:7: model.xs = 3: expected a list of real numbers");
  EXPECT_EQ(error_of(Json{{"xs", Json::array({1.0, "a"})}}, {of_kind("xs", ValueKind::real_list)}),
            "p.toml:7: model.xs.1 = \"a\": expected a real number");
  EXPECT_EQ(error_of(Json{{"t", Json::array({1.0})}}, {of_kind("t", ValueKind::table_list)}),
            "p.toml:7: model.t.0 = 1: expected a table");
  EXPECT_EQ(error_of(Json::array(), {}), "p.toml:7: model = []: expected a table");
}

TEST(ValidateParams, AcceptsItsOwnOutput) {
  auto a = real_spec("stiffness_n_per_m", 0, true, inf, false);
  auto b = of_kind("trim", ValueKind::real_list);
  b.optional = true;
  auto c = of_kind("harmonics", ValueKind::integer);
  c.default_value = 2;
  Json once = validate_params(Json{{"stiffness_n_per_m", 3}}, {a, b, c}, "model", FixedSourceMap());
  EXPECT_TRUE(once["trim"].is_null());
  EXPECT_EQ(validate_params(once, {a, b, c}, "model", FixedSourceMap()), once);
  // A required key left null is still missing.
  EXPECT_EQ(error_of(Json{{"stiffness_n_per_m", nullptr}}, {a}),
            "p.toml:7: missing required key 'model.stiffness_n_per_m' (contact stiffness [N/m])");
}

TEST(ValidateParams, IntegersAcceptWholeRealsAndLargeIntegersExactly) {
  auto n = of_kind("n", ValueKind::integer);
  Json out = validate_params(Json{{"n", 4.0}}, {n}, "m", FixedSourceMap());
  EXPECT_EQ(out["n"], 4);
  std::int64_t big = (std::int64_t{1} << 53) + 1;  // not representable as a double
  out = validate_params(Json{{"n", big}}, {n}, "m", FixedSourceMap());
  EXPECT_EQ(out["n"].get<std::int64_t>(), big);
}

TEST(ValidateParams, StringChoicesAreListedSorted) {
  auto s = of_kind("shape", ValueKind::string);
  s.choices = {"torsion", "bending"};
  EXPECT_EQ(error_of(Json{{"shape", "bendng"}}, {s}),
            "p.toml:7: model.shape = \"bendng\": not one of: bending, torsion (did you mean 'bending'?)");
  EXPECT_NO_THROW(validate_params(Json{{"shape", "torsion"}}, {s}, "model", FixedSourceMap()));
}

TEST(ValidateParams, MatricesMustBeRectangularAndListsLongEnough) {
  auto m = of_kind("a0", ValueKind::real_matrix);
  EXPECT_EQ(error_of(Json{{"a0", Json::parse("[[1, 2], [3]]")}}, {m}),
            "p.toml:7: model.a0.1 has 1 entries but row 0 has 2: a matrix must be rectangular");
  EXPECT_EQ(error_of(Json{{"a0", Json::parse("[[1, 2], 3]")}}, {m}),
            "p.toml:7: model.a0.1 = 3: expected a list of real numbers (a matrix row)");
  Json out = validate_params(Json{{"a0", Json::parse("[[1, 2], [3, 4]]")}}, {m}, "model", FixedSourceMap());
  EXPECT_EQ(out["a0"], Json::parse("[[1.0, 2.0], [3.0, 4.0]]"));
  auto list = of_kind("xs", ValueKind::real_list);
  list.min_items = 2;
  EXPECT_EQ(error_of(Json{{"xs", Json::array({1.0})}}, {list}),
            "p.toml:7: model.xs has 1 entries: needs at least 2 (xs description)");
}

TEST(ValidateParams, TableListsValidateEachItemAtItsOwnPath) {
  auto damping = real_spec("damping_ratio", 0, false, 1, true);
  auto modes = of_kind("modes", ValueKind::table_list);
  modes.fields = {damping};
  Json table = {{"modes", Json::parse(R"([{"damping_ratio": 0.1}, {"damping_ratio": 1.2}])")}};
  EXPECT_EQ(error_of(table, {modes}, "far"),
            "p.toml:40: far.modes.1.damping_ratio = 1.2 [N/m]: out of range, must be >= 0 and < 1 "
            "(contact stiffness)");
  table = {{"modes", Json::parse(R"([{"damping_ratio": 0.1, "mass": 2}])")}};
  EXPECT_EQ(error_of(table, {modes}), "p.toml:7: unknown key 'model.modes.0.mass'; valid keys: damping_ratio");
}

// A nested table ([feed_risk.simulation]): its fields validated at their own path; left out,
// the table of its fields' defaults (default_value {}) or null (optional).
TEST(ValidateParams, NestedTablesValidateTheirFieldsAndFillDefaults) {
  auto damping = real_spec("damping_ratio", 0, false, 1, true);
  auto steps = of_kind("steps", ValueKind::integer);
  steps.default_value = 8;
  auto simulation = of_kind("simulation", ValueKind::table);
  simulation.fields = {steps};
  simulation.default_value = Json::object();
  auto optimise = of_kind("optimise", ValueKind::table);
  optimise.fields = {damping};
  optimise.optional = true;
  const std::vector<ParamSpec> specs{simulation, optimise};
  Json out = validate_params(Json::object(), specs, "far", FixedSourceMap());
  EXPECT_EQ(out["simulation"], Json({{"steps", 8}}));
  EXPECT_TRUE(out["optimise"].is_null());
  EXPECT_EQ(validate_params(out, specs, "far", FixedSourceMap()), out);
  out = validate_params(Json::parse(R"({"simulation": {"steps": 3.0}, "optimise": {"damping_ratio": 0.5}})"),
                        specs, "far", FixedSourceMap());
  EXPECT_EQ(out["simulation"]["steps"], 3);
  EXPECT_EQ(out["optimise"]["damping_ratio"], 0.5);
  EXPECT_EQ(error_of(Json::parse(R"({"optimise": {"damping_ratio": 1.5}})"), specs, "far"),
            "p.toml:40: far.optimise.damping_ratio = 1.5 [N/m]: out of range, must be >= 0 and < 1 "
            "(contact stiffness)");
  EXPECT_EQ(error_of(Json::parse(R"({"simulation": {"step": 3}})"), specs),
            "p.toml:7: unknown key 'model.simulation.step' (did you mean 'steps'?); valid keys: steps");
  EXPECT_EQ(error_of(Json{{"simulation", 3}}, specs), "p.toml:7: model.simulation = 3: expected a table");
  // A required field of a table left out is missing even when the table is.
  optimise.optional = false;
  optimise.default_value = Json::object();
  EXPECT_EQ(error_of(Json::object(), {optimise}),
            "p.toml:7: missing required key 'model.optimise.damping_ratio' (contact stiffness [N/m])");
}

TEST(ParamValues, ReadsValidatedValuesAndRejectsUndeclaredKeys) {
  ParamValues values(Json::parse(R"({"k": 2.5, "n": 3, "b": true, "s": "x", "xs": [1, 2],
                                    "m": [[1, 2], [3, 4]], "t": [{"a": 1.0}], "o": null})"));
  EXPECT_EQ(values.real("k"), 2.5);
  EXPECT_EQ(values.integer("n"), 3);
  EXPECT_TRUE(values.boolean("b"));
  EXPECT_EQ(values.string("s"), "x");
  EXPECT_EQ(values.reals("xs"), (std::vector<double>{1, 2}));
  EXPECT_EQ(values.matrix("m")[1][0], 3.0);
  EXPECT_EQ(values.tables("t").at(0).real("a"), 1.0);
  EXPECT_TRUE(values.has("k"));
  EXPECT_FALSE(values.has("o")) << "null: an optional parameter left out";
  EXPECT_FALSE(values.has("missing"));
  EXPECT_THROW(values.real("missing"), std::logic_error);
}

}  // namespace
}  // namespace chatterlab::testing
