// The adaptive SUNDIALS route of the dynamics engine (the reference the fixed-step engine is
// compared against): ARKODE ERKStep (Dormand-Prince 5(4); the structural dynamics are oscillatory,
// not stiff) or CVODE Adams (fixed-point iteration), in one-step mode; after every step the
// regenerated surfaces are written at the angle grid points the contact passed, from the step's
// dense output, and the output samples are taken the same way. One SUNContext + integrator per
// call, so concurrent calls are independent. Every SUNDIALS call's return code is checked: a
// refused call is a PointFailure naming the routine and its flag. docs/dynamics.md explains the
// method and the settings.
#include "dynamics/sundials_engine.hpp"

#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <fmt/format.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "dynamics/engine_core.hpp"

namespace chatterlab::dynamics_detail {

namespace {

thread_local std::string failing_call_for_testing;

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


// Every SUNDIALS call goes through these: a flag < 0 (or a null object from a constructor) is a
// PointFailure naming the package, the routine and the flag, with SUNDIALS' own message when its
// error handler was already installed. The test hook (fail_sundials_call_for_testing) makes the
// named routine report failure, so each checked call site is exercised.
[[noreturn]] void refused(const char* package, const char* routine, const std::string& flag,
                          const std::string& message) {
  throw PointFailure(fmt::format("SUNDIALS {} {} failed: {}{}{}", package, routine, flag,
                                 message.empty() ? "" : ": ", message));
}
bool injected(const char* routine) { return !failing_call_for_testing.empty() && failing_call_for_testing == routine; }

// RAII owner of the SUNDIALS objects and the one integrator of a run: CVODE Adams or ARKODE
// ERKStep (SimulationSettings::integrator), behind the few calls the engine needs.
class Integrator {
 public:
  using Rhs = int (*)(sunrealtype, N_Vector, N_Vector, void*);
  using Root = int (*)(sunrealtype, N_Vector, sunrealtype*, void*);
  using Weights = int (*)(N_Vector, N_Vector, void*);
  using ErrorHandler = void (*)(int, const char*, const char*, char*, void*);

  Integrator() {
    int flag = SUNContext_Create(nullptr, &context_);
    if (injected("SUNContext_Create") && flag == 0) {
      SUNContext_Free(&context_);
      flag = -1;
    }
    if (flag != 0) {
      context_ = nullptr;
      refused("", "SUNContext_Create", fmt::format("flag {}", flag), "");
    }
  }
  ~Integrator() {
    // Release only: a destructor cannot report, and these calls fail only on a null argument.
    if (cvode_) CVodeFree(&cvode_);
    if (erk_) ERKStepFree(&erk_);
    if (solver_) SUNNonlinSolFree(solver_);
    for (N_Vector v : {y, dky, abstol, f_})
      if (v) N_VDestroy(v);
    if (context_) SUNContext_Free(&context_);
  }
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  void allocate(std::size_t n) {
    y = new_vector(n, "N_VNew_Serial");
    // Fused vector operations: the integrators clone y, and a Runge-Kutta stage then costs one
    // linear-combination call instead of one call per term.
    check_generic(N_VEnableFusedOps_Serial(y, SUNTRUE), "N_VEnableFusedOps_Serial");
    fast_serial::install(y);
    dky = new_vector(n, "N_VNew_Serial");
    abstol = new_vector(n, "N_VNew_Serial");
  }

