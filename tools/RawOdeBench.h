// Raw ODE on the bodies of a RawScene: the baseline of `crumble bench engine --engine ode`
// (the adapter's overhead against its raw library). Written against ODE's public API only,
// as a user of plain ODE would set up the same scene: a dConvex per body (one polygon per
// hull triangle), static planes and a static lid box, a hash space, dCollide with
// `contacts_per_pair` points, contact joints with Coulomb friction (dContactApprox1), soft
// ERP and dWorldQuickStep with the same iterations.
#pragma once
#include "core/RawScene.h"

namespace crumble {

std::unique_ptr<RawWorld> make_raw_ode_world(const RawScene& scene);

}  // namespace crumble
