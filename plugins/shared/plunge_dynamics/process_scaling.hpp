#pragma once
// How the G1 parameters follow the grinding process conditions (the ProcessConditionsModel
// capability of the plunge models, chatterlab/process_conditions.hpp; docs/feed_risk.md, table
// "Process model"). The model's own kc, kg, kw hold at `reference`; at `conditions`:
//
//   kc = kc_ref b/b_ref                                     (Hertz-type contact ~ width)
//   kw = kw_ref (b/b_ref) [Kv/(1+Kv)] / [Kv_ref/(1+Kv_ref)]  (G4: ks = psi B_w Kv/(1+Kv))
//   kg = kg_ref (b/b_ref) (1+Kv_ref)/(1+Kv)                 (kg = G ks v_s/v_w, grinding ratio G)
//   kc, kg times 1 - eps/2 (da/a)                           (S1, eq 5-29: eps = thickness exponent)
//
// with Kv = v_w/v_s (work over wheel surface speed) and da/a = depth_of_cut_ratio (conditions over
// reference) - 1; the speeds are replaced by the conditions' and the structural modes stay. A
// condition of 0 in both reference and conditions is "not given": the factor that needs it is 1.
// The speed factors need both speeds, the work radius and the wheel diameter, and are 1 when
// ProcessScaling::speed_dependent_stiffness is false (width only).
#include "chatterlab/process_conditions.hpp"
#include "shared/plunge_dynamics/plunge_parameters.hpp"

namespace chatterlab::plunge_dynamics {

// The factors of the table above from `reference` to `conditions`, whose speeds are both given:
// width b/b_ref, removal [Kv/(1+Kv)]/[Kv_ref/(1+Kv_ref)], wear (1+Kv_ref)/(1+Kv) and thickness
// 1 - eps/2 (da/a); 1 where a condition they need is not given (or the scaling switches them off).
// Any model whose process stiffnesses follow G4's and S1's laws uses them (G1, G4, G5).
struct ProcessFactors {
  double width = 1.0, removal = 1.0, wear = 1.0, thickness = 1.0;
};
ProcessFactors process_factors(const ProcessConditions& reference, const ProcessConditions& conditions,
                               const ProcessScaling& scaling);

// The speeds the parameters describe (the rest "not given").
ProcessConditions nominal_conditions(const PlungeRegenerativeParameters& parameters);

// `own` (holding at `reference`) moved to `conditions`. The operations are those of the feed_risk
// process model, in the same order, so a study switched to this capability gives the same numbers.
PlungeRegenerativeParameters parameters_at(const PlungeRegenerativeParameters& own,
                                           const ProcessConditions& reference,
                                           const ProcessConditions& conditions,
                                           const ProcessScaling& scaling);

// The factor by which G4's penetration-rate coefficient kd = ks sqrt(de u0)/vw (2-77/2-78)
// changes from `reference` to `conditions` for a model with these G1 parameters: kd follows the
// removal stiffness ks = kw of parameters_at, the contact length sqrt(de u0) (de from the work
// radius and the wheel diameter when both are given, u0 from the depth-of-cut ratio) and falls
// with the work surface speed v_w = pi 2 r n_w/60 (n_w alone when no radius is given: the radius
// is then the same at both). kd's 1/v_w is the penetration-rate law itself, not the Kv stiffness
// law, so it applies whatever ProcessScaling::speed_dependent_stiffness says.
double penetration_damping_factor(const PlungeRegenerativeParameters& own,
                                  const ProcessConditions& reference,
                                  const ProcessConditions& conditions,
                                  const ProcessScaling& scaling);

}  // namespace chatterlab::plunge_dynamics