  // Creates the integrator at t = 0 from y. max_step bounds every step; t_end is the stop time.
  void create(TimeIntegrator kind, Rhs rhs, Weights weights, ErrorHandler on_error, void* user,
              double max_step, double t_end) {
    rhs_ = rhs;
    user_ = user;
    if (kind == TimeIntegrator::adams) {
      cvode_ = created(CVodeCreate(CV_ADAMS, context_), "CVodeCreate", [](void* p) { CVodeFree(&p); });
      check(CVodeSetErrHandlerFn(cvode_, on_error, user), "CVodeSetErrHandlerFn");
      check(CVodeInit(cvode_, rhs, 0.0, y), "CVodeInit");
      check(CVodeSetUserData(cvode_, user), "CVodeSetUserData");
      check(CVodeWFtolerances(cvode_, weights), "CVodeWFtolerances");
      solver_ = SUNNonlinSol_FixedPoint(y, 0, context_);
      if (solver_ && injected("SUNNonlinSol_FixedPoint")) {
        SUNNonlinSolFree(solver_);
        solver_ = nullptr;
      }
      if (!solver_) refused("CVODE", "SUNNonlinSol_FixedPoint", "returned no solver", "");
      check(CVodeSetNonlinearSolver(cvode_, solver_), "CVodeSetNonlinearSolver");
      check(CVodeSetMaxStep(cvode_, max_step), "CVodeSetMaxStep");
      check(CVodeSetMaxNumSteps(cvode_, 100000), "CVodeSetMaxNumSteps");
      check(CVodeSetStopTime(cvode_, t_end), "CVodeSetStopTime");
      return;
    }
    f_ = N_VClone(y);
    if (f_ && injected("N_VClone")) {
      N_VDestroy(f_);
      f_ = nullptr;
    }
    if (!f_) refused("", "N_VClone", "returned no vector", "");
    erk_ = created(ERKStepCreate(rhs, 0.0, y, context_), "ERKStepCreate", [](void* p) { ERKStepFree(&p); });
    check(ERKStepSetErrHandlerFn(erk_, on_error, user), "ERKStepSetErrHandlerFn");
    check(ERKStepSetUserData(erk_, user), "ERKStepSetUserData");
    check(ERKStepSetTableNum(erk_, kErkTable), "ERKStepSetTableNum");
    check(ERKStepWFtolerances(erk_, weights), "ERKStepWFtolerances");
    check(ERKStepSetInterpolantDegree(erk_, 3), "ERKStepSetInterpolantDegree");
    check(ERKStepSetMaxStep(erk_, max_step), "ERKStepSetMaxStep");
    check(ERKStepSetMaxNumSteps(erk_, 100000), "ERKStepSetMaxNumSteps");
    check(ERKStepSetStopTime(erk_, t_end), "ERKStepSetStopTime");
    start_interpolant(0.0);
  }
  void root_init(Root g) {
    if (cvode_) check(CVodeRootInit(cvode_, 1, g), "CVodeRootInit");
    else check(ERKStepRootInit(erk_, 1, g), "ERKStepRootInit");
  }
  // One internal step towards t_end; returns the flag (0 step, 1 stop time, 2 root, < 0 failure:
  // the engine reports it with the time and step size).
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
    if (cvode_) check(CVodeGetRootInfo(cvode_, &direction), "CVodeGetRootInfo");
    else check(ERKStepGetRootInfo(erk_, &direction), "ERKStepGetRootInfo");
    return direction;
  }
  // Restart at (t, y) (a kink in the right-hand side: contact switch).
  void restart(double t) {
    restarts_steps_ += steps_since_restart();  // re-initialising zeroes the integrator's count
    if (cvode_) check(CVodeReInit(cvode_, t, y), "CVodeReInit");
    else check(ERKStepReInit(erk_, rhs_, t, y), "ERKStepReInit");
    if (erk_) start_interpolant(t);
  }
  long steps() { return restarts_steps_ + steps_since_restart(); }
  // Step size and time of the integrator (for a failure report: best effort, a refused query
  // leaves NaN rather than hiding the failure being reported).
  void current(double& h, double& t) {
    double step = std::nan(""), time = std::nan("");
    const bool ok = cvode_ ? CVodeGetCurrentStep(cvode_, &step) == CV_SUCCESS &&
                                 CVodeGetCurrentTime(cvode_, &time) == CV_SUCCESS
                           : ERKStepGetCurrentStep(erk_, &step) == ARK_SUCCESS &&
                                 ERKStepGetCurrentTime(erk_, &time) == ARK_SUCCESS;
    h = ok ? step : std::nan("");
    if (ok) t = time;
  }
  // "CVODE CV_TOO_CLOSE" / "ARKODE ARK_ERR_FAILURE"; step-size collapse flags are the same
  // numbers in both packages.
  std::string flag_name(int flag) const { return fmt::format("{} {}", package(), return_flag_name(flag)); }
  static bool step_size_collapse(int flag) {
    static_assert(CV_TOO_CLOSE == ARK_TOO_CLOSE && CV_ERR_FAILURE == ARK_ERR_FAILURE &&
                  CV_CONV_FAILURE == ARK_CONV_FAILURE);
    return flag == CV_TOO_CLOSE || flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE;
  }
  // SUNDIALS' own message for the last refused call (set by the engine's error handler).
  std::string* last_error = nullptr;

