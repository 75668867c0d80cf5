#include "rotorid/report/wrench_split.h"

#include "rotorid/core/error.h"
#include "rotorid/ident/identify.h"
#include "rotorid/ident/tls.h"
#include "rotorid/refine/effect_model.h"

namespace rotorid {

WrenchSplit ComputeWrenchSplit(const ProcessedFlight& flight, const std::map<std::string, double>& parameters,
                               const Effects& effects) {
  const Eigen::VectorXd chi_t = FlightChiT(flight, parameters);
  // Without effects the plain rows are the ones the linear identification used.
  const Eigen::MatrixXd w =
      effects.AllZero() ? BuildIdimMatrix(flight) : BuildIdimMatrixWithEffects(flight, effects);
  const int rows = flight.num_rows_samples();
  if (w.rows() != 6 * rows || w.cols() != chi_t.size())
    throw Error(flight.source + ": IDIM rows do not match the flight (" + std::to_string(w.rows()) + " rows for " +
                std::to_string(rows) + " samples)");
  WrenchSplit split;
  split.t_s.resize(rows);
  split.rigid_body.resize(rows, 6);
  split.rotor_model.resize(rows, 6);
  const Eigen::Index body_columns = chi_t.size() - 2;
  for (int r = 0; r < rows; ++r) {
    split.t_s[r] = flight.t_s[flight.row_samples[r]];
    const auto block = w.middleRows<6>(6 * r);
    split.rotor_model.row(r) = -(block.leftCols<2>() * chi_t.head<2>()).transpose();
    split.rigid_body.row(r) = (block.rightCols(body_columns) * chi_t.tail(body_columns)).transpose();
  }
  split.error = split.rigid_body - split.rotor_model;
  split.relative_error_pct = RelativeErrorPct(w, chi_t);
  return split;
}

}  // namespace rotorid
