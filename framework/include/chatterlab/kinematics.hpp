#pragma once
// Base class of kinematics plugins (MODELS.md P4 `three_table_revolution`, K2 `xc_cam`): the map
// between a point of the part's profile (in the part's own plane frame) and the positions of the
// machine's motor-driven axes that put the tool in contact there, and back.
//
// Frames and units: the profile lives in the part frame (x_mm, y_mm): for a solid of revolution
// x is the axial coordinate from the fixture reference plane and y the radius (the generatrix
// y = f(x)); for a cam, the cam's polar plane. Axis positions are in mm of table (or nut) travel;
// a motor turns positions into pulses through MotorAxis::mm_per_pulse, so a plan is
// "integer pulses per motor per segment" and anyone can replay it with inverse()/forward().
#include <span>
#include <string>
#include <vector>

#include "chatterlab/registry.hpp"

namespace chatterlab {

// One point of the target profile with its tangent (any non-zero length, pointing in the
// direction of travel along the profile).
struct CurvePoint {
  double x_mm = 0.0, y_mm = 0.0;
  double tangent_x = 1.0, tangent_y = 0.0;
};

// A stepper-driven axis in plan order (pulses.csv column "<name>_pulses").
struct MotorAxis {
  std::string name;             // "lower", "middle", "upper", ...
  double mm_per_pulse = 0.0;    // table (or nut) travel per pulse
  double max_pulse_rate_hz = 0.0;
  std::string position_name;    // what the position measures ("upper_nut"); empty: `name`
};

// Where on the tool the contact is (wear spreading moves it, MODELS.md P6): its position in the
// machine's tool frame relative to the nominal contact point (along the base rails and across
// them, towards the tool, mm) and the tilt of the tool surface's tangent there (rad, counter-
// clockwise). {0, 0, 0}: the nominal contact (P4). A cylindrical wheel's face: {zeta, 0, 0}; a
// profiled wheel's edge arc of radius r at arc angle phi: {r sin phi, r (1 - cos phi), phi}.
struct ToolContact {
  double along_mm = 0.0, across_mm = 0.0, tilt_rad = 0.0;
};

// The tool as seen from the part at one machine state: a disc of radius `radius_mm` centred on
// (x_mm, y_mm) in the part frame (radius 0: the nominal contact point itself). The profile
// deviation of that state is  (signed distance from the profile to the centre) - radius,
// positive when the tool stands off the nominal profile (material left), negative when it cuts in.
struct ToolInPart {
  double x_mm = 0.0, y_mm = 0.0, radius_mm = 0.0;
};

// Capability of a machine that grinds cams (MODELS.md K2): the part turns on a rotary axis and a
// slide keeps the wheel on the profile's tangent point, so the motors() are exactly two, in this
// order: the rotary axis (positions in degrees, a plan unwraps them) and the slide (mm). The
// cam_plan kind takes any machine that declares it (Kinematics::cam_grinding()), not a name.
class CamGrindingMachine {
 public:
  virtual ~CamGrindingMachine() = default;
  // Radius of the wheel disc (concave parts of a cam narrower than it are gouged).
  virtual double wheel_radius_mm() const = 0;
};

class Kinematics {
 public:
  virtual ~Kinematics() = default;

  // Typed capabilities (a plugin that has one derives from it and returns `this`).
  virtual const CamGrindingMachine* cam_grinding() const { return nullptr; }

  // The motor-driven axes, in the order inverse()/forward() use.
  virtual std::vector<MotorAxis> motors() const = 0;

  // Positions (axis units: mm, or deg for a rotary axis; one per motor) that bring the tool into
  // contact with the profile at `target`, touching at `contact` on the tool. Throws
  // std::domain_error where the machine cannot reach the point (e.g. a tangent at or beyond 90
  // degrees).
  virtual void inverse(const CurvePoint& target, const ToolContact& contact,
                       std::span<double> positions_mm) const = 0;

  // The tool in the part frame for given axis positions (the exact inverse of inverse() for the
  // same contact): replaying a quantised plan through forward() gives the produced profile
  // (MODELS.md P7).
  virtual ToolInPart forward(std::span<const double> positions_mm,
                             const ToolContact& contact) const = 0;
};

}  // namespace chatterlab
