#pragma once
// The linear delay system of a model written once (chatterlab/linearised_model.hpp) as matrices:
// shared by its characteristic function and the Floquet route (where the delays vary).
#include <Eigen/Core>
#include <vector>

#include "chatterlab/delay_system.hpp"
#include "chatterlab/linearised_model.hpp"

namespace chatterlab {

// Variables x (n), then S_r; A0 and one delayed matrix per regenerated rotor, in layout order.
void surface_system_matrices(const SurfaceLayout& layout, const JacobianMatrix& jacobian, Eigen::MatrixXd& a0,
                             std::vector<Eigen::MatrixXd>& delayed);

// The system at `point` with the delays of constant speeds (one revolution of each rotor).
LinearDelaySystem surface_linear_system(const LinearisedModel& model, const ProcessPoint& point = {});

}  // namespace chatterlab
