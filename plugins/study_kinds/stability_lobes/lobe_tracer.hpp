#pragma once
// Stability lobes: for every speed, the crossings of the imaginary axis (s = j w) by a
// characteristic root as one model parameter p varies, traced along each lobe by continuation in
// the speed; the lowest crossing per speed is the stability limit (the lobe diagram's envelope).
// docs/studies.md ("stability_lobes") explains the method for users; in short:
//
//   crossing     G(w; p, v) = 0 with G = E(j w) (roots route: the model's characteristic function)
//                or G = F(j w) (Nyquist route: the model's return difference): two real equations
//                in (w, p) at speed v.
//   bracketing   when p enters G as a Moebius map (p -> (a + b p)/(c + d p), affine included: every
//                stiffness of G1, in E and in F; checked against a fourth model), three models at
//                p0, p1, p2 give at every w the p*(w) that makes G vanish, by the invariance of
//                cross ratios; a crossing is where p*(w) is real. Sign changes of Im p*(w) over a
//                grid bracket the crossings, the Illinois method polishes them to 1e-14 in w, and
//                p = Re p*. Otherwise (a damping ratio, a natural frequency) sign changes of
//                Im(G conj dG/dp) seed a Newton iteration on (w, p) with dG/dw from the model and
//                dG/dp by a difference. Samples are packed around the model's fast frequencies
//                (delay lattices): a crossing of the wheel chain hides in a neighbourhood a
//                thousandth of a lattice spacing wide.
//   continuation each lobe is followed from speed to speed: predicted from its last two points (from
//                the tangent dG = 0 for a new lobe) and matched to the crossing nearest the
//                prediction, within a third of a lattice spacing and not taken by another lobe;
//                without one, the step is halved (points added between the user's speeds); a
//                crossing no lobe reached starts a new lobe, which is also followed backwards.
//   envelope     the lowest crossing at each speed; where the lowest lobe changes between two
//                speeds, the intersection of the two lobes is located (secant on p_a - p_b).
//
// In grinding both surfaces regenerate and the work period is long (G8: Tw = 1.09 s, Tg = 41 ms):
// a work lobe exists for every whole number of waves per work revolution (about one per
// n_w/60 Hz of chatter frequency), so a diagram over 25..85 rpm holds hundreds of lobes, each a
// short arc, whose envelope ripples a few per cent above the speed-independent limit of the
// compliance chart (G1 eq 2-21); the wheel lobes (one per 24 Hz) move only with the wheel speed.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/model.hpp"

namespace chatterlab::lobes {

enum class Route { roots, nyquist };

// The model at parameter value p and speed v (the kind sets the two keys in the [model] table).
using ModelAt = std::function<std::unique_ptr<Model>(double parameter, double speed)>;

struct Crossing {
  double speed = 0.0;
  double parameter = 0.0;
  double omega_rad_s = 0.0;  // chatter frequency on the boundary, rad/s
};

struct Lobe {
  int id = 0;
  std::vector<Crossing> points;  // ascending speed; includes points added between user speeds
};

struct TraceSettings {
  double parameter_min = 0.0, parameter_max = 0.0;
  double max_frequency_hz = 0.0;  // band of the scan
  Route route = Route::roots;
};

// The limit at one speed. Stable at the range's lower end: the lowest crossing, stable below it
// (a stiffness, a width). Unstable there but stable at the upper end: the highest crossing,
// stable above it (a damping ratio).
struct SpeedResult {
  std::optional<Crossing> limit;  // nullopt: none (see note)
  bool stable_below = true;       // which side of the limit is stable
  int lobe = -1;                  // id of the lobe giving the limit
  std::string note;               // why there is no limit ("stable over the whole range", ...)
};

struct LobeDiagram {
  std::vector<double> speeds;       // ascending (the user's speeds)
  std::vector<SpeedResult> at;      // one per speed
  std::vector<Lobe> lobes;
  std::vector<Crossing> envelope;   // the limit at each speed plus the lobe intersections between
  int seeds = 0, corrections = 0;   // work counters (benchmarks, docs)
  bool parameter_enters_as_moebius_map = false;  // crossings found without building more models
};

// Traces the lobes over `speeds` (sorted ascending, distinct). Throws PointFailure when the
// reference model cannot be built; a speed where nothing can be computed gets a note.
LobeDiagram trace_lobes(const ModelAt& model_at, const std::vector<double>& speeds, const TraceSettings& settings);

// The crossing polished by Newton from `guess` at its speed, or nullopt.
std::optional<Crossing> correct(const ModelAt& model_at, const Crossing& guess, Route route, double spacing_rad_s);

// dG/dw and dG/dp at a crossing, and dG/dq for a model differing in one more parameter: the
// boundary's sensitivity dp/dq = the p-component of -[G_w G_p]^{-1} G_q (G_w, G_p, G_q complex:
// two real equations). For a scalar characteristic function the characteristic matrix is 1 x 1
// and its left and right null vectors are 1, so this is the null-vector formula
// dp/dq = -Re-part solve of (w^H Delta_q v) against (w^H Delta_w v, w^H Delta_p v).
struct BoundaryDerivatives {
  Complex g_omega, g_parameter;
};
BoundaryDerivatives boundary_derivatives(const ModelAt& model_at, const Crossing& c, Route route);
// G at the crossing's (w) for `model` (a model at the crossing's p and v with one parameter changed).
Complex axis_value(const Model& model, double omega_rad_s, Route route);
// dp/dq from G_q = (G(q + dq) - G(q)) / dq.
double parameter_derivative(const BoundaryDerivatives& d, Complex g_q);

// Whether the model at (p, v) is stable: certified rightmost root (roots route, `band_hz`) or
// Nyquist count; nullopt when undecided (uncertified, unreliable count), with the reason.
struct StabilityCheck {
  std::optional<bool> stable;
  double growth_rate_per_s = 0.0;  // roots route only
  std::string reason;
};
StabilityCheck check_stability(const Model& model, Route route, double band_hz);

// Runs fn(0), ..., fn(n - 1) on the OpenMP team: as tasks when called inside a parallel region
// (the runner's: idle threads of its team pick them up), else in a parallel region of its own.
// The first exception is rethrown after all ran.
void for_each_index(std::size_t n, const std::function<void(std::size_t)>& fn);

}  // namespace chatterlab::lobes
