#include "planning/task_space.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flexirob::planning {

TaskMetric::TaskMetric(TaskSpace space, double alpha) : space_(space), alpha_(alpha) {
  if (!(alpha >= 0.0 && alpha < 1.0)) {
    throw std::invalid_argument("task metric: expected 0 <= alpha < 1, got " + std::to_string(alpha));
  }
}

double quaternionAngle(const double* q1, const double* q2) {
  const double dot = q1[0] * q2[0] + q1[1] * q2[1] + q1[2] * q2[2] + q1[3] * q2[3];
  // Eq. 7.6; the clamp guards against rounding just outside [-1, 1].
  return std::acos(std::clamp(2.0 * dot * dot - 1.0, -1.0, 1.0));
}

double TaskMetric::distance(const double* a, const double* b) const {
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  const double d_T = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (space_ == TaskSpace::kPosition) return d_T;
  return (1.0 - alpha_) * d_T + alpha_ * quaternionAngle(a + 3, b + 3);  // Eq. 7.5
}

double TaskMetric::thalesProduct(const double* a, const double* b, const double* x) const {
  if (space_ == TaskSpace::kPosition) {
    return (a[0] - x[0]) * (b[0] - x[0]) + (a[1] - x[1]) * (b[1] - x[1]) + (a[2] - x[2]) * (b[2] - x[2]);
  }
  const double d_xa = distance(x, a);
  const double d_xb = distance(x, b);
  const double d_ab = distance(a, b);
  return 0.5 * (d_xa * d_xa + d_xb * d_xb - d_ab * d_ab);
}

void TaskMetric::midpoint(const double* a, const double* b, double* out) const {
  for (int i = 0; i < 3; ++i) out[i] = a[i] + 0.5 * (b[i] - a[i]);  // Eq. 7.2
  if (space_ == TaskSpace::kPosition) return;
  const double dot = a[3] * b[3] + a[4] * b[4] + a[5] * b[5] + a[6] * b[6];
  const double sign = dot < 0.0 ? -1.0 : 1.0;
  double norm = 0.0;
  for (int i = 3; i < 7; ++i) {
    out[i] = a[i] + sign * b[i];
    norm += out[i] * out[i];
  }
  // With the sign chosen so that <a, b> >= 0 the sum has norm >= sqrt(2): no division by zero.
  norm = std::sqrt(norm);
  for (int i = 3; i < 7; ++i) out[i] /= norm;
}

}  // namespace flexirob::planning
