#include "study_kinds/feed_risk/feed_risk.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <exception>
#include <iterator>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <unordered_map>

#include "chatterlab/errors.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/kit/model.hpp"
#include "chatterlab/roots.hpp"

namespace chatterlab::feed_risk {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Runs task(i) for i = 0..count-1 on the OpenMP threads (dynamic schedule); exceptions are caught
// per task and the first one in index order is rethrown after all tasks ran, so the outcome does
// not depend on the thread count.
template <class Task>
void parallel_tasks(std::size_t count, const Task& task) {
  std::vector<std::exception_ptr> failures(count);
  const auto n = static_cast<long>(count);
#pragma omp parallel for schedule(dynamic)
  for (long i = 0; i < n; ++i) {
    const auto t = static_cast<std::size_t>(i);
    try {
      task(t);
    } catch (...) {
      failures[t] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

double surface_speed_m_per_s(double diameter_mm, double rpm) { return kPi * diameter_mm * 1e-3 * rpm / 60.0; }

struct CellsHash {
  std::size_t operator()(const std::vector<long long>& key) const {
    std::size_t h = key.size();
    for (long long v : key) h ^= std::hash<long long>{}(v) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    return h;
  }
};

// Groups of items (segments, or their phases) whose model parameters are equal within a relative
// tolerance (every number of the parameter table on a log grid), each with its representative (the
// first item in the order the items were added: its parameters are the group's). Cells of
// different pools never merge, so ratings that must not share roots keep their own pools.
struct Grouping {
  std::vector<SegmentProcess> representative;
  std::vector<std::vector<long long>> cells;  // the representative's parameter cells, then its pool
  std::unordered_map<std::vector<long long>, std::size_t, CellsHash> group_of_cells;

  // The group of `key`, a new one (represented by `item`) if none holds it yet.
  std::size_t add(const std::vector<long long>& key, const SegmentProcess& item) {
    if (auto it = group_of_cells.find(key); it != group_of_cells.end()) return it->second;
    group_of_cells.emplace(key, representative.size());
    representative.push_back(item);
    cells.push_back(key);
    return representative.size() - 1;
  }
};

// The cells of every parameter value (positive ones on the log grid; others exactly, by their
// bits), in the model's order. Consecutive items mostly share most values (the structural modes
// never change, a segment's phases share its width): a value equal to the previous call's at the
// same position reuses its cell instead of another logarithm.
class CellKeys {
 public:
  explicit CellKeys(double tolerance) : tolerance_(std::max(tolerance, 1e-15)) {}

  // The key of `values` in `pool` (valid until the next call).
  const std::vector<long long>& operator()(const std::vector<double>& values, long long pool) {
    if (values.size() != values_.size()) {
      values_.assign(values.size(), std::numeric_limits<double>::quiet_NaN());  // equal to no value
      cells_.assign(values.size(), 0);
    }
    key_.clear();
    for (std::size_t k = 0; k < values.size(); ++k) {
      const double v = values[k];
      if (v > 0.0 && std::isfinite(v)) {
        if (!(v == values_[k])) cells_[k] = std::llround(std::log(v) / tolerance_);
        key_.push_back(cells_[k]);
      } else {
        key_.push_back(std::numeric_limits<long long>::min());
        key_.push_back(std::bit_cast<long long>(v));
      }
      values_[k] = v;
    }
    key_.push_back(pool);
    return key_;
  }

 private:
  double tolerance_;
  std::vector<double> values_;
  std::vector<long long> cells_, key_;
};

// The [model] table: the model's type and its parameters.
Json with_type(const Json& model_table, const Json& parameters) {
  Json t = Json{{"type", model_table.at("type")}};
  t.update(parameters);
  return t;
}

// Adds `items` (in their order) to the groups of `g` in `pool` and returns each item's group. The
// keys come from the parameter values without their JSON table. Serial: rate_plans groups its
// ratings in parallel.
std::vector<std::size_t> group_items(const ProcessSettings& p, const std::vector<SegmentProcess>& items,
                                     double tolerance, Grouping& g, long long pool = 0) {
  const ProcessConditionsModel& process = process_model(p);
  const ProcessConditions reference = reference_conditions(p);
  ProcessScaling scaling;
  scaling.speed_dependent_stiffness = p.speed_scaling;
  CellKeys keys(tolerance);
  std::vector<double> values;
  std::vector<std::size_t> group_of_item(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    process.parameter_values_at(reference, segment_conditions(p, items[i]), scaling, values);
    group_of_item[i] = g.add(keys(values, pool), items[i]);
  }
  return group_of_item;
}

// Adds the groups of `part` to `g` in their order and returns the group in `g` of each: merging the
// groupings of consecutive batches in batch order gives the groups (and representatives) of one
// serial pass over all items.
std::vector<std::size_t> merge_groups(Grouping& g, const Grouping& part) {
  std::vector<std::size_t> group_of_part(part.cells.size());
  for (std::size_t j = 0; j < part.cells.size(); ++j)
    group_of_part[j] = g.add(part.cells[j], part.representative[j]);
  return group_of_part;
}

struct RootValue {
  double growth_rate_per_s = kNaN, frequency_hz = kNaN;
  bool certified = false;
  std::string error;
};

// Groups are solved in blocks of consecutive groups (OpenMP over blocks, serially within one).
// Within a block, a group's search is warm-started from the roots of the earlier group of the
// block nearest to it in parameter cells: neighbouring segments have nearly the same roots, so
// Newton from them converges in a step or two and the pruning keeps only the few candidates for
// the rightmost root (about a third of a search's evaluations otherwise go to the ~300 lattice
// guesses). The blocks and the sources depend only on the groups, never on the thread count or
// timing, so the results are the same bytes for any schedule.
constexpr std::size_t kWarmStartBlock = 32;

// Distance between two groups' parameter cells: summed cell differences, "far" where a
// parameter is not on the log grid (then the cells are exact bits) and differs.
long long cell_distance(const std::vector<long long>& a, const std::vector<long long>& b) {
  constexpr long long far = 1LL << 40;
  if (a.size() != b.size()) return far;
  long long d = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (a[k] == b[k]) continue;
    const bool exact = a[k] == std::numeric_limits<long long>::min() || b[k] == std::numeric_limits<long long>::min() ||
                       (k > 0 && (a[k - 1] == std::numeric_limits<long long>::min() ||
                                  b[k - 1] == std::numeric_limits<long long>::min()));
    d += exact ? far : std::min(far, std::llabs(a[k] - b[k]));
  }
  return d;
}

std::vector<RootValue> solve_groups(const Json& model_table, const ProcessSettings& p, const Grouping& g,
                                    const RootSettings& settings) {
  std::vector<RootValue> values(g.representative.size());
  const kit::StabilitySettings stability = kit::stability_settings_table().read(settings.stability);
  const std::size_t blocks = (values.size() + kWarmStartBlock - 1) / kWarmStartBlock;
  const auto n = static_cast<long>(blocks);
#pragma omp parallel for schedule(dynamic)
  for (long b = 0; b < n; ++b) {
    const std::size_t first = static_cast<std::size_t>(b) * kWarmStartBlock;
    const std::size_t last = std::min(values.size(), first + kWarmStartBlock);
    std::vector<std::vector<Complex>> approximate(last - first);
    for (std::size_t u = first; u < last; ++u) {
      try {
        auto model = kit::build_model(segment_model_table(model_table, p, g.representative[u]));
        auto characteristic = model->characteristic();
        if (!characteristic) throw PointFailure("the model has no characteristic function here");
        RootSearchOptions options = kit::root_search_options(stability, *characteristic);
        options.keep_approximate_roots = true;
        std::size_t source = last;
        long long nearest = std::numeric_limits<long long>::max();
        for (std::size_t j = first; j < u; ++j) {
          const long long d = cell_distance(g.cells[u], g.cells[j]);
          if (!approximate[j - first].empty() && d < nearest) {
            nearest = d;
            source = j;
          }
        }
        if (source != last) options.warm_start = &approximate[source - first];
        RightmostRoot root = find_rightmost_root(*characteristic, options);
        values[u].growth_rate_per_s = root.root.real();
        values[u].frequency_hz = std::abs(root.root.imag()) / (2 * kPi);
        values[u].certified = root.certified;
        approximate[u - first] = std::move(root.approximate_roots);
      } catch (const std::exception& e) {
        values[u].error = e.what();
      }
    }
  }
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!values[i].error.empty())
      throw PointFailure(fmt::format("root search failed at x = {:.4g} mm (work {:.4g} rpm, contact width {:.4g} mm): {}",
                                     g.representative[i].x_mid_mm, g.representative[i].work_speed_rpm,
                                     g.representative[i].contact_width_mm, values[i].error));
  return values;
}

}  // namespace

const char* to_string(Risk risk) {
  switch (risk) {
    case Risk::stable: return "stable";
    case Risk::marginal: return "marginal";
    case Risk::chatter: return "chatter";
  }
  return "?";
}

// ------------------------------------------------------------------ process model

double contact_width_mm(const ProcessSettings& p, const planner::GeneratrixValue& part) {
  if (p.contact_width_mm) return *p.contact_width_mm;
  // Curvature of the part's generatrix seen from the wheel: > 0 where the part is convex (f'' < 0).
  const double kappa = -part.d2 / std::pow(1.0 + part.d1 * part.d1, 1.5);
  double section_width = p.wheel_thickness_mm;
  double inverse_rho = kappa;
  if (p.profiled_wheel) {
    inverse_rho += 1.0 / p.edge_radius_mm;
    section_width = 2.0 * p.edge_radius_mm * std::sin(0.5 * p.edge_angle_deg * kPi / 180.0);
  }
  const double h = p.depth_of_cut_mm;
  if (!(inverse_rho > 0.0)) return section_width;  // conforming or concave: the whole section
  const double rho = 1.0 / inverse_rho;
  if (h >= rho) return section_width;
  return std::min(section_width, 2.0 * std::sqrt(h * (2.0 * rho - h)));
}

namespace {

// map_segment with the engaged width already known: it depends on the part at the segment's
// middle only, so the phases of a modulated rating (the same segment at other speeds) share it.
SegmentProcess map_segment_with_width(const ProcessSettings& p, const planner::SegmentConditions& c,
                                      double contact_width_mm) {
  SegmentProcess s;
  s.x_mid_mm = 0.5 * (c.x_start_mm + c.x_end_mm);
  s.radius_mm = c.radius_mm;
  s.work_speed_rpm = c.spindle_speed_rpm;
  const double d_w = 2.0 * c.radius_mm, d_s = p.wheel_diameter_mm;
  s.work_surface_speed_m_per_s = surface_speed_m_per_s(d_w, c.spindle_speed_rpm);
  const double v_s = surface_speed_m_per_s(d_s, p.wheel_speed_rpm);
  s.speed_ratio = s.work_surface_speed_m_per_s / v_s;
  s.equivalent_diameter_mm = d_w * d_s / (d_w + d_s);
  s.contact_length_mm = std::sqrt(p.depth_of_cut_mm * s.equivalent_diameter_mm);
  s.contact_width_mm = contact_width_mm;
  s.axial_feed_per_rev_mm = std::abs(c.axial_speed_mm_per_s) * 60.0 / c.spindle_speed_rpm;
  s.overlap_ratio = std::max(0.0, 1.0 - s.axial_feed_per_rev_mm / s.contact_width_mm);
  return s;
}

}  // namespace

SegmentProcess map_segment(const ProcessSettings& p, const planner::SegmentConditions& c,
                           const planner::Generatrix& generatrix) {
  const planner::GeneratrixValue part = generatrix.evaluate(0.5 * (c.x_start_mm + c.x_end_mm));
  return map_segment_with_width(p, c, contact_width_mm(p, part));
}

const ProcessConditionsModel& process_model(const ProcessSettings& p) {
  const ProcessConditionsModel* process = p.model ? p.model->process_conditions() : nullptr;
  if (!process)
    throw std::invalid_argument("the model's parameters do not follow the process conditions (no "
                                "ProcessConditionsModel capability)");
  return *process;
}

ProcessConditions reference_conditions(const ProcessSettings& p) {
  ProcessConditions c = process_model(p).nominal_conditions();
  c.contact_width_mm = p.reference_contact_width_mm;
  c.work_radius_mm = p.reference_work_radius_mm;
  c.wheel_diameter_mm = p.wheel_diameter_mm;
  return c;
}

ProcessConditions segment_conditions(const ProcessSettings& p, const SegmentProcess& s) {
  ProcessConditions c;
  c.wheel_speed_rpm = p.wheel_speed_rpm;
  c.work_speed_rpm = s.work_speed_rpm;
  c.contact_width_mm = s.contact_width_mm;
  c.work_radius_mm = s.radius_mm;
  c.wheel_diameter_mm = p.wheel_diameter_mm;
  return c;
}

namespace {

Json model_table_at(const Json& model_table, const ProcessSettings& p, const ProcessConditions& conditions) {
  ProcessScaling scaling;
  scaling.speed_dependent_stiffness = p.speed_scaling;
  return with_type(model_table, process_model(p).parameters_at(reference_conditions(p), conditions, scaling));
}

}  // namespace

Json segment_model_table(const Json& model_table, const ProcessSettings& p, const SegmentProcess& s) {
  return model_table_at(model_table, p, segment_conditions(p, s));
}

// ------------------------------------------------------------------ risk

void accumulate(const std::vector<planner::SegmentConditions>& plan, const RiskThresholds& thresholds,
                PlanRisk& risk) {
  double log_a = 0.0, floored = 0.0;
  risk.max_growth_rate_per_s = -std::numeric_limits<double>::infinity();
  risk.max_floored_log_amplification = 0.0;
  risk.worst = Risk::stable;
  for (double& t : risk.time_in_risk_s) t = 0.0;
  const double chatter_log = std::log(thresholds.chatter_amplification);
  for (std::size_t k = 0; k < plan.size(); ++k) {
    SegmentRisk& r = risk.segments[k];
    const double growth = r.growth_rate_per_s * plan[k].duration_s;
    log_a += growth;
    floored = std::max(0.0, floored + growth);
    r.log_amplification = log_a;
    r.floored_log_amplification = floored;
    if (floored >= chatter_log)
      r.risk = Risk::chatter;
    else if (r.growth_rate_per_s > -thresholds.marginal_growth_rate_per_s || floored > 0.0)
      r.risk = Risk::marginal;
    else
      r.risk = Risk::stable;
    risk.max_growth_rate_per_s = std::max(risk.max_growth_rate_per_s, r.growth_rate_per_s);
    risk.max_floored_log_amplification = std::max(risk.max_floored_log_amplification, floored);
    risk.worst = std::max(risk.worst, r.risk);
    risk.time_in_risk_s[static_cast<int>(r.risk)] += plan[k].duration_s;
  }
  risk.final_log_amplification = log_a;
}

namespace {

// The items of a rating: each segment's process at the plan's speed, and per segment its `phases`
// frozen work speeds n (1 + a sin phi_j) (S2, eqs 5-37..5-39: the amplitude after many revolutions
// is the product of the per-revolution factors); a = 0: the segment itself.
struct RatingItems {
  std::vector<SegmentProcess> process;  // per segment
  std::vector<SegmentProcess> phases;   // per segment and phase (empty when there is one phase)
  int phase_count = 1;