  N_Vector y = nullptr, dky = nullptr, abstol = nullptr;

 private:
  const char* package() const { return cvode_ ? "CVODE" : "ARKODE"; }
  std::string return_flag_name(int flag) const {
    char* name = cvode_ ? CVodeGetReturnFlagName(flag) : ERKStepGetReturnFlagName(flag);
    std::string text = name ? name : fmt::format("flag {}", flag);
    free(name);  // both allocate
    return text;
  }
  // An integrator routine's flag (CV_SUCCESS == ARK_SUCCESS == 0).
  void check(int flag, const char* routine) {
    static_assert(CV_SUCCESS == 0 && ARK_SUCCESS == 0 && CV_MEM_FAIL == ARK_MEM_FAIL);
    if (flag >= 0 && injected(routine)) flag = CV_MEM_FAIL;
    if (flag >= 0) return;
    refused(package(), routine, return_flag_name(flag), last_error ? *last_error : "");
  }
  // A vector or context routine's int flag (0 = success).
  static void check_generic(int flag, const char* routine) {
    if (flag == 0 && injected(routine)) flag = -1;
    if (flag != 0) refused("", routine, fmt::format("flag {}", flag), "");
  }
  N_Vector new_vector(std::size_t n, const char* routine) {
    N_Vector v = N_VNew_Serial(static_cast<sunindextype>(n), context_);
    if (v && injected(routine)) {
      N_VDestroy(v);
      v = nullptr;
    }
    if (!v) refused("", routine, "returned no vector", fmt::format("length {}", n));
    return v;
  }
  // An integrator's memory from CVodeCreate / ERKStepCreate, or the failure naming it.
  static void* created(void* memory, const char* routine, void (*release)(void*)) {
    if (memory && injected(routine)) {
      release(memory);
      memory = nullptr;
    }
    if (!memory) refused(routine[0] == 'C' ? "CVODE" : "ARKODE", routine, "returned no integrator", "");
    return memory;
  }
  void set_end(double t) {
    const auto n = static_cast<std::size_t>(NV_LENGTH_S(y));  // inline, as data()
    const double* x = data(y);
    y1_.resize(n);
    copy_state(x, n, y1_.data());
    end_rhs_flag_ = rhs_(t, y, f_, user_);
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
    if (cvode_) check(CVodeGetNumSteps(cvode_, &n), "CVodeGetNumSteps");
    else check(ERKStepGetNumSteps(erk_, &n), "ERKStepGetNumSteps");
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
  int end_rhs_flag_ = 0;  // the right-hand side at the last step end (not finite: < 0)
  long restarts_steps_ = 0;

 public:
  // False when the right-hand side at the last recorded step end was not finite.
  bool end_slope_finite() const { return end_rhs_flag_ == 0; }
};

class SundialsEngine final : public EngineCore {
 public:
  SundialsEngine(const TimeDomainModel& model, const SimulationSettings& settings)
      : EngineCore(model, settings), state_scratch_(n_), cache_y_(n_), cache_f_(n_) {
    sun_.last_error = &last_error_;
  }

  SimulationResult run();

  // CVODE callbacks.
  static int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* self) {
    auto& e = *static_cast<SundialsEngine*>(self);
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
    ++e.result_.rhs_evaluations;
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
    auto& e = *static_cast<SundialsEngine*>(self);
    g[0] = e.penetration(t, {data(y), e.n_});
    return 0;
  }
  static int error_weights(N_Vector y, N_Vector weights, void* self) {
    auto& e = *static_cast<SundialsEngine*>(self);
    const double* x = data(y);
    const double* atol = data(e.sun_.abstol);
    double* w = data(weights);
    for (std::size_t i = 0; i < e.n_; ++i) w[i] = 1.0 / (e.settings_.relative_tolerance * std::abs(x[i]) + atol[i]);
    return 0;
  }
  static void silent_error(int, const char*, const char*, char* message, void* self) {
    static_cast<SundialsEngine*>(self)->last_error_ = message;
  }

