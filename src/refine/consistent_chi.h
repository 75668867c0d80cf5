#pragma once

// The refinement's chi block, physically consistent by construction (MODEL.md 10, issue 37): each
// configuration's body (its first moment and inertia, the known mass held) moves on a chart of the
// log-Cholesky parameterisation of its pseudo-inertia (Rucker and Wensing 2022;
// rotorid/model/physical_consistency.h), the parameters the essential selection holds at 0 stay
// there, and the other coordinates (kt, kd) are Euclidean. Internal; tests check its Jacobians.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "rotorid/ident/tls.h"
#include "rotorid/model/physical_consistency.h"

namespace rotorid::internal {

// One body on its chart: the chi coordinates of its nine parameters (ToVector's order).
struct ChartedBody {
  std::string name;  // "A", or "A.flight1" for a configuration with per-flight first moments
  ConsistentBodyChart chart;
  std::array<int, kNumBodyParameters> columns;
};

// The charts of a solution's bodies: per configuration, the body of its first flight's first moment,
// with the parameters `fixed` (chi coordinates held at 0) held at `chi`'s values. A configuration with
// several first moments charts the first one only (they share one inertia, and a product of charts is
// no chart of that set): its other first moments stay Euclidean, and the check judges them. A body with
// a diagonal inertia held at 0 (the paper's method discards without profiling) has no chart; `notes`
// says which were left out and why.
std::vector<ChartedBody> ChartBodies(const IdimLayout& layout, const std::map<std::string, double>& mass_kg,
                                     const std::vector<int>& fixed, const Eigen::VectorXd& chi,
                                     std::vector<std::string>* notes);

// The chi block (in units of chi_scale) as a manifold: ambient = every chi coordinate; tangent = the
// free Euclidean coordinates, then each charted body's chart coordinates; the `fixed` coordinates
// outside the bodies have no tangent (as ceres::SubsetManifold). Plus(x, delta) maps x's bodies to
// their chart coordinates, adds delta and maps back: every point it reaches is a body.
class ConsistentChiManifold : public ceres::Manifold {
 public:
  ConsistentChiManifold(int ambient_size, const std::vector<int>& fixed, std::vector<ChartedBody> bodies,
                        Eigen::VectorXd chi_scale);

  int AmbientSize() const override { return ambient_size_; }
  int TangentSize() const override { return tangent_size_; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;

 private:
  // Body b's chart coordinates at x; false when it is not a body.
  bool BodyCoordinates(size_t b, const double* x, Eigen::VectorXd* coordinates) const;
  // d (body b's nine scaled chi coordinates) / d (its chart coordinates) at x.
  bool BodyJacobian(size_t b, const double* x, Eigen::MatrixXd* jacobian) const;

  int ambient_size_ = 0, tangent_size_ = 0;
  std::vector<int> euclidean_;  // ambient coordinates with a tangent of their own, in tangent order
  std::vector<ChartedBody> bodies_;
  std::vector<int> body_offset_;  // first tangent coordinate of each body
  Eigen::VectorXd chi_scale_;
};

// The start of a constrained refinement: `chi` with every charted body that is no body (an
// unconstrained TLS estimate) replaced by the nearest body on its chart in the TLS estimate's metric
// (its covariance over the body's estimated parameters; ProjectOntoConsistentBodies). Returns the
// largest distance moved, in std, and names the moved bodies in `moved` ("A 12.3 std").
double ProjectStartOntoCharts(const std::vector<ChartedBody>& bodies, const TlsSolution& tls, Eigen::VectorXd* chi,
                              std::vector<std::string>* moved);

}  // namespace rotorid::internal
