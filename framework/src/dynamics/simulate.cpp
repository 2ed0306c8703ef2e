// The dynamics engine: ARKODE ERKStep (Dormand-Prince 5(4); the structural dynamics are
// oscillatory, not stiff) or CVODE Adams (fixed-point iteration), in one-step mode; after every
// step the regenerated surfaces are written at the angle grid points the contact passed, from
// the step's dense output, and the output samples are taken the same way. One SUNContext +
// integrator per call, so concurrent calls are independent. docs/dynamics.md explains the method
// and the settings.
#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "dynamics/surface_memory.hpp"

namespace chatterlab {

namespace {

using dynamics_detail::SurfaceMemory;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::size_t kMaxSurfaceSamples = std::size_t{1} << 22;

// The data of a serial N_Vector (every vector of a run is serial: N_VNew_Serial and the
// integrators' clones of it). NV_DATA_S reads the pointer inline; N_VGetArrayPointer is a call
// through the vector's operation table, 5 % of a G1 run when called in every callback.
inline double* data(N_Vector v) { return NV_DATA_S(v); }

// Copies a state of n components. Fixed-size copies for the usual sizes (G1 with one or two
// modes, G5): std::copy of a run-time length is a library call, which for two components cost
// more than the copy (the right-hand-side cache and the interpolant copy states several times per
// step: 3 % of a G1 run by callgrind).
inline void copy_state(const double* from, std::size_t n, double* to) {
  switch (n) {
    case 2: std::copy_n(from, 2, to); return;
    case 4: std::copy_n(from, 4, to); return;
    case 8: std::copy_n(from, 8, to); return;
    default: std::copy_n(from, n, to);
  }
}

// The vector operations an explicit Runge-Kutta step spends its time in, for serial vectors,
// installed on the run's vectors (SUNDIALS takes user-supplied N_Vector operations; ARKODE's
// clones inherit them). The distribution's SUNDIALS 6.4.1 is compiled without optimisation
// (every value goes through the stack frame): N_VLinearCombination_Serial took ~370 instructions
// per call for a 2-component state, 20 % of a G1 run (callgrind). Same arithmetic, in the same
// order, as the serial originals.
namespace fast_serial {
inline sunindextype length(N_Vector v) { return NV_LENGTH_S(v); }
// z = sum_i c_i x_i for a state of N components: the N sums in registers, each operand's data
// pointer read once (in the generic loop below it is reloaded for every element, since the store
// to z may alias it): 116 instructions per call for a 2-component state there, 10 % of a G1 run
// (callgrind). The same sums in the same order.
template <int N>
void combine(int nvec, const sunrealtype* c, N_Vector* x, double* zd) {
  double sum[N];
  const double* x0 = data(x[0]);
  for (int j = 0; j < N; ++j) sum[j] = c[0] * x0[j];
  for (int i = 1; i < nvec; ++i) {
    const double* xi = data(x[i]);
    for (int j = 0; j < N; ++j) sum[j] += c[i] * xi[j];
  }
  for (int j = 0; j < N; ++j) zd[j] = sum[j];
}
int linear_combination(int nvec, sunrealtype* c, N_Vector* x, N_Vector z) {
  if (nvec < 1) return -1;
  const sunindextype n = length(z);
  double* zd = data(z);
  switch (n) {  // one or two structural modes (G1), G5's eight states
    case 2: combine<2>(nvec, c, x, zd); return 0;
    case 4: combine<4>(nvec, c, x, zd); return 0;
    case 8: combine<8>(nvec, c, x, zd); return 0;
    default: break;
  }
  // Element by element: safe when z is one of the x (ARKODE accumulates in place).
  for (sunindextype j = 0; j < n; ++j) {
    double sum = c[0] * data(x[0])[j];
    for (int i = 1; i < nvec; ++i) sum += c[i] * data(x[i])[j];
    zd[j] = sum;
  }
  return 0;
}
void linear_sum(sunrealtype a, N_Vector x, sunrealtype b, N_Vector y, N_Vector z) {
  const double *xd = data(x), *yd = data(y);
  double* zd = data(z);
  for (sunindextype j = 0, n = length(z); j < n; ++j) zd[j] = a * xd[j] + b * yd[j];
}
void scale(sunrealtype c, N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype j = 0, n = length(z); j < n; ++j) zd[j] = c * xd[j];
}
sunrealtype weighted_square_sum(N_Vector x, N_Vector w) {
  const double *xd = data(x), *wd = data(w);
  double sum = 0.0;
  for (sunindextype j = 0, n = length(x); j < n; ++j) sum += (xd[j] * wd[j]) * (xd[j] * wd[j]);
  return sum;
}
sunrealtype weighted_rms_norm(N_Vector x, N_Vector w) {
  return std::sqrt(weighted_square_sum(x, w) / static_cast<double>(length(x)));
}
void install(N_Vector v) {
  v->ops->nvlinearcombination = linear_combination;
  v->ops->nvlinearsum = linear_sum;
  v->ops->nvscale = scale;
  v->ops->nvwsqrsumlocal = weighted_square_sum;
  v->ops->nvwrmsnorm = weighted_rms_norm;
}
}  // namespace fast_serial

// RAII owner of the SUNDIALS objects and the one integrator of a run: CVODE Adams or ARKODE
// ERKStep (SimulationSettings::integrator), behind the few calls the engine needs.
class Integrator {
 public:
  using Rhs = int (*)(sunrealtype, N_Vector, N_Vector, void*);
  using Root = int (*)(sunrealtype, N_Vector, sunrealtype*, void*);
  using Weights = int (*)(N_Vector, N_Vector, void*);
  using ErrorHandler = void (*)(int, const char*, const char*, char*, void*);