  // The items whose roots the rating averages: the phases, or the segments themselves.
  const std::vector<SegmentProcess>& items() const { return phase_count == 1 ? process : phases; }
};

RatingItems rating_items(const ProcessSettings& p, const std::vector<planner::SegmentConditions>& plan,
                         const planner::Generatrix& generatrix, double amplitude_ratio, int phases) {
  RatingItems r;
  for (const auto& c : plan) r.process.push_back(map_segment(p, c, generatrix));
  r.phase_count = amplitude_ratio > 0.0 ? std::max(phases, 1) : 1;
  if (r.phase_count == 1) return r;
  r.phases.reserve(r.process.size() * static_cast<std::size_t>(r.phase_count));
  for (std::size_t k = 0; k < plan.size(); ++k)
    for (int j = 0; j < r.phase_count; ++j) {
      planner::SegmentConditions c = plan[k];
      c.spindle_speed_rpm *= 1.0 + amplitude_ratio * std::sin(2 * kPi * (j + 0.5) / r.phase_count);
      r.phases.push_back(map_segment_with_width(p, c, r.process[k].contact_width_mm));
    }
  return r;
}

// A rating from its items' groups and the groups' roots: the growth rate per segment averaged over
// its phases (the frequency and group of the fastest-growing phase), then the amplification.
PlanRisk assemble_rating(const std::vector<planner::SegmentConditions>& plan, const RiskThresholds& thresholds,
                         RatingItems&& rating, const std::vector<std::size_t>& group_of_item,
                         const std::vector<RootValue>& values) {
  PlanRisk risk;
  risk.process = std::move(rating.process);
  const int phase_count = rating.phase_count;
  std::vector<std::size_t> groups(group_of_item);
  std::sort(groups.begin(), groups.end());
  risk.groups = static_cast<std::size_t>(std::unique(groups.begin(), groups.end()) - groups.begin());
  risk.segments.resize(plan.size());
  for (std::size_t k = 0; k < plan.size(); ++k) {
    SegmentRisk& r = risk.segments[k];
    r.growth_rate_per_s = 0.0;
    r.certified = true;
    double best = -std::numeric_limits<double>::infinity();
    for (int j = 0; j < phase_count; ++j) {
      const std::size_t item = k * static_cast<std::size_t>(phase_count) + static_cast<std::size_t>(j);
      const RootValue& v = values[group_of_item[item]];
      r.growth_rate_per_s += v.growth_rate_per_s / phase_count;
      r.certified = r.certified && v.certified;
      if (v.growth_rate_per_s > best) {
        best = v.growth_rate_per_s;
        r.chatter_frequency_hz = v.frequency_hz;
        r.group = group_of_item[item];
      }
    }
  }
  accumulate(plan, thresholds, risk);
  return risk;
}

// A rating to compute: a plan at its speeds, and the modulation whose frozen-speed phases it averages.
struct RatingRequest {
  std::vector<planner::SegmentConditions> plan;
  double amplitude_ratio = 0.0;
};

// Rates the plans with one grouping and one batch of root searches. Ratings share condition groups
// only where that is the approximation already made within one rating: the phases of all
// modulated ratings (frozen speeds spread over +-amplitude around each one's speed) form one pool,
// so a cell that several candidates' phases visit is solved once (the shipped problem-2 study's
// candidates: about 1,200 roots instead of 6,600). An unmodulated rating keeps its own pool: it
// stands for its exact speed, whose verdict may hinge on an exact speed ratio (a representative
// from a rating 1 % away would hide or invent that artefact). Each rating's items are grouped in
// parallel, the groupings merged in rating order (the groups and representatives of one serial
// pass over all items) and the groups solved together (OpenMP over blocks of groups), so nothing
// depends on the thread count.
std::vector<PlanRisk> rate_plans(const Json& model_table, const ProcessSettings& p,
                                 const std::vector<RatingRequest>& requests, const planner::Generatrix& generatrix,
                                 const RootSettings& roots, const RiskThresholds& thresholds, int phases) {
  const std::size_t count = requests.size();
  std::vector<RatingItems> ratings(count);
  std::vector<Grouping> own(count);
  std::vector<std::vector<std::size_t>> group_of_item(count);
  parallel_tasks(count, [&](std::size_t t) {
    const RatingRequest& r = requests[t];
    ratings[t] = rating_items(p, r.plan, generatrix, r.amplitude_ratio, phases);
    const long long pool = r.amplitude_ratio > 0.0 ? 0 : static_cast<long long>(t) + 1;
    group_of_item[t] = group_items(p, ratings[t].items(), roots.condition_tolerance, own[t], pool);
    ratings[t].phases = {};  // the groups hold what the roots need
  });
  Grouping groups;
  for (std::size_t t = 0; t < count; ++t) {
    const std::vector<std::size_t> merged = merge_groups(groups, own[t]);
    for (std::size_t& g : group_of_item[t]) g = merged[g];
  }
  const std::vector<RootValue> values = solve_groups(model_table, p, groups, roots);
  std::vector<PlanRisk> rated(count);
  for (std::size_t t = 0; t < count; ++t)
    rated[t] = assemble_rating(requests[t].plan, thresholds, std::move(ratings[t]), group_of_item[t], values);
  return rated;
}

// The spindle-speed factors of a rating over the tolerance band: the nominal speed first.
std::vector<double> band_factors(double tolerance) {
  if (!(tolerance > 0.0)) return {1.0};
  return {1.0, 1.0 - tolerance, 1.0 + tolerance};
}

std::vector<planner::SegmentConditions> at_speed_factor(std::vector<planner::SegmentConditions> plan, double factor) {
  if (factor != 1.0)
    for (auto& c : plan) c.spindle_speed_rpm *= factor;
  return plan;
}

// The worst case per segment of the nominal rating and the band's shifted ratings.
PlanRisk worst_over_band(PlanRisk worst, const std::vector<const PlanRisk*>& shifted,
                         const std::vector<planner::SegmentConditions>& plan, const RiskThresholds& thresholds) {
  if (shifted.empty()) return worst;
  for (const PlanRisk* r : shifted)
    for (std::size_t k = 0; k < plan.size(); ++k) {
      SegmentRisk& w = worst.segments[k];
      w.certified = w.certified && r->segments[k].certified;
      if (r->segments[k].growth_rate_per_s > w.growth_rate_per_s) {
        w.growth_rate_per_s = r->segments[k].growth_rate_per_s;
        w.chatter_frequency_hz = r->segments[k].chatter_frequency_hz;
      }
    }
  accumulate(plan, thresholds, worst);
  return worst;
}

}  // namespace

PlanRisk evaluate_roots(const Json& model_table, const ProcessSettings& p,
                        const std::vector<planner::SegmentConditions>& plan,
                        const planner::Generatrix& generatrix, const RootSettings& roots,
                        const RiskThresholds& thresholds, double speed_tolerance) {
  // The nominal rating and (with a tolerance) the band's shifted ones: the worst case per segment.
  std::vector<RatingRequest> requests;
  for (double factor : band_factors(speed_tolerance)) requests.push_back({at_speed_factor(plan, factor), 0.0});
  std::vector<PlanRisk> rated = rate_plans(model_table, p, requests, generatrix, roots, thresholds, 1);
  std::vector<const PlanRisk*> shifted;
  for (std::size_t i = 1; i < rated.size(); ++i) shifted.push_back(&rated[i]);
  return worst_over_band(std::move(rated.front()), shifted, plan, thresholds);
}

// ------------------------------------------------------------------ simulation

namespace {

class AlongPlanModel final : public TimeDomainModel {
 public:
  AlongPlanModel(std::vector<std::unique_ptr<TimeDomainModel>> models, std::vector<std::size_t> model_of_segment,
                 std::vector<double> segment_start_s, double wheel_rpm, double work_rpm)
      : models_(std::move(models)), model_of_segment_(std::move(model_of_segment)),
        start_s_(std::move(segment_start_s)), wheel_rpm_(wheel_rpm), work_rpm_(work_rpm) {}

