// Tests of the {{name}} machine: the library is loaded exactly as `chatterlab` loads it (by path,
// argument 1), then held to the conformance suite and to the geometry of a disc touching a line.
#include <chatterlab/kinematics.hpp>
#include <chatterlab/plugin_api.hpp>
#include <chatterlab/plugin_test.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  // Loads the library (argument 1) as chatterlab does and runs the conformance suite first.
  return chatterlab::plugin_test_main(argc, argv, [](chatterlab::PluginChecks& check) {

    const auto machine = chatterlab::kinematics_registry().at("{{name}}").create(chatterlab::ParamValues(
        {{"wheel_radius_mm", 200.0}, {"screw_pitch_mm", 5.0}, {"steps_per_turn", 200.0}, {"max_pulse_rate_hz", 2000.0}}));
    std::vector<double> axes(2);
    // A cylinder of radius 20 mm: the wheel centre 200 mm above the surface point.
    machine->inverse({30.0, 20.0, 1.0, 0.0}, {}, axes);
    check(std::abs(axes[0] - 30.0) < 1e-12 && std::abs(axes[1] - 220.0) < 1e-12, "cylinder: centre above the point");
    // A 45 degree taper (radius growing along x): the centre along the normal (-1, 1)/sqrt 2.
    machine->inverse({30.0, 20.0, 1.0, 1.0}, {}, axes);
    const double d = 200.0 / std::sqrt(2.0);
    check(std::abs(axes[0] - (30.0 - d)) < 1e-9 && std::abs(axes[1] - (20.0 + d)) < 1e-9, "taper: centre along the normal");
    // forward() is the exact inverse: the disc touches the profile point (distance = radius).
    const chatterlab::ToolContact shifted{3.0, 0.5, 0.0};
    machine->inverse({30.0, 20.0, 1.0, 1.0}, shifted, axes);
    const chatterlab::ToolInPart tool = machine->forward(axes, shifted);
    check(std::abs(std::hypot(tool.x_mm - 30.0, tool.y_mm - 20.0) - tool.radius_mm) < 1e-9,
          "forward(inverse(p)) touches p");
    check(machine->motors().at(0).mm_per_pulse == 5.0 / 200.0, "travel per pulse = pitch / steps");
    bool refused = false;
    try {
      machine->inverse({30.0, 20.0, 0.0, 1.0}, {}, axes);
    } catch (const std::domain_error&) {
      refused = true;
    }
    check(refused, "a shoulder (tangent across the axis) is out of reach");
  });
}
