#pragma once

// The two sides of the IDIM for one flight, per row sample and wrench component (the paper's
// Fig. 3/4): with W the rows of the flight (columns [kt kd chi(9) m]) and chi_t its parameters,
//   rotor model   D_k chi_k        = -W[:, 0:2]  chi_t[0:2]
//   rigid body    m D_m + D chi    =  W[:, 2:12] chi_t[2:12]   (Newton-Euler wrench)
//   error         rigid - rotor    =  W chi_t = rho
// Rows come from BuildIdimMatrixWithEffects, so a refined parameter set is drawn with its effects.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"

namespace rotorid {

struct WrenchSplit {
  Eigen::VectorXd t_s;          // time of each row sample (s)
  Eigen::MatrixXd rigid_body;   // rows x 6 (Fx Fy Fz in N, Mx My Mz in N m)
  Eigen::MatrixXd rotor_model;  // rows x 6
  Eigen::MatrixXd error;        // rows x 6, rigid_body - rotor_model
  // Table III on this flight: ||rho_j|| / ||W_k chi_k (j)|| in %, nullopt where undefined.
  std::vector<std::optional<double>> relative_error_pct;
};

// Throws rotorid::Error when the flight's configuration has parameters missing from `parameters`.
WrenchSplit ComputeWrenchSplit(const ProcessedFlight& flight, const std::map<std::string, double>& parameters,
                               const Effects& effects);

}  // namespace rotorid
