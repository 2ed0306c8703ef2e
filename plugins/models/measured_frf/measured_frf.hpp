#pragma once
// Model `measured_frf`: MODELS.md G1 (eq 2-16, wheel and work regeneration) with the machine
// compliance at the wheel-work contact taken from a measured FRF (a tap test: CSV or UFF dataset
// 58, chatterlab/frf.hpp) instead of typed-in modes. Two routes (machine_compliance):
//   fitted_modes  the FRF's modes (chatterlab/modal_fit.hpp) go into plunge_regenerative, reached
//                 through the model registry: roots with certificates, simulation, closed forms,
//                 and also the Nyquist count of the fitted H;
//   measured      H(j w) is the measurement itself (natural spline between lines): only the
//                 Nyquist count on the imaginary axis (chatterlab/nyquist.hpp), no fit involved.
// The process stiffnesses may scale with the grinding width (all three are proportional to the
// engaged width), which makes the width a parameter of a lobe diagram.
// docs/models/measured_frf.md is the user documentation.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chatterlab/frf.hpp"
#include "chatterlab/modal_fit.hpp"
#include "chatterlab/model.hpp"
#include "chatterlab/param_table.hpp"
#include "chatterlab/registry.hpp"
#include "models/measured_frf/g1_return_difference.hpp"

namespace chatterlab {

enum class MachineCompliance { fitted_modes, measured };

struct MeasuredFrfParameters {
  std::optional<std::string> frf_file;
  int frf_dataset = 0;
  std::optional<std::vector<double>> frf_frequency_hz, frf_real_m_per_n, frf_imag_m_per_n;
  MachineCompliance machine_compliance = MachineCompliance::fitted_modes;
  ModalFitSettings fit;
  double wheel_speed_rpm = 0.0;
  double work_speed_rpm = 0.0;
  double contact_stiffness_n_per_m = 0.0;
  double wheel_wear_stiffness_n_per_m = 0.0;
  double work_removal_stiffness_n_per_m = 0.0;
  bool wheel_regeneration = true;
  bool work_regeneration = true;
  std::optional<double> grinding_width_mm, reference_width_mm;
};

const ParamTable<MeasuredFrfParameters>& measured_frf_table();

// The measurement and (for fitted_modes) its fit, shared by every model built from the same FRF
// and fit settings in a process: a lobe diagram builds thousands of models.
struct MeasuredMachineData {
  MeasuredFrf frf;
  std::optional<ModalFit> fit;
};

class MeasuredFrfModel final : public Model, public MeasuredMachine {
 public:
  explicit MeasuredFrfModel(const ParamValues& values);
  static PluginInfo info();

  std::unique_ptr<CharacteristicFunction> characteristic() const override;
  std::unique_ptr<ReturnDifference> return_difference() const override;
  std::optional<double> wheel_period_s() const override;
  std::unique_ptr<TimeDomainModel> time_domain() const override;
  std::optional<StiffnessChain> stiffness_chain() const override;
  const MeasuredMachine* measured_machine() const override { return this; }

  const MeasuredFrf& measured_frf() const override { return machine_->frf; }
  const ModalFit* modal_fit() const override { return machine_->fit ? &*machine_->fit : nullptr; }
  const G1Process& process() const { return process_; }

 private:
  MeasuredFrfParameters parameters_;
  std::shared_ptr<const MeasuredMachineData> machine_;
  G1Process process_;
  std::unique_ptr<Model> fitted_g1_;  // plunge_regenerative with the fitted modes (fitted_modes)
};

}  // namespace chatterlab