  std::size_t state_size() const override { return models_.front()->state_size(); }
  void initial_state(const Disturbance& d, std::span<double> state) const override {
    at(0.0).initial_state(d, state);
  }
  void state_scales(double displacement_m, std::span<double> scales) const override {
    at(0.0).state_scales(displacement_m, scales);
  }
  double highest_frequency_hz() const override {
    double f = 0.0;
    for (const auto& m : models_) f = std::max(f, m->highest_frequency_hz());
    return f;
  }
  bool regenerates(Rotor rotor) const override { return models_.front()->regenerates(rotor); }
  double nominal_speed_rpm(Rotor rotor) const override { return rotor == Rotor::wheel ? wheel_rpm_ : work_rpm_; }
  void contact(const ContactInput& in, ContactOutput& out) const override { at(in.t_s).contact(in, out); }
  void derivatives(const ContactInput& in, const ContactOutput& contact, std::span<double> dx) const override {
    at(in.t_s).derivatives(in, contact, dx);
  }
  double displacement_m(std::span<const double> state) const override { return models_.front()->displacement_m(state); }
  // Piecewise linear: the segment model's form, one id per condition group; it changes where the
  // next segment belongs to another group.
  std::optional<LinearForm> linear_form(double t_s) const override { return at(t_s).linear_form(t_s); }
  std::size_t linear_form_id(double t_s) const override { return model_of_segment_[segment(t_s)]; }
  double next_linear_form_change_s(double t_s) const override {
    const std::size_t k = segment(t_s);
    auto next = std::upper_bound(start_s_.begin(), start_s_.end(), t_s) - start_s_.begin();
    for (auto j = static_cast<std::size_t>(next); j < start_s_.size(); ++j)
      if (model_of_segment_[j] != model_of_segment_[k]) return start_s_[j];
    return std::numeric_limits<double>::infinity();
  }
  double linear_forcing(const ContactInput& in) const override { return at(in.t_s).linear_forcing(in); }

