// Names of the model choices, the number format of messages and the cross-parameter
// checks of a case (laser_params.h).
#include <sstream>

#include "laser_params.h"

namespace laser {

std::string fmt(double v, int precision) {
  std::ostringstream o;
  o.precision(precision);
  o << v;
  return o.str();
}

const char* to_string(FlowModel m) {
  switch (m) {
    case FlowModel::Conduction: return "conduction";
    case FlowModel::Rising: return "rising";
    case FlowModel::RisingFall: return "risingfall";
    case FlowModel::Boundary: return "boundary";
  }
  return "?";
}
const char* to_string(SolidModel m) {
  switch (m) {
    case SolidModel::Exact: return "exact";
    case SolidModel::Shifted: return "shifted";
    case SolidModel::Stefan: return "stefan";
  }
  return "?";
}
const char* to_string(MeltEnergy m) { return m == MeltEnergy::Advected ? "advected" : "text"; }
const char* to_string(MeltFlow m) { return m == MeltFlow::Conservative ? "conservative" : "text"; }
const char* to_string(CurvatureForm m) { return m == CurvatureForm::Text ? "text" : "conduction"; }

void validate(Config& c) {
  const Material& m = c.mat;
  if (!(m.Tm > m.Ti))
    throw UsageError("--T-initial: must be below --T-melt (" + fmt(m.Tm) + " K), got " + fmt(m.Ti) + " K");
  if (!(m.Tc > m.Tsat0))
    throw UsageError("--T-critical: must be above --T-sat0 (" + fmt(m.Tsat0) + " K), got " + fmt(m.Tc) + " K");
  if (!(m.Tsat0 > m.Tm))
    throw UsageError("--T-melt: must be below --T-sat0 (" + fmt(m.Tsat0) + " K), got " + fmt(m.Tm) + " K");
  if (c.melt_heat == MeltHeat::Flux && c.melt_flow != MeltFlow::Conservative)
    throw UsageError("--melt-heat: flux needs --melt-flow conservative (the face fluxes are the conservative flow's), "
                     "got --melt-flow text");
  if (c.melt_content == MeltContent::Transient && !c.flux_heat())
    throw UsageError("--melt-content: transient needs --melt-heat flux (the layer's content is balanced against the "
                     "face heat fluxes; (4-27) is quasi-steady), got --melt-heat ode");
  if (c.melt_content == MeltContent::Transient && c.model == FlowModel::Conduction)
    throw UsageError("--melt-content: transient needs a melt flow model (the layer's content changes through b2 of "
                     "(4-25), which --model conduction does not have), got --model conduction");
  // the heat Courant sub-steps split the face heat fluxes of the conservative flow: without
  // them (the ODE b2 of (4-25), or no melt flow) the option would change nothing
  if (c.heat_courant > 0.0 && (!c.flux_heat() || c.model == FlowModel::Conduction)) {
    const bool fluxes = c.flux_heat();  // (then the missing part is the melt flow)
    const std::string lacks = !fluxes ? "--melt-heat " + std::string(c.melt_heat == MeltHeat::Ode ? "ode" : "auto with --melt-flow text")
                                      : std::string("--model conduction");
    throw UsageError("--heat-courant: a value in (0, 10] splits the face heat fluxes of " +
                     std::string(!fluxes ? "--melt-heat flux" : "a melt flow") + ", which " + lacks +
                     " does not have (the option would be inert); got --heat-courant " + fmt(c.heat_courant) +
                     " (0 = off is accepted)");
  }
  if (c.dtau > 0.0) c.dt = c.dtau * c.R * c.R / (m.kl / (m.rho * m.cpl));
  if (c.dt > 0.0 && !(c.dt < c.tp))
    throw UsageError(std::string(c.dtau > 0 ? "--dtau" : "--dt") + ": the time step " + fmt(c.dt) +
                     " s must be shorter than the pulse (--pulse " + fmt(c.tp) + " s)");
  if (c.xi_max > 0.0 && c.xi_max < 2.0 * c.dxi)
    throw UsageError("--xi-max: must be 0 (automatic) or at least 2 --dxi = " + fmt(2 * c.dxi) + ", got " +
                     fmt(c.xi_max));
}


}  // namespace laser
