#pragma once
// Task-space coordinates of the ITM and their metric (thesis Sect. 7.2, Eq. 7.5-7.6).
//
// A task-space point is stored as a flat vector:
//   position task space (M = 3): [x, y, z]                      (m, robot base frame)
//   pose task space     (M = 6): [x, y, z, qw, qx, qy, qz]      (m; unit quaternion)
// The pose variant has seven stored numbers for six degrees of freedom.
#include <Eigen/Core>

namespace flexirob::planning {

enum class TaskSpace { kPosition, kPose };

/// Stored numbers per task-space point: 3 (position) or 7 (position + quaternion w,x,y,z).
constexpr int storedSize(TaskSpace space) { return space == TaskSpace::kPosition ? 3 : 7; }

/// The task-space metric D_xi. Position: Euclidean distance D_T [m]. Pose:
/// D = (1 - alpha) D_T + alpha D_O with D_O = acos(2 <q1,q2>^2 - 1) [rad]  (Eq. 7.5, Eq. 7.6).
class TaskMetric {
 public:
  /// alpha in [0, 1) weights the rotational part (thesis: 0.1).
  TaskMetric(TaskSpace space, double alpha);

  TaskSpace space() const { return space_; }
  int size() const { return storedSize(space_); }
  double alpha() const { return alpha_; }

  /// D_xi(a, b); a and b point to size() numbers each.
  double distance(const double* a, const double* b) const;

  /// Lower bound of D_xi per metre of translational distance: D >= translationFactor() * D_T.
  /// Lets a spatial index over positions answer metric queries exactly.
  double translationFactor() const { return space_ == TaskSpace::kPosition ? 1.0 : 1.0 - alpha_; }

  /// True when x lies strictly outside the Thales sphere over a and b, i.e. the angle a-x-b is
  /// acute: (a - x) . (b - x) > 0 (Alg. 7.1 step 4). For poses the inner product is taken from
  /// the metric by the law of cosines, 2<a-x, b-x> = D(x,a)^2 + D(x,b)^2 - D(a,b)^2, which is the
  /// dot product exactly in the Euclidean case.
  double thalesProduct(const double* a, const double* b, const double* x) const;

  /// The bootstrapping sample between a and b (Eq. 7.2): the midpoint of the positions and, for
  /// poses, the rotation halfway between the orientations (normalized quaternion sum after
  /// choosing the nearer sign, equal to slerp at 1/2). Writes size() numbers to out.
  void midpoint(const double* a, const double* b, double* out) const;

 private:
  TaskSpace space_;
  double alpha_;
};

/// Rotation angle between two unit quaternions [w,x,y,z] (Eq. 7.6), in [0, pi].
double quaternionAngle(const double* q1, const double* q2);

}  // namespace flexirob::planning