 private:
  // The segment in progress at t (the last whose start is <= t). The engine asks in time order,
  // mostly within one segment: the last answer is checked first (a binary search per call was 2 %
  // of a 3000 s plan's simulation). One simulation uses an instance, so the hint is not shared.
  std::size_t segment(double t) const {
    const std::size_t k = last_segment_;
    if (t >= start_s_[k] && (k + 1 == start_s_.size() || t < start_s_[k + 1])) return k;
    auto it = std::upper_bound(start_s_.begin(), start_s_.end(), t);
    last_segment_ = it == start_s_.begin() ? 0 : static_cast<std::size_t>(it - start_s_.begin()) - 1;
    return last_segment_;
  }
  const TimeDomainModel& at(double t) const { return *models_[model_of_segment_[segment(t)]]; }
  std::vector<std::unique_ptr<TimeDomainModel>> models_;
  std::vector<std::size_t> model_of_segment_;
  std::vector<double> start_s_;
  double wheel_rpm_, work_rpm_;
  mutable std::size_t last_segment_ = 0;
};

}  // namespace

std::unique_ptr<TimeDomainModel> along_plan_model(const Json& model_table, const ProcessSettings& p,
                                                  const std::vector<planner::SegmentConditions>& plan,
                                                  const PlanRisk& risk) {
  // Own grouping of the segments' parameters (exact to 1e-9): the risk's groups may merge
  // segments within the root tolerance or come from averaged phases.
  Grouping g;
  const std::vector<std::size_t> group_of_item = group_items(p, risk.process, 1e-9, g);
  std::map<std::size_t, std::size_t> model_of_group;
  std::vector<std::unique_ptr<TimeDomainModel>> models;
  std::vector<std::size_t> model_of_segment;
  std::vector<double> start;
  const double t0 = plan.empty() ? 0.0 : plan.front().start_s;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    auto [it, inserted] = model_of_group.emplace(group_of_item[k], models.size());
    if (inserted) {
      auto model = kit::build_model(segment_model_table(model_table, p, g.representative[group_of_item[k]]));
      auto td = model->time_domain();
      if (!td) throw std::invalid_argument("the model has no time-domain form");
      models.push_back(std::move(td));
    }
    model_of_segment.push_back(it->second);
    start.push_back(plan[k].start_s - t0);
  }
  return std::make_unique<AlongPlanModel>(std::move(models), std::move(model_of_segment), std::move(start),
                                          p.wheel_speed_rpm, plan.front().spindle_speed_rpm);
}

