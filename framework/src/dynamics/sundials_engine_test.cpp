// Every SUNDIALS call of the reference route is checked (issue 16, item 9): when any set-up call
// is refused, simulate() throws a PointFailure naming the package, the routine and the flag (a
// grid point then records it and the run goes on), never a crash or a silently wrong run. The
// refusals are injected one routine at a time (fail_sundials_call_for_testing).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "chatterlab/dynamics.hpp"
#include "chatterlab/errors.hpp"
#include "chatterlab/runner.hpp"
#include "chatterlab/study.hpp"
#include "dynamics/sundials_engine.hpp"
#include "models/plunge_regenerative/plunge_time_domain.hpp"
#include "unit/g1_test_machines.hpp"

namespace chatterlab {
namespace {

// Refuses one routine for the lifetime of the object.
class FailingCall {
 public:
  explicit FailingCall(std::string routine) { dynamics_detail::fail_sundials_call_for_testing(std::move(routine)); }
  ~FailingCall() { dynamics_detail::fail_sundials_call_for_testing(""); }
  FailingCall(const FailingCall&) = delete;
  FailingCall& operator=(const FailingCall&) = delete;
};

PlungeTimeDomain model() { return PlungeTimeDomain(reference_g1_case()); }

SimulationSettings settings(TimeIntegrator integrator) {
  SimulationSettings s;
  s.integrator = integrator;
  s.duration_s = 0.05;
  s.sample_rate_hz = 5000.0;
  s.infeed_rate_m_per_s = 1e-5;  // one-sided contact with a switch: the root and restart calls run
  s.disturbance = {1e-6, 0.0};
  return s;
}

void expect_refusal_named(TimeIntegrator integrator, const std::string& routine, const std::string& package) {
  SCOPED_TRACE(routine);
  FailingCall failing(routine);
  try {
    simulate(model(), settings(integrator));
    FAIL() << "no failure reported for " << routine;
  } catch (const PointFailure& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("SUNDIALS " + package), std::string::npos) << what;
    EXPECT_NE(what.find(routine + " failed"), std::string::npos) << what;
  }
}

TEST(SundialsChecks, EveryRefusedArkodeCallIsAPointFailureNamingIt) {
  // The run without injection works and switches contact (so the root and restart calls ran).
  const SimulationResult ok = simulate(model(), settings(TimeIntegrator::explicit_runge_kutta));
  ASSERT_EQ(ok.status, "completed");
  ASSERT_GT(ok.contact_events, 0);
  for (const char* routine : {"SUNContext_Create", "N_VNew_Serial", "N_VEnableFusedOps_Serial", "N_VClone"})
    expect_refusal_named(TimeIntegrator::explicit_runge_kutta, routine, "");
  for (const char* routine : {"ERKStepCreate", "ERKStepSetErrHandlerFn", "ERKStepSetUserData", "ERKStepSetTableNum",
                              "ERKStepWFtolerances", "ERKStepSetInterpolantDegree", "ERKStepSetMaxStep",
                              "ERKStepSetMaxNumSteps", "ERKStepSetStopTime", "ERKStepRootInit",
                              "ERKStepGetRootInfo", "ERKStepReInit", "ERKStepGetNumSteps"})
    expect_refusal_named(TimeIntegrator::explicit_runge_kutta, routine, "ARKODE");
}

TEST(SundialsChecks, EveryRefusedCvodeCallIsAPointFailureNamingIt) {
  const SimulationResult ok = simulate(model(), settings(TimeIntegrator::adams));
  ASSERT_EQ(ok.status, "completed");
  ASSERT_GT(ok.contact_events, 0);
  for (const char* routine : {"CVodeCreate", "CVodeSetErrHandlerFn", "CVodeInit", "CVodeSetUserData",
                              "CVodeWFtolerances", "SUNNonlinSol_FixedPoint", "CVodeSetNonlinearSolver",
                              "CVodeSetMaxStep", "CVodeSetMaxNumSteps", "CVodeSetStopTime", "CVodeRootInit",
                              "CVodeGetRootInfo", "CVodeReInit", "CVodeGetNumSteps"})
    expect_refusal_named(TimeIntegrator::adams, routine, "CVODE");
}

// The message carries the flag's name (the injected refusal reports ARK_MEM_FAIL).
TEST(SundialsChecks, TheFlagNameIsReported) {
  FailingCall failing("ERKStepSetMaxStep");
  try {
    simulate(model(), settings(TimeIntegrator::explicit_runge_kutta));
    FAIL();
  } catch (const PointFailure& e) {
    EXPECT_NE(std::string(e.what()).find("SUNDIALS ARKODE ERKStepSetMaxStep failed: ARK_MEM_FAIL"), std::string::npos)
        << e.what();
  }
  // The hook is off again: the run completes.
  dynamics_detail::fail_sundials_call_for_testing("");
  EXPECT_EQ(simulate(model(), settings(TimeIntegrator::explicit_runge_kutta)).status, "completed");
}

// Through a study: a grid over the integrator, the reference route's set-up refused. That point
// is recorded as failed with the routine in its status, the fixed-step point completes, the run
// goes on (exit code 1: a point failed). One thread: the hook is per thread.
TEST(SundialsChecks, ARefusedSetUpIsARecordedPointFailureOfAStudy) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "chatterlab_sundials_checks";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "study.toml") << "[study]\nkind = \"simulate\"\n"
                                     << testing::model_table_toml("plunge_regenerative", testing::g1_reference_machine)
                                     << R"([simulation]
duration_s = 0.05
sample_rate_hz = 5000
[grid]
"simulation.integrator" = ["fixed_step", "explicit_runge_kutta"]
)";
  const Study study = load_study(dir / "study.toml");
  RunOptions options;
  options.out_dir = dir / "out";
  options.threads = 1;
  options.progress = false;
  options.plots = false;
  FailingCall failing("ERKStepSetStopTime");
  const RunSummary summary = run_study(study, options);
  EXPECT_EQ(summary.points, 2u);
  EXPECT_EQ(summary.failed, 1u);
  EXPECT_EQ(summary.exit_code(), 1);
  std::ifstream in(dir / "out" / "results.csv");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("SUNDIALS ARKODE ERKStepSetStopTime failed: ARK_MEM_FAIL"), std::string::npos) << text;
  EXPECT_NE(text.find(",ok"), std::string::npos) << text;
}

}  // namespace
}  // namespace chatterlab
