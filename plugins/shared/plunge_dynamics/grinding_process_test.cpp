// G4 known answers: the energy balance 2-72..2-75 the stiffnesses come from, the plane-grinding
// limit of the equivalent diameter, the book's 2-78 form, and the filtering condition behind v_c.
#include "shared/plunge_dynamics/grinding_process.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace chatterlab {
namespace {

using namespace grinding_process;

TEST(GrindingProcess, StiffnessesReproduceTheEnergyBalance) {
  // E1 = psi Bw {(u0 + du/2) vw dt + sqrt(2 Rg u0) du} (2-73) equals E2 = Ft (vg + vw) dt (2-74):
  // Ft = ks (u0 + du/2) + kd' du/dt with kd' = psi Bw sqrt(2 Rg u0)/(vg (1 + Kv)) = kd (2-77).
  const double psi = 2e10, width = 0.035, vw = 0.29, vg = 35.0, rg = 0.2, u0 = 5e-6;
  const double du = 1e-7, dt = 1e-4;
  const double de = 2.0 * rg;  // plane grinding
  const double ks = psi * width * removal_speed_factor(speed_ratio(vw, vg));
  const double kd = dynamic_grinding_coefficient_n_s_per_m(ks, de, u0, vw);
  const double energy = psi * width * ((u0 + 0.5 * du) * vw * dt + std::sqrt(2.0 * rg * u0) * du);
  const double force = ks * (u0 + 0.5 * du) + kd * du / dt;
  EXPECT_NEAR(force * (vg + vw) * dt, energy, 1e-12 * energy);
  EXPECT_NEAR(kd, psi * width * std::sqrt(2.0 * rg * u0) / (vg * (1.0 + vw / vg)), 1e-9 * kd);
  EXPECT_NEAR(ks, psi * width * 0.29 / 35.29, 1e-6 * ks);
  // The wear stiffness of the same force over a wheel surface passing vg/vw times faster is
  // kg = G ks vg/vw = G psi Bw/(1 + Kv): the two speed factors differ by exactly Kv.
  EXPECT_NEAR(removal_speed_factor(0.29 / 35.0) / wear_speed_factor(0.29 / 35.0), 0.29 / 35.0, 1e-15);
  EXPECT_NEAR(surface_speed_m_per_s(100.0, 55.0), std::numbers::pi * 0.1 * 55.0 / 60.0, 1e-15);
}

TEST(GrindingProcess, EquivalentDiameterAndBookForm2_78) {
  const double dw = 0.1, dg = 0.4;
  EXPECT_NEAR(equivalent_diameter_m(dw, dg, Contact::external), 0.08, 1e-15);
  EXPECT_NEAR(equivalent_diameter_m(0.4, 0.1, Contact::internal), 0.04 / 0.3, 1e-15);
  // A flat workpiece (dw -> infinity) is plane grinding: de -> dg = 2 Rg.
  EXPECT_NEAR(equivalent_diameter_m(1e9, dg, Contact::external), dg, 1e-9);
  EXPECT_NEAR(equivalent_diameter_m(1e9, dg, Contact::internal), dg, 1e-9);
  // 2-78: kd = ks (1/vw) sqrt(u0 / (1/dg + mu/dw)), mu = +1 external.
  const double ks = 1e7, u0 = 1e-5, vw = 0.3;
  const double kd = dynamic_grinding_coefficient_n_s_per_m(ks, equivalent_diameter_m(dw, dg, Contact::external), u0, vw);
  EXPECT_NEAR(kd, ks / vw * std::sqrt(u0 / (1.0 / dg + 1.0 / dw)), 1e-9 * kd);
  EXPECT_NEAR(contact_length_m(0.08, 1e-5), std::sqrt(8e-7), 1e-15);
  EXPECT_THROW(equivalent_diameter_m(0.1, 0.2, Contact::internal), std::invalid_argument);
  EXPECT_THROW(equivalent_diameter_m(0.0, 0.2, Contact::external), std::invalid_argument);
}

TEST(GrindingProcess, CriticalWorkSpeedIsWhereWaveCurvatureMatchesTheWheel) {
  // The G8 experiment: work 100 mm, wheel 400 mm, chatter 820 Hz with a 1.5 um wave.
  const double f = 820.0, y = 1.5e-6, rw = 0.05, rg = 0.2;
  const double vc = critical_work_speed_m_per_s(f, y, rw, rg);
  const double re = rw * rg / (rw + rg);
  // At vw = v_c the wave y sin(2 pi f x / vw) has peak curvature y (2 pi f/vw)^2 = 1/Re.
  EXPECT_NEAR(y * std::pow(2.0 * std::numbers::pi * f / vc, 2), 1.0 / re, 1e-9 / re);
  // v_c = 1.26 m/s; the G8 work speed (100 mm at 55 rpm: 0.288 m/s) is below it, so the wheel
  // cannot copy a 1.5 um, 820 Hz wave fully: geometric filtering keeps work regeneration weak in
  // plunge grinding (book 2.4.2).
  EXPECT_NEAR(vc, 2.0 * std::numbers::pi * 820.0 * std::sqrt(1.5e-6 * 0.04), 1e-12);
  EXPECT_NEAR(vc, 1.262, 1e-3);
  EXPECT_GT(vc, std::numbers::pi * 0.1 * 55.0 / 60.0);
  // Scaling: v_c ~ f sqrt(y).
  EXPECT_NEAR(critical_work_speed_m_per_s(2 * f, 4 * y, rw, rg), 4.0 * vc, 1e-12);
}

}  // namespace
}  // namespace chatterlab