double fitted_growth_rate_per_s(const std::vector<RevolutionRow>& rows, double t0, double t1) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (const RevolutionRow& r : rows) {
    if (r.t_s < t0 || r.t_s > t1 || !(r.vibration_amplitude_m > 0)) continue;
    const double y = std::log(r.vibration_amplitude_m);
    n += 1;
    st += r.t_s;
    sy += y;
    stt += r.t_s * r.t_s;
    sty += r.t_s * y;
  }
  const double d = n * stt - st * st;
  return n >= 3 && d > 0 ? (n * sty - st * sy) / d : kNaN;
}

std::shared_ptr<const SpeedLaw> plan_spindle_speed(const std::vector<planner::SegmentConditions>& plan) {
  bool constant = true;
  for (const auto& c : plan) constant = constant && c.spindle_speed_rpm == plan.front().spindle_speed_rpm;
  if (constant) return make_modulated_speed(plan.front().spindle_speed_rpm, SpeedModulation::constant, 0.0, 0.0);
  // Each segment's speed held over the segment: a schedule with a short linear ramp (1 ms) at
  // each change, times from the plan's start.
  std::vector<double> times{0.0}, rpm{plan.front().spindle_speed_rpm};
  const double t0 = plan.front().start_s;
  for (std::size_t k = 1; k < plan.size(); ++k) {
    if (plan[k].spindle_speed_rpm == plan[k - 1].spindle_speed_rpm) continue;
    const double t = plan[k].start_s - t0;
    times.push_back(std::max(t - 1e-3, times.back() + 1e-9));
    rpm.push_back(plan[k - 1].spindle_speed_rpm);
    times.push_back(std::max(t, times.back() + 1e-9));
    rpm.push_back(plan[k].spindle_speed_rpm);
  }
  return make_scheduled_speed(std::move(times), std::move(rpm));
}

