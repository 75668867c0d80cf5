#include "rotorid/model/parameters.h"

#include "rotorid/core/text.h"

namespace rotorid {

Eigen::Matrix<double, kNumBodyParameters, 1> BodyParameters::ToVector() const {
  Eigen::Matrix<double, kNumBodyParameters, 1> chi;
  chi << first_moment, inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2);
  return chi;
}

BodyParameters BodyParameters::FromVector(const Eigen::Ref<const Eigen::VectorXd>& chi) {
  BodyParameters body;
  body.first_moment = chi.head<3>();
  body.inertia << chi[3], chi[6], chi[7],  //
      chi[6], chi[4], chi[8],              //
      chi[7], chi[8], chi[5];
  return body;
}

BodyParameters AddPointMass(const BodyParameters& body, double mass_kg, const Eigen::Vector3d& p_m) {
  BodyParameters out = body;
  out.first_moment += mass_kg * p_m;
  out.inertia += mass_kg * (p_m.squaredNorm() * Eigen::Matrix3d::Identity() - p_m * p_m.transpose());
  return out;
}

bool PositiveByPhysics(const std::string& name) {
  return name == "kt" || name == "kd" || EndsWith(name, ".I_xx") || EndsWith(name, ".I_yy") || EndsWith(name, ".I_zz");
}

}  // namespace rotorid
