// The feed plan's figures (docs/planner.md, "Outputs"): the part with the replayed deviation on
// its own micrometre axis, the error along x against the tolerance with the segments where it
// binds, the segment lengths the tolerance chose, the pulse rates, the wear, and for point
// tables the fit residual and the curvature of the raw and the smoothed curve.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/plot.hpp"
#include "planner/plan_io.hpp"

namespace chatterlab::planner {

namespace {

constexpr double um_per_mm = 1000.0;

}  // namespace

void draw_plan_plots(const PlanRun& run, const Json& document, const std::filesystem::path& dir,
                     Json& failures) {
  const Schedule& s = run.schedule;
  const FeedPlan& plan = s.plan;
  const ProfileErrors& e = run.errors;
  const std::size_t n = plan.segments.size(), motors = plan.motors.size();
  const double tol_um = um_per_mm * run.tolerance_settings.max_profile_error_mm;
  auto draw = [&](const plot::Curves& figure, const std::string& stem) {
    try {
      plot::render(figure, dir, stem);
    } catch (const std::exception& ex) {
      failures.push_back(fmt::format("{}: {}", stem, ex.what()));
    }
  };
  const std::string name = document.contains("study") && document["study"].contains("name")
                               ? document["study"]["name"].get<std::string>() : "feed plan";
  // Segments where the tolerance binds: the replayed error uses >= 90 % of it.
  plot::Series binding{"tolerance binds (>= 90 % used)", {}, {}, "points"};
  for (std::size_t k = 0; k < n; ++k)
    if (e.segment_max_abs_mm(k) >= 0.9 * run.tolerance_settings.max_profile_error_mm) {
      binding.x.push_back(e.segment_x_mm[k]);
      binding.y.push_back(um_per_mm * (std::abs(e.segment_max_mm[k]) >= std::abs(e.segment_min_mm[k])
                                           ? e.segment_max_mm[k] : e.segment_min_mm[k]));
    }

  // The part (mm, left) and the replayed deviation (um, right): two quantities, two axes.
  plot::Curves profile;
  profile.title = fmt::format("{}: generatrix and replayed deviation", name);
  profile.x_label = "axial position x [mm]";
  profile.y_label = "radius f(x) [mm]";
  profile.y2_label = "normal deviation [um] (+ material left)";
  plot::Series nominal{"generatrix f(x) (left axis)", {}, {}, "lines"};
  plot::Series hi{"largest deviation in segment (right axis)", e.segment_x_mm, {}, "lines"};
  plot::Series lo{"smallest deviation in segment (right axis)", e.segment_x_mm, {}, "lines"};
  hi.right_axis = lo.right_axis = true;
  for (std::size_t k = 0; k < n; ++k) {
    nominal.x.push_back(e.segment_x_mm[k]);
    nominal.y.push_back(run.generatrix->evaluate(e.segment_x_mm[k]).f);
    hi.y.push_back(um_per_mm * e.segment_max_mm[k]);
    lo.y.push_back(um_per_mm * e.segment_min_mm[k]);
  }
  profile.series = {nominal, hi, lo};
  draw(profile, "profile");

  plot::Curves error;
  error.title = fmt::format("{}: replayed profile error, tolerance +-{:.3g} um ({})", name, tol_um,
                            run.tolerance.met ? "met" : "NOT met");
  error.x_label = "axial position x [mm]";
  error.y_label = "normal deviation [um] (+ material left)";
  // Both tolerance lines as one series (NaN breaks the line), so they share colour and key entry.
  const double x0 = s.knots_mm.front(), x1 = s.knots_mm.back(), gap = std::nan("");
  plot::Series band{fmt::format("tolerance +-{:.3g} um", tol_um), {x0, x1, gap, x0, x1},
                    {tol_um, tol_um, gap, -tol_um, -tol_um}, "dashes"};
  plot::Series emax{"largest in segment", e.segment_x_mm, hi.y, "lines"};
  plot::Series emin{"smallest in segment", e.segment_x_mm, lo.y, "lines"};
  error.series = {emax, emin, band};
  if (!binding.x.empty()) error.series.push_back(binding);
  error.reference_y = 0.0;
  error.reference_label = "generatrix";
  draw(error, "error_along_x");

  // The lengths the tolerance asked for (nominal knots) and the segments after the knot choice
  // moved each knot within +-25 % of its spacing to where the motor steps round best.
  plot::Curves lengths;
  lengths.title = fmt::format("{}: segment lengths ({} segments)", name, n);
  lengths.x_label = "axial position x [mm]";
  lengths.y_label = "segment length [mm]";
  lengths.y2_label = "replayed |error| / tolerance";
  plot::Series actual{"segment (left axis)", e.segment_x_mm, {}, "points"};
  plot::Series nominal_length{"nominal for the tolerance (left axis)", {}, {}, "steps"};
  plot::Series used{"largest |error| / tolerance (right axis)", e.segment_x_mm, {}, "lines"};
  used.right_axis = true;
  for (std::size_t k = 0; k < n; ++k) {
    actual.y.push_back(s.knots_mm[k + 1] - s.knots_mm[k]);
    used.y.push_back(e.segment_max_abs_mm(k) / run.tolerance_settings.max_profile_error_mm);
  }
  const auto& nk = run.tolerance.nominal_knots_mm;
  for (std::size_t k = 0; k + 1 < nk.size(); ++k) {
    nominal_length.x.push_back(nk[k]);
    nominal_length.y.push_back(nk[k + 1] - nk[k]);
  }
  lengths.series = {actual, nominal_length, used};
  draw(lengths, "segment_lengths");

  plot::Curves rates;
  rates.title = fmt::format("{}: pulse rate per motor", name);
  rates.x_label = "time t [s]";
  rates.y_label = "pulse rate [pulses/s] (signed)";
  for (std::size_t m = 0; m < motors; ++m) {
    plot::Series series{plan.motors[m].name + " motor", {}, {}, "lines"};
    for (std::size_t k = 0; k < n; ++k) {
      series.x.push_back(plan.segments[k].start_s + 0.5 * plan.segments[k].duration_s);
      series.y.push_back(static_cast<double>(plan.segments[k].pulses[m]) / plan.segments[k].duration_s);
    }
    rates.series.push_back(std::move(series));
  }
  draw(rates, "pulse_rates");

  if (run.sweep.law != "none") {
    plot::Curves wear;
    wear.title = fmt::format("{}: wear (contact dwell) over the wheel face", name);
    wear.x_label = "contact position on the wheel face [mm]";
    wear.y_label = "dwell time per bin [s]";
    wear.series = {{fmt::format("{} sweep, uniformity {:.3f}", run.sweep.law, run.wear.uniformity),
                    run.wear.bin_centre_mm, run.wear.dwell_s, "steps"}};
    draw(wear, "wear_histogram");
  }

  const PartGeometry& part = run.part;
  if (part.fit) {
    plot::Curves fit;
    fit.title = fmt::format("table about the smoothing spline ({}, RMS {:.3g} um)", part.smoothing,
                            um_per_mm * part.fit->residual_rms_mm);
    fit.x_label = "axial position x [mm]";
    fit.y_label = "measured - smoothed radius [um]";
    plot::Series residual{"table point - smoothing spline", part.table_x_mm, {}, "points"};
    for (std::size_t i = 0; i < part.table_x_mm.size(); ++i)
      residual.y.push_back(um_per_mm * (part.table_y_mm[i] - run.generatrix->evaluate(part.table_x_mm[i]).f));
    fit.series = {residual};
    fit.reference_y = 0.0;
    fit.reference_label = "smoothing spline";
    draw(fit, "table_residual");

    // Curvature of the raw (interpolating) and the smoothed curve: the noise shows here first.
    plot::Curves curvature;
    curvature.title = "curvature of the spline through the table and of the smoothing spline";
    curvature.x_label = "axial position x [mm]";
    curvature.y_label = "curvature f''/(1+f'^2)^1.5 [1/m] (+ concave)";
    // The key carries what each curve costs when ground: the effect of the noise on time and
    // reversals (the raw spline planned the same way, summary.json point_table).
    const NoiseEffect& raw_plan = run.noise;
    const std::string raw_cost =
        raw_plan.planned ? fmt::format(": plan {:.0f} s, {} reversals, edge radius <= {:.4g} mm", raw_plan.total_time_s,
                                       raw_plan.reversals, raw_plan.max_edge_radius_mm)
                         : ": no plan (" + raw_plan.failure + ")";
    plot::Series raw{"spline through the raw points" + raw_cost, {}, {}, "lines"};
    plot::Series smooth{fmt::format("smoothing spline (planned): {:.0f} s, {} reversals, edge radius <= {:.4g} mm",
                                    s.plan.total_time_s(), s.certificate.reversals, run.max_edge_radius_mm),
                        {}, {}, "lines"};
    const double a = run.generatrix->x_min_mm(), b = run.generatrix->x_max_mm();
    const std::size_t samples = std::min<std::size_t>(4000, 8 * part.table_x_mm.size());
    for (std::size_t i = 0; i <= samples; ++i) {
      const double x = a + (b - a) * static_cast<double>(i) / static_cast<double>(samples);
      auto kappa = [&](const GeneratrixValue& v) { return 1000.0 * v.d2 / std::pow(1 + v.d1 * v.d1, 1.5); };
      raw.x.push_back(x);
      raw.y.push_back(kappa(part.interpolating->evaluate(x)));
      smooth.x.push_back(x);
      smooth.y.push_back(kappa(run.generatrix->evaluate(x)));
    }
    curvature.series = {raw, smooth};
    curvature.reference_y = 0.0;
    curvature.reference_label = "straight";
    draw(curvature, "table_curvature");
  }
}

}  // namespace chatterlab::planner