namespace {

// Per work revolution: extremes of the displacement and of the work surface generated (surface
// one revolution ago at the contact + this pass's removal), reduced from the streamed samples.
class RevolutionReducer {
 public:
  RevolutionReducer(const std::vector<planner::SegmentConditions>& plan, std::shared_ptr<const SpeedLaw> work,
                    std::vector<RevolutionRow>& rows)
      : plan_(plan), work_(std::move(work)), rows_(rows), t0_(plan.front().start_s) {}

  void add(const OutputSample& sample) {
    const long rev = static_cast<long>(std::floor(work_->angle_rad(sample.t_s) / (2 * kPi)));
    if (rev != revolution_) {
      flush();
      revolution_ = rev;
    }
    const double surface = sample.surface_at_contact_m[static_cast<std::size_t>(Rotor::work)] + sample.depth_of_cut_m;
    if (count_ == 0) {
      x_min_ = x_max_ = sample.displacement_m;
      w_min_ = w_max_ = surface;
      t_sum_ = 0;
    }
    x_min_ = std::min(x_min_, sample.displacement_m);
    x_max_ = std::max(x_max_, sample.displacement_m);
    w_min_ = std::min(w_min_, surface);
    w_max_ = std::max(w_max_, surface);
    t_sum_ += sample.t_s;
    ++count_;
  }

  void flush() {
    if (count_ == 0) return;
    RevolutionRow row;
    row.t_s = t_sum_ / static_cast<double>(count_);
    row.x_mm = x_at(row.t_s);
    row.vibration_amplitude_m = 0.5 * (x_max_ - x_min_);
    row.work_waviness_m = 0.5 * (w_max_ - w_min_);
    row.growth_rate_per_s = kNaN;
    rows_.push_back(row);
    count_ = 0;
  }

 private:
  // x at time t from the plan's start: linear inside each segment.
  double x_at(double t) const {
    auto it = std::upper_bound(plan_.begin(), plan_.end(), t + t0_,
                               [](double v, const planner::SegmentConditions& c) { return v < c.start_s; });
    const std::size_t k = it == plan_.begin() ? 0 : static_cast<std::size_t>(it - plan_.begin()) - 1;
    const auto& c = plan_[k];
    const double u = std::clamp((t + t0_ - c.start_s) / c.duration_s, 0.0, 1.0);
    return c.x_start_mm + u * (c.x_end_mm - c.x_start_mm);
  }

  const std::vector<planner::SegmentConditions>& plan_;
  std::shared_ptr<const SpeedLaw> work_;
  std::vector<RevolutionRow>& rows_;
  double t0_;
  long revolution_ = 0;
  double x_min_ = 0, x_max_ = 0, w_min_ = 0, w_max_ = 0, t_sum_ = 0;
  long count_ = 0;
};

// The engine's settings for the whole plan: bilateral (linear, as the roots) contact, streamed.
SimulationSettings along_plan_engine_settings(const AlongPlanSettings& settings, double duration_s,
                                              std::shared_ptr<const SpeedLaw> work) {
  SimulationSettings s;
  s.duration_s = duration_s;
  s.sample_rate_hz = settings.sample_rate_hz;
  s.disturbance = {settings.initial_waviness_m, 0.0};
  s.initial_waviness_m = settings.random_initial_surfaces ? settings.initial_waviness_m : 0.0;
  s.seed = settings.seed;
  s.one_sided_contact = false;  // the linear model of the roots (perturbation about the steady cut)
  s.speed[static_cast<std::size_t>(Rotor::work)] = std::move(work);
  s.integrator = settings.integrator;
  s.fixed_steps_per_wave = settings.fixed_steps_per_wave;
  s.relative_tolerance = settings.relative_tolerance;
  s.samples_per_wave = settings.samples_per_wave;
  s.store_samples = false;
  s.divergence_limit_m = settings.divergence_limit_m;
  return s;
}

}  // namespace

