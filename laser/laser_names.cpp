// Names of the model choices and the number format of messages (laser_params.h).
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

}  // namespace laser