  Integrator() {
    if (SUNContext_Create(nullptr, &context_) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~Integrator() {
    if (cvode_) CVodeFree(&cvode_);
    if (erk_) ERKStepFree(&erk_);
    if (solver_) SUNNonlinSolFree(solver_);
    for (N_Vector v : {y, dky, abstol, f_})
      if (v) N_VDestroy(v);
    SUNContext_Free(&context_);
  }
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  void allocate(std::size_t n) {
    y = N_VNew_Serial(static_cast<sunindextype>(n), context_);
    // Fused vector operations: the integrators clone y, and a Runge-Kutta stage then costs one
    // linear-combination call instead of one call per term.
    N_VEnableFusedOps_Serial(y, SUNTRUE);
    fast_serial::install(y);
    dky = N_VNew_Serial(static_cast<sunindextype>(n), context_);
    abstol = N_VNew_Serial(static_cast<sunindextype>(n), context_);
  }

  // Creates the integrator at t = 0 from y. max_step bounds every step; t_end is the stop time.
  void create(TimeIntegrator kind, Rhs rhs, Weights weights, ErrorHandler on_error, void* user,
              double max_step, double t_end) {
    rhs_ = rhs;
    user_ = user;
    if (kind == TimeIntegrator::adams) {
      cvode_ = CVodeCreate(CV_ADAMS, context_);
      if (!cvode_) throw std::runtime_error("CVodeCreate failed");
      CVodeSetErrHandlerFn(cvode_, on_error, user);
      if (CVodeInit(cvode_, rhs, 0.0, y) != CV_SUCCESS) throw std::runtime_error("CVodeInit failed");
      CVodeSetUserData(cvode_, user);
      CVodeWFtolerances(cvode_, weights);
      solver_ = SUNNonlinSol_FixedPoint(y, 0, context_);
      CVodeSetNonlinearSolver(cvode_, solver_);
      CVodeSetMaxStep(cvode_, max_step);
      CVodeSetMaxNumSteps(cvode_, 100000);
      CVodeSetStopTime(cvode_, t_end);
      return;
    }
    f_ = N_VClone(y);
    erk_ = ERKStepCreate(rhs, 0.0, y, context_);
    if (!erk_) throw std::runtime_error("ERKStepCreate failed");
    ERKStepSetErrHandlerFn(erk_, on_error, user);
    ERKStepSetUserData(erk_, user);
    ERKStepSetTableNum(erk_, kErkTable);
    ERKStepWFtolerances(erk_, weights);
    ERKStepSetInterpolantDegree(erk_, 3);
    ERKStepSetMaxStep(erk_, max_step);
    ERKStepSetMaxNumSteps(erk_, 100000);
    ERKStepSetStopTime(erk_, t_end);
    start_interpolant(0.0);
  }
  void root_init(Root g) {
    if (cvode_) CVodeRootInit(cvode_, 1, g);
    else ERKStepRootInit(erk_, 1, g);
  }
  // One internal step towards t_end; returns the flag (0 step, 1 stop time, 2 root, < 0 failure).
  int step(double t_end, double& t_new) {
    return cvode_ ? CVode(cvode_, t_end, y, &t_new, CV_ONE_STEP)
                  : ERKStepEvolve(erk_, t_end, y, &t_new, ARK_ONE_STEP);
  }
  static constexpr int root_return = CV_ROOT_RETURN;
  static_assert(CV_ROOT_RETURN == ARK_ROOT_RETURN);
  // Dense output at t inside the last step, into dky.
  bool dense_output(double t) {
    if (cvode_) return CVodeGetDky(cvode_, t, 0, dky) == CV_SUCCESS;
    const double h = t1_ - t0_;
    if (!(t >= t0_ - 1e-12 * std::abs(h) && t <= t1_ + 1e-12 * std::abs(h))) return false;
    const double u = h > 0.0 ? (t - t0_) / h : 1.0;
    double* out = data(dky);
    const std::size_t n = y1_.size();
    if (quintic_) {
      // P(u) = ya + w (ga + w (d2 + u (d3 + u (d4 + (u - 1) d5)))), w = u - a (record_step).
      const double w = u - a_;
      for (std::size_t i = 0; i < n; ++i) {
        const double* d = &newton_[6 * i];
        out[i] = d[0] + w * (d[1] + w * (d[2] + u * (d[3] + u * (d[4] + (u - 1.0) * d[5]))));
      }
      return true;
    }
    // Cubic Hermite from y and f at the step's two ends (the first step after a (re)start).
    const double a0 = (1.0 - u) * (1.0 - u) * (1.0 + 2.0 * u), a1 = u * u * (3.0 - 2.0 * u);
    const double b0 = h * u * (1.0 - u) * (1.0 - u), b1 = -h * u * u * (1.0 - u);
    for (std::size_t i = 0; i < n; ++i) out[i] = a0 * y0_[i] + a1 * y1_[i] + b0 * f0_[i] + b1 * f1_[i];
    return true;
  }
  // After a successful step to t_new (y holds the new state): the new step's interpolant. ERK
  // only: f at (t_new, y) is one right-hand side; for Dormand-Prince it is the last stage of the
  // step and the first of the next, so the engine's right-hand-side cache answers it.
  //
  // Dense output (docs/dynamics.md): the quintic Hermite interpolant through y and f at the ends
  // of the last two steps (t_a < t_0 < t_1), evaluated on [t_0, t_1]. Its error is
  // y^(6) (t - t_a)^2 (t - t_0)^2 (t - t_1)^2 / 720: for an oscillation at w with h w = 1 about
  // 1.6e-4 of the amplitude, against (h w)^4 / 384 = 2.6e-3 for the cubic Hermite of one step,
  // whose error systematically shrinks the surfaces the engine writes from it (a bias of the
  // regenerative loop gain, i.e. of the growth rate). Right after a (re)start there is no
  // previous step (a contact switch is a kink): cubic Hermite then.
  void record_step(double t_new) {
    if (cvode_) return;
    ta_ = t0_;
    t0_ = t1_;
    std::swap(ya_, y0_);
    std::swap(fa_, f0_);
    std::swap(y0_, y1_);
    std::swap(f0_, f1_);
    set_end(t_new);
    // Both steps of positive length (a zero-length step, e.g. at a stop time, has no slope
    // information to add and would divide by zero).
    quintic_ = have_previous_ && t1_ > t0_ && t0_ > ta_;
    have_previous_ = true;
    if (!quintic_) return;
    // Confluent Newton divided differences on u = (t - t0)/h at the nodes a, a, 0, 0, 1, 1
    // (a = (ta - t0)/h < 0), derivatives scaled to u (g = h f).
    const double h = t1_ - t0_;
    const double a = (ta_ - t0_) / h;
    a_ = a;
    const std::size_t n = y1_.size();
    newton_.resize(6 * n);
    for (std::size_t i = 0; i < n; ++i) {
      const double ga = h * fa_[i], g0 = h * f0_[i], g1 = h * f1_[i];
      const double f12 = (y0_[i] - ya_[i]) / (-a), f34 = y1_[i] - y0_[i];
      const double f012 = (f12 - ga) / (-a), f123 = (g0 - f12) / (-a);
      const double f234 = f34 - g0, f345 = g1 - f34;
      const double f0123 = (f123 - f012) / (-a), f1234 = (f234 - f123) / (1.0 - a), f2345 = f345 - f234;
      const double f01234 = (f1234 - f0123) / (1.0 - a), f12345 = (f2345 - f1234) / (1.0 - a);
      double* d = &newton_[6 * i];
      d[0] = ya_[i];
      d[1] = ga;
      d[2] = f012;
      d[3] = f0123;
      d[4] = f01234;
      d[5] = (f12345 - f01234) / (1.0 - a);
    }
  }
  int root_direction() {
    int direction = 0;
    if (cvode_) CVodeGetRootInfo(cvode_, &direction);
    else ERKStepGetRootInfo(erk_, &direction);
    return direction;
  }
  // Restart at (t, y) (a kink in the right-hand side: contact switch).
  void restart(double t) {
    restarts_steps_ += steps_since_restart();  // re-initialising zeroes the integrator's count
    if (cvode_) CVodeReInit(cvode_, t, y);
    else ERKStepReInit(erk_, rhs_, t, y);
    if (erk_) start_interpolant(t);
  }
  long steps() { return restarts_steps_ + steps_since_restart(); }
  void current(double& h, double& t) {
    if (cvode_) {
      CVodeGetCurrentStep(cvode_, &h);
      CVodeGetCurrentTime(cvode_, &t);
    } else {
      ERKStepGetCurrentStep(erk_, &h);
      ERKStepGetCurrentTime(erk_, &t);
    }
  }
  // "CVODE CV_TOO_CLOSE" / "ARKODE ARK_ERR_FAILURE"; step-size collapse flags are the same
  // numbers in both packages.
  std::string flag_name(int flag) const {
    char* name = cvode_ ? CVodeGetReturnFlagName(flag) : ERKStepGetReturnFlagName(flag);
    std::string text = fmt::format("{} {}", cvode_ ? "CVODE" : "ARKODE", name);
    free(name);  // both allocate
    return text;
  }
  static bool step_size_collapse(int flag) {
    static_assert(CV_TOO_CLOSE == ARK_TOO_CLOSE && CV_ERR_FAILURE == ARK_ERR_FAILURE &&
                  CV_CONV_FAILURE == ARK_CONV_FAILURE);
    return flag == CV_TOO_CLOSE || flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE;
  }

  N_Vector y = nullptr, dky = nullptr, abstol = nullptr;

 private:
  void set_end(double t) {
    const auto n = static_cast<std::size_t>(NV_LENGTH_S(y));  // inline, as data()
    const double* x = data(y);
    y1_.resize(n);
    copy_state(x, n, y1_.data());
    rhs_(t, y, f_, user_);
    const double* f = data(f_);
    f1_.resize(n);
    copy_state(f, n, f1_.data());
    t1_ = t;
  }
  void start_interpolant(double t) {
    have_previous_ = quintic_ = false;
    set_end(t);
    t0_ = t;
    y0_ = y1_;
    f0_ = f1_;
  }
  long steps_since_restart() {
    long n = 0;
    if (cvode_) CVodeGetNumSteps(cvode_, &n);
    else ERKStepGetNumSteps(erk_, &n);
    return n;
  }
  // ERK table: see docs/dynamics.md (settings).
  static constexpr ARKODE_ERKTableID kErkTable = ARKODE_DORMAND_PRINCE_7_4_5;

  SUNContext context_ = nullptr;
  SUNNonlinearSolver solver_ = nullptr;
  void* cvode_ = nullptr;
  void* erk_ = nullptr;
  Rhs rhs_ = nullptr;
  void* user_ = nullptr;
  N_Vector f_ = nullptr;
  // ERK: the last two steps [ta, t0], [t0, t1] and y, f at their ends; the quintic's Newton
  // coefficients (6 per component) when the step before exists (have_previous_).
  double ta_ = 0.0, t0_ = 0.0, t1_ = 0.0, a_ = 0.0;
  std::vector<double> ya_, y0_, y1_, fa_, f0_, f1_, newton_;
  bool have_previous_ = false, quintic_ = false;
  long restarts_steps_ = 0;
};

void validate(const SimulationSettings& s) {
  auto positive = [](double v, const char* what) {
    if (!(std::isfinite(v) && v > 0.0)) throw std::invalid_argument(fmt::format("{} must be > 0", what));
  };
  positive(s.duration_s, "duration_s");
  positive(s.sample_rate_hz, "sample_rate_hz");
  positive(s.relative_tolerance, "relative_tolerance");
  positive(s.samples_per_wave, "samples_per_wave");
  positive(s.max_steps_per_wave, "max_steps_per_wave");
  positive(s.divergence_limit_m, "divergence_limit_m");
  const double samples = s.duration_s * s.sample_rate_hz;
  if (s.store_samples && samples > max_output_samples)
    throw std::invalid_argument(fmt::format(
        "duration_s * sample_rate_hz = {:.4g} output samples exceeds the limit of {:.4g}: shorten "
        "the run or lower the sample rate",
        samples, max_output_samples));
  for (double arc : s.contact_arc_deg)
    if (!(std::isfinite(arc) && arc >= 0.0 && arc < 90.0))
      throw std::invalid_argument("contact arc must be in [0, 90) deg");
  for (double t : s.snapshot_times_s)
    if (!(std::isfinite(t) && t >= 0.0 && t <= s.duration_s))
      throw std::invalid_argument(fmt::format("snapshot time {} s is outside [0, duration_s]", t));
}

class Engine {
 public:
  Engine(const TimeDomainModel& model, const SimulationSettings& settings)
      : model_(model), settings_(settings), n_(model.state_size()), state_scratch_(n_), cache_y_(n_), cache_f_(n_) {
    validate(settings);
    f_max_ = model.highest_frequency_hz();
    if (!(std::isfinite(f_max_) && f_max_ > 0.0))
      throw std::logic_error("TimeDomainModel::highest_frequency_hz must be > 0");
    for (std::size_t r = 0; r < rotor_count; ++r) setup_rotor(static_cast<Rotor>(r));
    result_.end_state.assign(n_, 0.0);
  }

  SimulationResult run();

  // CVODE callbacks.
  static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* self) {
    auto& e = *static_cast<Engine*>(self);
    std::span<const double> x(data(y), e.n_);
    std::span<double> dx(data(ydot), e.n_);
    // The same (t, y) again: Dormand-Prince's last stage is f at the new step end, which the
    // dense output needs too (record_step) and ARKODE evaluates again as the next step's first
    // stage; answered from the cache, bit for bit what the evaluation would give: f depends on
    // (t, y) and on surface samples one revolution back, which later writes never change (a
    // read whose stencil reached the newest samples invalidates the cache at the next write).
    if (e.cache_valid_ && t == e.cache_t_ && std::equal(x.begin(), x.end(), e.cache_y_.begin())) {
      copy_state(e.cache_f_.data(), e.n_, dx.data());
      return 0;
    }
    ++e.rhs_evaluations_;
    ContactInput& in = e.contact_input_;
    ContactOutput out;
    e.evaluate_contact(t, x, in, out);
    e.model_.derivatives(in, out, dx);
    e.cache_valid_ = std::all_of(dx.begin(), dx.end(), [](double v) { return std::isfinite(v); });
    if (!e.cache_valid_) {
      // A derivative that is not a number would make ARKODE's error test fail without bound
      // (the step adaptation then loops for ever): stop the integrator with an unrecoverable
      // failure (its flag, and the run a PointFailure naming the time).
      if (e.nonfinite_rhs_.empty())
        e.nonfinite_rhs_ = fmt::format("right-hand side not finite at t = {:.6g} s", t);
      return -1;
    }
    e.cache_t_ = t;
    copy_state(x.data(), e.n_, e.cache_y_.data());
    copy_state(dx.data(), e.n_, e.cache_f_.data());
    e.cache_settled_ = e.reads_settled(in);
    return 0;
  }
  static int root(sunrealtype t, N_Vector y, sunrealtype* g, void* self) {
    auto& e = *static_cast<Engine*>(self);
    std::span<const double> x(data(y), e.n_);
    ContactInput in;
    ContactOutput out;
    e.evaluate_contact(t, x, in, out, false);
    g[0] = out.penetration_m;
    return 0;
  }
  static int error_weights(N_Vector y, N_Vector weights, void* self) {
    auto& e = *static_cast<Engine*>(self);
    const double* x = data(y);
    const double* atol = data(e.sun_.abstol);
    double* w = data(weights);
    for (std::size_t i = 0; i < e.n_; ++i) w[i] = 1.0 / (e.settings_.relative_tolerance * std::abs(x[i]) + atol[i]);
    return 0;
  }
  static void silent_error(int, const char*, const char*, char* message, void* self) {
    static_cast<Engine*>(self)->last_error_ = message;
  }

 private:
  struct RotorState {
    std::shared_ptr<const SpeedLaw> law;       // null when the angle is a model state
    std::optional<std::size_t> angle_state;    // index of the angle in the state
    std::optional<SurfaceMemory> surface;      // when regenerated
    // A law constant over the run: its speed [rad/s] (angle = omega t), read without the
    // virtual calls of the law (0 otherwise). Reads of speed and angle are the engine's
    // innermost operation (every right-hand side, surface write and sample).
    double constant_rad_per_s = 0.0;
    double constant_rpm = 0.0;
    double arc_rad = 0.0;
  };

  void setup_rotor(Rotor r) {
    RotorState& rotor = rotors_[static_cast<std::size_t>(r)];
    rotor.angle_state = model_.angle_state(r);
    double min_rpm = model_.nominal_speed_rpm(r);
    double max_rpm = min_rpm;
    if (!rotor.angle_state) {
      rotor.law = settings_.speed[static_cast<std::size_t>(r)];
      if (!rotor.law)
        rotor.law = make_modulated_speed(model_.nominal_speed_rpm(r), SpeedModulation::constant, 0.0, 0.0);
      min_rpm = rotor.law->min_rpm(settings_.duration_s);
      max_rpm = rotor.law->max_rpm(settings_.duration_s);
      if (min_rpm == max_rpm && min_rpm > 0.0) {
        rotor.constant_rpm = min_rpm;
        rotor.constant_rad_per_s = kTwoPi / 60.0 * min_rpm;
      }
    } else {
      min_rpm *= 0.5;  // a state speed varies; resolve a revolution at half the nominal speed
      max_rpm *= 2.0;
    }
    if (!(min_rpm > 0.0)) throw std::invalid_argument(fmt::format("{} speed must stay > 0 rpm", to_string(r)));
    max_rpm_ = std::max(max_rpm_, max_rpm);
    rotor.arc_rad = settings_.contact_arc_deg[static_cast<std::size_t>(r)] * kTwoPi / 360.0;
    if (!model_.regenerates(r)) return;
    // Samples per revolution: samples_per_wave at the highest frequency over the longest
    // revolution, so the cubic interpolation error stays ~1e-5 of the wave amplitude.
    double wanted = std::ceil(settings_.samples_per_wave * f_max_ * 60.0 / min_rpm);
    auto samples = static_cast<std::size_t>(std::clamp(wanted, 64.0, static_cast<double>(kMaxSurfaceSamples)));
    if (wanted > static_cast<double>(kMaxSurfaceSamples))
      diagnostics_.push_back(fmt::format(
          "{} surface: {} samples per revolution capped at {} (speed down to {:.3g} rpm)",
          to_string(r), wanted, kMaxSurfaceSamples, min_rpm));
    std::vector<double> initial;
    if (settings_.initial_waviness_m > 0.0) {
      std::mt19937_64 random(settings_.seed + static_cast<std::uint64_t>(r));
      std::uniform_real_distribution<double> uniform(-settings_.initial_waviness_m,
                                                     settings_.initial_waviness_m);
      initial.resize(samples);
      for (double& v : initial) v = uniform(random);
    }
    rotor.surface.emplace(samples, std::move(initial), rotor.arc_rad > 0.0);
    result_.surface_samples_per_rev[static_cast<std::size_t>(r)] = samples;
  }

  double rotor_angle(std::size_t r, double t, std::span<const double> x) const {
    const RotorState& rotor = rotors_[r];
    if (rotor.constant_rad_per_s > 0.0) return rotor.constant_rad_per_s * t;
    return rotor.law ? rotor.law->angle_rad(t) : x[*rotor.angle_state];
  }
  double rotor_rpm(std::size_t r, double t, std::span<const double> x) const {
    const RotorState& rotor = rotors_[r];
    if (rotor.constant_rpm > 0.0) return rotor.constant_rpm;
    return rotor.law ? rotor.law->rpm(t) : model_.speed_rpm_from_state(static_cast<Rotor>(r), x);
  }

  // Builds the model's input at (t, x) and settles one-sided contact.
  // known_rotor < rotor_count: that rotor's previous surface is known_previous_m (a surface
  // write at its own grid angle, where it is exactly the sample one revolution back).
  void evaluate_contact(double t, std::span<const double> x, ContactInput& in, ContactOutput& out,
                        bool settle = true, std::size_t known_rotor = rotor_count,
                        double known_previous_m = 0.0) const {
    in.t_s = t;
    in.state = x;
    if (settings_.infeed) {
      in.infeed_m = settings_.infeed->infeed_m(t);
      in.infeed_rate_m_per_s = settings_.infeed->rate_m_per_s(t);
    } else {
      in.infeed_m = settings_.infeed_rate_m_per_s * t;
      in.infeed_rate_m_per_s = settings_.infeed_rate_m_per_s;
    }
    for (std::size_t r = 0; r < rotor_count; ++r) {
      in.speed_rpm[r] = rotor_rpm(r, t, x);
      in.angle_rad[r] = rotor_angle(r, t, x);
      const RotorState& rotor = rotors_[r];
      in.previous_surface_m[r] = r == known_rotor ? known_previous_m
                                 : rotor.surface     ? rotor.surface->mean(in.angle_rad[r] - kTwoPi, rotor.arc_rad)
                                                     : 0.0;
    }
    model_.contact(in, out);
    if (settle && settings_.one_sided_contact && !(out.penetration_m > 0.0)) {
      out.normal_force_n = out.tangential_force_n = out.depth_of_cut_m = 0.0;
      for (double& removed : out.removed_m) removed = 0.0;
    }
  }

  // State at t inside the last step (dense output), or the initial state before any step.
  std::span<const double> state_at(double t) {
    if (!stepped_) return {data(sun_.y), n_};
    if (!sun_.dense_output(t)) throw std::logic_error("dense output outside the last step");
    return {data(sun_.dky), n_};
  }

  // Time in [t_lo, t_hi] at which rotor r reaches angle `target` (angles increase): Newton on
  // angle(t) with the speed as derivative, kept inside a shrinking bracket.
  double time_of_angle(std::size_t r, double target, double t_lo, double t_hi) {
    const RotorState& rotor = rotors_[r];
    if (rotor.constant_rad_per_s > 0.0) return std::clamp(target / rotor.constant_rad_per_s, t_lo, t_hi);
    // A speed law needs no state: angle and speed are functions of time alone.
    auto angle = [&](double t) { return rotor.law ? rotor.law->angle_rad(t) : rotor_angle(r, t, state_at(t)); };
    auto rate = [&](double t) {
      return kTwoPi / 60.0 * (rotor.law ? rotor.law->rpm(t) : rotor_rpm(r, t, state_at(t)));
    };
    double a_lo = angle(t_lo), a_hi = angle(t_hi);
    if (a_hi <= a_lo) return t_hi;
    double t = t_lo + (target - a_lo) / (a_hi - a_lo) * (t_hi - t_lo);
    for (int it = 0; it < 30; ++it) {
      t = std::clamp(t, t_lo, t_hi);
      const double residual = angle(t) - target;
      if (residual > 0) t_hi = t; else t_lo = t;
      if (std::abs(residual) <= 1e-13 * std::max(1.0, std::abs(target)) || t_hi - t_lo < 1e-15 * std::max(1.0, t))
        return t;
      const double speed = rate(t);
      const double next = speed > 0 ? t - residual / speed : 0.5 * (t_lo + t_hi);
      t = (next > t_lo && next < t_hi) ? next : 0.5 * (t_lo + t_hi);
    }
    return t;
  }

  // True if every surface read of `in` used written (or initial) samples only, so that later
  // writes cannot change it (the right-hand-side cache relies on this).
  bool reads_settled(const ContactInput& in) const {
    for (std::size_t r = 0; r < rotor_count; ++r) {
      const RotorState& rotor = rotors_[r];
      if (rotor.surface && !rotor.surface->settled(in.angle_rad[r] - kTwoPi + 0.5 * rotor.arc_rad)) return false;
    }
    return true;
  }

  // Writes every surface grid point the contact passed up to time t_end.
  void write_surfaces(double t_start, double t_end) {
    if (!cache_settled_) cache_valid_ = false;
    for (std::size_t r = 0; r < rotor_count; ++r) {
      RotorState& rotor = rotors_[r];
      if (!rotor.surface) continue;
      SurfaceMemory& surface = *rotor.surface;
      // A speed law needs no state (no dense-output call per step and rotor).
      const double end_angle = rotor.law ? rotor_angle(r, t_end, {}) : rotor_angle(r, t_end, state_at(t_end));
      double t_lo = t_start;
      const auto n = static_cast<std::int64_t>(surface.samples_per_rev());
      while (static_cast<double>(surface.next_index()) * surface.spacing_rad() <= end_angle) {
        const std::int64_t k = surface.next_index();
        const double target = static_cast<double>(k) * surface.spacing_rad();
        const double t = k == 0 ? 0.0 : time_of_angle(r, target, t_lo, t_end);
        t_lo = t;
        ContactInput& in = contact_input_;
        ContactOutput out;
        // New surface = the surface one revolution ago (as the contact saw it) + this pass's
        // removal; without a contact arc that is exactly sample k - n (no interpolated read).
        if (rotor.arc_rad > 0.0) evaluate_contact(t, state_at(t), in, out);
        else evaluate_contact(t, state_at(t), in, out, true, r, surface.value(k - n));
        surface.push(in.previous_surface_m[r] + out.removed_m[r]);
      }
    }
  }

  bool record_sample(double t) {
    std::span<const double> x = state_at(t);
    ContactInput& in = contact_input_;
    ContactOutput out;
    evaluate_contact(t, x, in, out);
    const double displacement = model_.displacement_m(x);
    const bool contact = !settings_.one_sided_contact || out.penetration_m > 0.0;
    const double values[] = {displacement, out.normal_force_n, out.depth_of_cut_m,
                             in.speed_rpm[0], in.speed_rpm[1], in.previous_surface_m[0],
                             in.previous_surface_m[1]};
    for (double v : values)
      if (!std::isfinite(v)) return false;
    if (settings_.on_sample) {
      OutputSample sample;
      sample.t_s = t;
      sample.displacement_m = displacement;
      sample.force_n = out.normal_force_n;
      sample.depth_of_cut_m = out.depth_of_cut_m;
      sample.infeed_m = in.infeed_m;
      for (std::size_t r = 0; r < rotor_count; ++r) {
        sample.speed_rpm[r] = in.speed_rpm[r];
        sample.surface_at_contact_m[r] = in.previous_surface_m[r];
      }
      sample.in_contact = contact;
      settings_.on_sample(sample);
    }
    if (!settings_.store_samples) return true;
    result_.t_s.push_back(t);
    result_.displacement_m.push_back(displacement);
    result_.force_n.push_back(out.normal_force_n);
    result_.depth_of_cut_m.push_back(out.depth_of_cut_m);
    result_.infeed_m.push_back(in.infeed_m);
    for (std::size_t r = 0; r < rotor_count; ++r) {
      result_.speed_rpm[r].push_back(in.speed_rpm[r]);
      result_.surface_at_contact_m[r].push_back(in.previous_surface_m[r]);
    }
    result_.in_contact.push_back(contact ? 1.0 : 0.0);
    return true;
  }

  void take_snapshot(double t) {
    SurfaceSnapshot snap;
    snap.t_s = t;
    std::size_t grid = 0;
    for (const RotorState& rotor : rotors_)
      if (rotor.surface) grid = std::max(grid, rotor.surface->samples_per_rev());
    grid = std::clamp<std::size_t>(grid, 360, 1 << 16);
    for (std::size_t i = 0; i < grid; ++i) snap.angle_deg.push_back(360.0 * static_cast<double>(i) / static_cast<double>(grid));
    for (std::size_t r = 0; r < rotor_count; ++r) {
      const RotorState& rotor = rotors_[r];
      snap.surface_m[r].assign(grid, 0.0);
      if (!rotor.surface) continue;
      // Body-angle profile of the last revolution, resampled (periodic linear) onto the grid.
      std::vector<double> profile = rotor.surface->last_revolution();
      const double m = static_cast<double>(profile.size());
      for (std::size_t i = 0; i < grid; ++i) {
        double pos = m * static_cast<double>(i) / static_cast<double>(grid);
        auto j = static_cast<std::size_t>(pos);
        double u = pos - static_cast<double>(j);
        snap.surface_m[r][i] = (1 - u) * profile[j % profile.size()] + u * profile[(j + 1) % profile.size()];
      }
    }
    result_.snapshots.push_back(std::move(snap));
  }

  // True if the run must stop: state not finite or displacement beyond the limit.
  bool check_divergence(double t) {
    std::span<const double> x(data(sun_.y), n_);
    bool finite = std::all_of(x.begin(), x.end(), [](double v) { return std::isfinite(v); });
    double displacement = finite ? model_.displacement_m(x) : std::nan("");
    if (finite && std::isfinite(displacement) && std::abs(displacement) <= settings_.divergence_limit_m)
      return false;
    result_.diverged = true;
    std::string state;
    for (std::size_t i = 0; i < n_ && i < 12; ++i) state += fmt::format("{}{:.4g}", i ? ", " : "", x[i]);
    result_.status = finite ? fmt::format("diverged at t = {:.6g} s: |displacement| = {:.4g} m exceeds "
                                          "divergence_limit_m = {:.4g} m (state: {})",
                                          t, std::abs(displacement), settings_.divergence_limit_m, state)
                            : fmt::format("diverged at t = {:.6g} s: state not finite (state: {})", t, state);
    return true;
  }

  void fail(int flag, double t) {
    double h = 0.0, t_current = t;
    sun_.current(h, t_current);
    std::string what = fmt::format("integrator failed at t = {:.6g} s (step size h = {:.3g} s", t_current, h);
    if (Integrator::step_size_collapse(flag)) what += ", step-size collapse";
    if (!nonfinite_rhs_.empty()) what += ", " + nonfinite_rhs_;
    what += fmt::format("; {}{}{})", sun_.flag_name(flag), last_error_.empty() ? "" : ": ", last_error_);
    throw PointFailure(what);
  }

  const TimeDomainModel& model_;
  const SimulationSettings& settings_;
  std::size_t n_;
  std::vector<double> state_scratch_;
  RotorState rotors_[rotor_count];
  double f_max_ = 0.0, max_rpm_ = 0.0;
  Integrator sun_;
  bool stepped_ = false;
  long rhs_evaluations_ = 0;
  // The model input of the hot paths (right-hand side, surface writes, output samples), reused:
  // evaluate_contact sets every field, and a fresh one cost a zero fill of 88 bytes per call.
  ContactInput contact_input_;
  // The last right-hand side (Engine::rhs): its (t, y), f, and whether its surface reads are
  // final (reads_settled).
  bool cache_valid_ = false, cache_settled_ = false;
  double cache_t_ = 0.0;
  std::vector<double> cache_y_, cache_f_;
  std::string last_error_;
  std::string nonfinite_rhs_;  // the first right-hand side that was not finite
  std::vector<std::string> diagnostics_;
  SimulationResult result_;
};

SimulationResult Engine::run() {
  const double t_end = settings_.duration_s;
  sun_.allocate(n_);
  std::span<double> y(data(sun_.y), n_);
  model_.initial_state(settings_.disturbance, y);

  // Absolute tolerances: the relative tolerance times the state scale of a displacement of the
  // disturbance (or the infeed of a wheel revolution, whichever is larger), so that a decaying
  // response stays resolved far below its start.
  double reference = std::max({std::abs(settings_.disturbance.displacement_m),
                               settings_.infeed_rate_m_per_s * 60.0 / max_rpm_,
                               settings_.initial_waviness_m, 1e-12});
  std::span<double> scales(data(sun_.abstol), n_);
  model_.state_scales(reference, scales);
  for (double& s : scales) s = 1e-3 * settings_.relative_tolerance * std::max(s, 1e-300);
  const std::vector<double> tolerance_floor(scales.begin(), scales.end());
  // Absolute tolerances follow the amplitude: each component of an oscillation passes through
  // zero twice a period, where only the absolute tolerance bounds its error weight; a fixed one
  // set for the start is far too strict once the response has decayed or grown by orders of
  // magnitude (the step size then collapses to resolve noise). Every window the tolerance is
  // reset to 0.1 rtol times the component's largest magnitude over the last two windows.
  const double tolerance_window_s = std::max(4.0 / f_max_, 0.02);
  std::vector<double> window_max(n_, 0.0), previous_window_max(n_, 0.0);
  double window_end = tolerance_window_s;
  auto adapt_tolerances = [&](double t_now) {
    std::span<const double> x(data(sun_.y), n_);
    for (std::size_t i = 0; i < n_; ++i) window_max[i] = std::max(window_max[i], std::abs(x[i]));
    if (t_now < window_end) return;
    std::span<double> atol(data(sun_.abstol), n_);
    for (std::size_t i = 0; i < n_; ++i) {
      atol[i] = std::max(tolerance_floor[i],
                         0.1 * settings_.relative_tolerance * std::max(window_max[i], previous_window_max[i]));
      previous_window_max[i] = window_max[i];
      window_max[i] = 0.0;
    }
    window_end = t_now + tolerance_window_s;
  };

  // Largest step: a fraction of the shortest wave (dense output and contact events stay local)
  // and well below a revolution (a read one revolution back must find written surface).
  const double max_step = std::min(1.0 / (settings_.max_steps_per_wave * f_max_), 0.25 * 60.0 / max_rpm_);
  // Error weights 1/(rtol |y_i| + atol_i) from a weight function reading sun_.abstol, so the
  // absolute tolerances can follow the amplitude during the run (adapt_tolerances below).
  sun_.create(settings_.integrator, &Engine::rhs, &Engine::error_weights, &Engine::silent_error, this,
              max_step, t_end);
  if (settings_.one_sided_contact) sun_.root_init(&Engine::root);

  std::vector<double> snapshots = settings_.snapshot_times_s;
  std::sort(snapshots.begin(), snapshots.end());
  std::size_t next_snapshot = 0;
  const auto sample_count = static_cast<std::size_t>(std::floor(t_end * settings_.sample_rate_hz + 1e-9)) + 1;
  std::size_t next_sample = 0;
  // Every output series is reserved once (growing ~12 series by doubling cost copies and page
  // faults comparable to the integration itself).
  for (std::vector<double>* series : {&result_.t_s, &result_.displacement_m, &result_.force_n, &result_.depth_of_cut_m,
                                      &result_.infeed_m, &result_.speed_rpm[0], &result_.speed_rpm[1],
                                      &result_.surface_at_contact_m[0], &result_.surface_at_contact_m[1],
                                      &result_.in_contact})
    if (settings_.store_samples) series->reserve(sample_count);

  // Contact bookkeeping (one-sided): intervals out of contact.
  auto penetration_now = [&](double t, std::span<const double> x) {
    ContactInput in;
    ContactOutput out;
    evaluate_contact(t, x, in, out, false);
    return out.penetration_m;
  };
  bool in_contact = !settings_.one_sided_contact || penetration_now(0.0, y) > 0.0;
  double lost_since = 0.0;

  write_surfaces(0.0, 0.0);
  double t = 0.0;
  bool stop = false;
  while (!stop) {
    // Output samples and snapshots up to t (inclusive), then one step.
    while (next_sample < sample_count &&
           static_cast<double>(next_sample) / settings_.sample_rate_hz <= t) {
      if (!record_sample(static_cast<double>(next_sample) / settings_.sample_rate_hz)) {
        check_divergence(t);
        if (!result_.diverged) {
          result_.diverged = true;
          result_.status = fmt::format("diverged at t = {:.6g} s: outputs not finite", t);
        }
        stop = true;
        break;
      }
      ++next_sample;
    }
    while (next_snapshot < snapshots.size() && snapshots[next_snapshot] <= t) {
      take_snapshot(t);
      ++next_snapshot;
    }
    if (stop || t >= t_end) break;

    double t_new = t;
    int flag = sun_.step(t_end, t_new);
    if (flag < 0) fail(flag, t);
    sun_.record_step(t_new);
    stepped_ = true;
    write_surfaces(t, t_new);
    if (flag == Integrator::root_return) {
      const int direction = sun_.root_direction();
      ++result_.contact_events;
      const bool entering = direction > 0;
      if (in_contact && !entering) lost_since = t_new;
      if (!in_contact && entering) {
        result_.contact_loss_intervals.emplace_back(lost_since, t_new);
        result_.contact_loss_time_s += t_new - lost_since;
      }
      in_contact = entering;
    } else if (settings_.one_sided_contact &&
               (penetration_now(t_new, {data(sun_.y), n_}) > 0.0) != in_contact) {
      // A switch the event function cannot see: starting exactly at zero penetration (no
      // sign change to detect), e.g. the first touch of an infeed from rest.
      if (in_contact) {
        lost_since = t_new;
      } else {
        result_.contact_loss_intervals.emplace_back(lost_since, t_new);
        result_.contact_loss_time_s += t_new - lost_since;
      }
      in_contact = !in_contact;
    }
    // Samples inside this step come from the dense output before a restart discards it.
    while (next_sample < sample_count &&
           static_cast<double>(next_sample) / settings_.sample_rate_hz <= t_new) {
      if (!record_sample(static_cast<double>(next_sample) / settings_.sample_rate_hz)) break;
      ++next_sample;
    }
    t = t_new;
    if (check_divergence(t)) break;
    adapt_tolerances(t);
    if (flag == Integrator::root_return) {
      // The force law has a kink at the contact switch: restart the multistep method there.
      sun_.restart(t);
      stepped_ = false;
    }
  }
  if (!in_contact) {
    result_.contact_loss_intervals.emplace_back(lost_since, t);
    result_.contact_loss_time_s += t - lost_since;
  }
  result_.end_time_s = t;
  if (!result_.diverged) result_.status = "completed";
  std::copy(y.begin(), y.end(), result_.end_state.begin());
  result_.steps = sun_.steps();
  result_.rhs_evaluations = rhs_evaluations_;
  result_.diagnostics = diagnostics_;
  for (std::string& d : model_.diagnostics()) result_.diagnostics.push_back(std::move(d));
  return std::move(result_);
}

}  // namespace

SimulationResult simulate(const TimeDomainModel& model, const SimulationSettings& settings) {
  Engine engine(model, settings);
  return engine.run();
}

}  // namespace chatterlab