AlongPlanSimulation simulate_along_plan(const Json& model_table, const ProcessSettings& p,
                                        const std::vector<planner::SegmentConditions>& plan,
                                        const PlanRisk& risk, const AlongPlanSettings& settings) {
  AlongPlanSimulation out;
  const auto started = std::chrono::steady_clock::now();
  const double t0 = plan.front().start_s;
  const double duration = plan.back().start_s + plan.back().duration_s - t0;
  std::shared_ptr<const SpeedLaw> work = settings.work_speed;
  if (!work) work = plan_spindle_speed(plan);
  RevolutionReducer reducer(plan, work, out.revolutions);
  SimulationSettings s = along_plan_engine_settings(settings, duration, work);
  s.on_sample = [&](const OutputSample& sample) { reducer.add(sample); };
  try {
    auto model = along_plan_model(model_table, p, plan, risk);
    const SimulationResult r = simulate(*model, s);
    reducer.flush();
    out.status = r.status;
    out.diverged = r.diverged;
    out.end_time_s = r.end_time_s + t0;
    out.steps = r.steps;
  } catch (const std::exception& e) {
    reducer.flush();
    out.status = fmt::format("simulation failed: {}", e.what());
    out.failed = true;
  }
  // Rolling growth rate over fit_window_revolutions around each row (the first revolution, where
  // the random initial surface is not yet regenerated, is left out).
  const auto half = static_cast<std::size_t>(std::max(1.0, std::round(0.5 * settings.fit_window_revolutions)));
  auto& rows = out.revolutions;
  for (std::size_t i = 1 + half; i + half < rows.size(); ++i)
    rows[i].growth_rate_per_s = fitted_growth_rate_per_s(rows, rows[i - half].t_s, rows[i + half].t_s);
  for (RevolutionRow& row : rows) row.t_s += t0;
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

// ------------------------------------------------------------------ optimisation

namespace {

// The contiguous run of admissible candidates stable over their bands around the best one, among
// those with its modulation amplitude (candidates are generated in increasing speed).
void stable_window(OptimiseResult& result) {
  const Candidate& best = result.candidates[result.best];
  result.stable = best.worst == Risk::stable;
  std::vector<const Candidate*> row;
  for (const Candidate& c : result.candidates)
    if (c.amplitude_ratio == best.amplitude_ratio) row.push_back(&c);
  if (row.size() > 1) result.speed_spacing_rpm = row[1]->spindle_speed_rpm - row[0]->spindle_speed_rpm;
  if (!result.stable) return;
  std::size_t i = 0;
  while (row[i] != &best) ++i;
  auto ok = [&](std::size_t k) { return row[k]->admissible && row[k]->worst == Risk::stable; };
  std::size_t lo = i, hi = i;
  while (lo > 0 && ok(lo - 1)) --lo;
  while (hi + 1 < row.size() && ok(hi + 1)) ++hi;
  result.stable_window_rpm = std::pair{row[lo]->spindle_speed_rpm, row[hi]->spindle_speed_rpm};
}

// The candidates (amplitude ratio x spindle speed, in increasing speed per amplitude) and their
// plans at the spindle speed. The planner runs once per planning speed (a modulated candidate is
// planned at its lowest speed), the speeds in parallel: plans are independent and the planner's
// expression trees are immutable, so the plans are the same for any thread count.
std::vector<std::vector<planner::SegmentConditions>> candidates_and_plans(const Replan& replan,
                                                                        const OptimiseSettings& settings,
                                                                        std::vector<Candidate>& candidates) {
  for (double a : settings.amplitude_ratios) {
    const double lo = settings.spindle_min_rpm / (1.0 - a), hi = settings.spindle_max_rpm / (1.0 + a);
    if (!(a >= 0.0 && a < 1.0) || lo > hi * (1 + 1e-12))
      throw std::invalid_argument(fmt::format("amplitude ratio {} leaves no spindle speed in [{}, {}] rpm", a,
                                              settings.spindle_min_rpm, settings.spindle_max_rpm));
    const int steps = lo < hi ? std::max(settings.speed_steps, 1) : 1;
    for (int i = 0; i < steps; ++i) {
      Candidate c;
      c.amplitude_ratio = a;
      c.spindle_speed_rpm = steps == 1 ? std::min(lo, hi) : lo + (hi - lo) * i / (steps - 1);
      c.planning_speed_rpm = c.spindle_speed_rpm * (1.0 - a);
      candidates.push_back(c);
    }
  }
  std::map<double, std::size_t> plan_of_speed;  // planning speed -> index into plans
  for (const Candidate& c : candidates) plan_of_speed.emplace(c.planning_speed_rpm, plan_of_speed.size());
  std::vector<double> speeds(plan_of_speed.size());
  for (const auto& [speed, index] : plan_of_speed) speeds[index] = speed;
  std::vector<std::vector<planner::SegmentConditions>> plans(speeds.size());
  parallel_tasks(speeds.size(), [&](std::size_t k) { plans[k] = replan(speeds[k]); });
  std::vector<std::vector<planner::SegmentConditions>> candidate_plans;
  for (const Candidate& c : candidates) {
    std::vector<planner::SegmentConditions> plan = plans[plan_of_speed.at(c.planning_speed_rpm)];
    for (auto& seg : plan) seg.spindle_speed_rpm = c.spindle_speed_rpm;
    candidate_plans.push_back(std::move(plan));
  }
  return candidate_plans;
}

}  // namespace

OptimiseResult optimise(const Json& model_table, const ProcessSettings& p, const Replan& replan,
                        double baseline_time_s, const planner::Generatrix& generatrix,
                        const RootSettings& roots, const RiskThresholds& thresholds,
                        const OptimiseSettings& settings) {
  OptimiseResult result;
  RootSettings coarse = roots;
  coarse.condition_tolerance = settings.condition_tolerance;
  // 1. The candidates and their plans.
  std::vector<std::vector<planner::SegmentConditions>> candidate_plans =
      candidates_and_plans(replan, settings, result.candidates);
  // 2. Every rating (candidate x speed factor of the band, the nominal one also being the
  // candidate's nominal rating), in one batch (rate_plans: the modulated candidates' phases share
  // their roots).
  const std::vector<double> factors = band_factors(settings.speed_tolerance);
  const std::size_t per_candidate = factors.size();
  std::vector<RatingRequest> requests;
  for (std::size_t k = 0; k < result.candidates.size(); ++k)
    for (double factor : factors)
      requests.push_back({at_speed_factor(candidate_plans[k], factor), result.candidates[k].amplitude_ratio});
  std::vector<PlanRisk> rated =
      rate_plans(model_table, p, requests, generatrix, coarse, thresholds, settings.phase_samples);
  // 3. The band's worst case per candidate, and the best candidate in candidate order.
  bool found = false;
  for (std::size_t k = 0; k < result.candidates.size(); ++k) {
    Candidate& c = result.candidates[k];
    const std::vector<planner::SegmentConditions>& plan = candidate_plans[k];
    c.nominal_max_growth_rate_per_s = rated[k * per_candidate].max_growth_rate_per_s;
    std::vector<const PlanRisk*> shifted;
    for (std::size_t j = 1; j < per_candidate; ++j) shifted.push_back(&rated[k * per_candidate + j]);
    const PlanRisk risk = worst_over_band(std::move(rated[k * per_candidate]), shifted, plan, thresholds);
    if (c.amplitude_ratio == 0.0) c.exact_speed_ratio = kit::exact_ratio(p.wheel_speed_rpm, c.spindle_speed_rpm);
    c.total_time_s = plan.back().start_s + plan.back().duration_s - plan.front().start_s;
    c.time_factor = c.total_time_s / baseline_time_s;
    c.max_growth_rate_per_s = risk.max_growth_rate_per_s;
    c.max_floored_log_amplification = risk.max_floored_log_amplification;
    c.worst = risk.worst;
    c.admissible = c.time_factor <= settings.max_time_factor * (1 + 1e-12);
    if (!c.admissible) continue;
    const Candidate& b = result.candidates[result.best];
    const bool better = !found || c.max_floored_log_amplification < b.max_floored_log_amplification - 1e-9 ||
                        (std::abs(c.max_floored_log_amplification - b.max_floored_log_amplification) <= 1e-9 &&
                         (c.max_growth_rate_per_s < b.max_growth_rate_per_s - 1e-9 ||
                          (std::abs(c.max_growth_rate_per_s - b.max_growth_rate_per_s) <= 1e-9 &&
                           c.total_time_s < b.total_time_s)));
    if (better) {
      result.best = k;
      found = true;
    }
  }
  if (!found) throw PointFailure("chatter-aware planning: no candidate within the time limit");
  result.best_plan = std::move(candidate_plans[result.best]);
  stable_window(result);
  return result;
}

// ------------------------------------------------------------------ levers

namespace {

struct LeverDefinition {
  const char* name;
  const char* acts_on;
  void (*scale)(ProcessConditions& conditions, double factor);
};

const LeverDefinition lever_definitions[] = {
    {"width of cut", "engaged contact width b", [](ProcessConditions& c, double f) { c.contact_width_mm *= f; }},
    {"work speed", "work spindle speed", [](ProcessConditions& c, double f) { c.work_speed_rpm *= f; }},
    {"wheel speed", "wheel spindle speed", [](ProcessConditions& c, double f) { c.wheel_speed_rpm *= f; }},
    {"depth of cut", "depth of cut per work revolution", [](ProcessConditions& c, double f) { c.depth_of_cut_ratio *= f; }},
};

// The worst growth rate over the work-speed tolerance band, as the candidates are rated: a lever
// evaluated at an exact speed ratio alone would start from the ratio's artefact.
double growth_at(const Json& model_table, const ProcessSettings& p, const ProcessConditions& conditions,
                 const RootSettings& roots, double speed_tolerance) {
  double worst = -std::numeric_limits<double>::infinity();
  const kit::StabilitySettings stability = kit::stability_settings_table().read(roots.stability);
  for (double factor : {1.0 - speed_tolerance, 1.0, 1.0 + speed_tolerance}) {
    ProcessConditions at = conditions;
    at.work_speed_rpm *= factor;
    auto model = kit::build_model(model_table_at(model_table, p, at));
    worst = std::max(worst, kit::rightmost_root(*model, stability).root.real());
    if (!(speed_tolerance > 0.0)) break;
  }
  return worst;
}

}  // namespace

std::vector<Lever> stability_levers(const Json& model_table, const ProcessSettings& p, const SegmentProcess& segment,
                                    const RootSettings& roots, double target_growth_per_s, double speed_tolerance,
                                    double max_factor) {
  const ProcessConditions conditions = segment_conditions(p, segment);
  auto worst_growth = [&](const LeverDefinition& d, double factor) {
    ProcessConditions changed = conditions;
    d.scale(changed, factor);
    return growth_at(model_table, p, changed, roots, speed_tolerance);
  };
  constexpr double step = 0.05;  // central difference in ln(quantity)
  constexpr std::size_t count = std::size(lever_definitions);
  // The growth rate at the segment and the central differences: independent searches, in
  // parallel (task 0: the segment; 1 + 2i, 2 + 2i: lever i at e^{+-step}).
  std::vector<double> growth(1 + 2 * count);
  parallel_tasks(growth.size(), [&](std::size_t t) {
    growth[t] = t == 0 ? growth_at(model_table, p, conditions, roots, speed_tolerance)
                       : worst_growth(lever_definitions[(t - 1) / 2], std::exp((t % 2 == 1 ? 1.0 : -1.0) * step));
  });
  const double growth0 = growth[0];
  std::vector<Lever> levers(count);
  std::vector<double> log_changes(count, 0.0);
  for (std::size_t i = 0; i < count; ++i) {
    Lever& lever = levers[i];
    lever.name = lever_definitions[i].name;
    lever.acts_on = lever_definitions[i].acts_on;
    lever.growth_per_unit_log = (growth[1 + 2 * i] - growth[2 + 2 * i]) / (2 * step);
    lever.growth_rate_after_per_s = growth0;
    if (lever.growth_per_unit_log != 0.0) {
      const double limit = std::log(max_factor);
      const double log_change =
          std::clamp((target_growth_per_s - growth0) / lever.growth_per_unit_log, -limit, limit);
      lever.change_percent = 100.0 * (std::exp(log_change) - 1.0);
      log_changes[i] = log_change;
    }
  }
  // The change each lever needs, checked by its own search (in parallel).
  parallel_tasks(count, [&](std::size_t i) {
    Lever& lever = levers[i];
    if (!lever.change_percent) return;
    lever.growth_rate_after_per_s = worst_growth(lever_definitions[i], std::exp(log_changes[i]));
    lever.reaches_target = lever.growth_rate_after_per_s <= target_growth_per_s;
  });
  return levers;
}

}  // namespace chatterlab::feed_risk