 private:
  // State at t inside the last step (dense output), or the initial state before any step.
  std::span<const double> state_at(double t) override {
    if (!stepped_) return {data(sun_.y), n_};
    if (!sun_.dense_output(t)) throw std::logic_error("dense output outside the last step");
    return {data(sun_.dky), n_};
  }
  void before_surface_writes() override {
    if (!cache_settled_) cache_valid_ = false;
  }

  [[noreturn]] void fail(int flag, double t) {
    double h = 0.0, t_current = t;
    sun_.current(h, t_current);
    std::string what = fmt::format("integrator failed at t = {:.6g} s (step size h = {:.3g} s", t_current, h);
    if (Integrator::step_size_collapse(flag)) what += ", step-size collapse";
    if (!nonfinite_rhs_.empty()) what += ", " + nonfinite_rhs_;
    what += fmt::format("; {}{}{})", sun_.flag_name(flag), last_error_.empty() ? "" : ": ", last_error_);
    throw PointFailure(what);
  }

  std::vector<double> state_scratch_;
  Integrator sun_;
  bool stepped_ = false;
  // The last right-hand side (rhs): its (t, y), f, and whether its surface reads are final
  // (reads_settled).
  bool cache_valid_ = false, cache_settled_ = false;
  double cache_t_ = 0.0;
  std::vector<double> cache_y_, cache_f_;
  std::string last_error_;
  std::string nonfinite_rhs_;  // the first right-hand side that was not finite
};

SimulationResult SundialsEngine::run() {
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
  sun_.create(settings_.integrator, &SundialsEngine::rhs, &SundialsEngine::error_weights,
              &SundialsEngine::silent_error, this, max_step, t_end);
  if (settings_.one_sided_contact) sun_.root_init(&SundialsEngine::root);
  result_.method = settings_.integrator == TimeIntegrator::adams
                       ? fmt::format("CVODE Adams (fixed-point iteration), rtol {:.3g}", settings_.relative_tolerance)
                       : fmt::format("ARKODE ERKStep (Dormand-Prince 5(4)), rtol {:.3g}", settings_.relative_tolerance);

  // Contact bookkeeping (one-sided): intervals out of contact.
  in_contact_ = !settings_.one_sided_contact || penetration(0.0, y) > 0.0;

  write_surfaces(0.0, 0.0);
  double t = 0.0;
  for (;;) {
    // Output samples and snapshots up to t (inclusive), then one step.
    if (!record_samples_until(t)) {
      check_divergence(t, y);
      break;
    }
    take_snapshots_until(t);
    if (t >= t_end) break;

    double t_new = t;
    int flag = sun_.step(t_end, t_new);
    if (flag < 0) fail(flag, t);
    sun_.record_step(t_new);
    if (!sun_.end_slope_finite()) fail(ARK_RHSFUNC_FAIL, t_new);
    stepped_ = true;
    write_surfaces(t, t_new);
    if (flag == Integrator::root_return) {
      ++result_.contact_events;
      contact_switch(t_new, sun_.root_direction() > 0);
    } else if (settings_.one_sided_contact && (penetration(t_new, y) > 0.0) != in_contact_) {
      // A switch the event function cannot see: starting exactly at zero penetration (no
      // sign change to detect), e.g. the first touch of an infeed from rest.
      contact_switch(t_new, !in_contact_);
    }
    // Samples inside this step come from the dense output before a restart discards it.
    const bool outputs_finite = record_samples_until(t_new);
    t = t_new;
    if (check_divergence(t, y) || !outputs_finite) break;
    adapt_tolerances(t);
    if (flag == Integrator::root_return) {
      // The force law has a kink at the contact switch: restart the multistep method there.
      sun_.restart(t);
      stepped_ = false;
    }
  }
  result_.steps = sun_.steps();
  return finish(t, y);
}

}  // namespace

SimulationResult simulate_sundials(const TimeDomainModel& model, const SimulationSettings& settings) {
  SundialsEngine engine(model, settings);
  return engine.run();
}

void fail_sundials_call_for_testing(std::string routine) { failing_call_for_testing = std::move(routine); }

}  // namespace chatterlab::dynamics_detail
