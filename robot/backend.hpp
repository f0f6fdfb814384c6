#pragma once
// The robot backend interface: one seam for the Bullet simulation, the real LWR IV over FRI and
// the replay of recordings (DESIGN §2, §8 "interfaces at the seams").
//
// The command is the one of FRI's joint impedance mode (thesis App. A.3): a commanded posture
// q_cmd with per-joint stiffness and damping; the robot's inner loop compensates gravity and
// acts like a spring-damper around q_cmd. Everything in SI units, joint space in radians
// (metres for prismatic joints), Cartesian quantities in the base frame W.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "robot/robot_model.hpp"

namespace flexirob::robot {

/// What a backend measures each cycle. Vectors have the robot's dof() entries.
struct RobotState {
  double time = 0.0;            ///< [s] since the backend started
  Eigen::VectorXd q;            ///< measured joint positions
  Eigen::VectorXd qd;           ///< measured joint velocities [rad/s]
  Eigen::VectorXd q_cmd;        ///< the command the inner loop currently tracks
  Eigen::VectorXd tau_ext;      ///< estimated external joint torques [Nm] (FRI estExtJntTrq)
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  ///< tip pose for q
  /// The simulation alone: a link overlaps an obstacle, the table or another link, a posture no
  /// real arm can be in (the simulated links pass through). A real robot, over FRI, reports false.
  bool in_contact = false;
  Eigen::Vector3d p_WT() const { return X_WT.translation(); }

  /// Sizes every vector for `dof` joints (zeros), so that later reads do not allocate.
  void resize(int dof) {
    q.setZero(dof);
    qd.setZero(dof);
    q_cmd.setZero(dof);
    tau_ext.setZero(dof);
  }
};

/// FRI joint impedance command (JNTPOS | JNTSTIFF | JNTDAMP).
struct JointImpedanceCommand {
  Eigen::VectorXd q_cmd;      ///< commanded posture
  Eigen::VectorXd stiffness;  ///< [Nm/rad] per joint
  /// Normalized damping (damping ratio, dimensionless) per joint, as FRI's jntDamping: the
  /// inner loop's damping is 2·damping·sqrt(stiffness·M_jj(q)). Tab. A.1 lists 0.7 and 0.95.
  Eigen::VectorXd damping;

  void resize(int dof) {
    q_cmd.setZero(dof);
    stiffness.setZero(dof);
    damping.setZero(dof);
  }
};

/// Result of handing a command to a backend.
enum class CommandStatus { kAccepted, kRejected };

class RobotBackend {
 public:
  virtual ~RobotBackend() = default;
  virtual const RobotModel& model() const = 0;
  /// Control period [s] (1e-3 for FRI at 1 kHz and for the simulation).
  virtual double cycleTime() const = 0;
  /// Copies the latest measurement into `state` (sized by the caller with resize(dof()):
  /// then no allocation).
  virtual void readState(RobotState& state) const = 0;
  /// Sets the command the inner loop tracks from the next step on. A command with a wrong size,
  /// a non-finite entry, negative stiffness or damping, or a posture outside the hardware
  /// limits is rejected (the previous command stays), as the real robot would refuse it.
  virtual CommandStatus writeCommand(const JointImpedanceCommand& command) = 0;
  /// Advances one control cycle: the simulation integrates cycleTime(); the real robot waits
  /// for its next measurement.
  virtual void step() = 0;
};

}  // namespace flexirob::robot
