#pragma once
// Orocos KDL as a peer of the benchmarks (optional: built only when liborocos-kdl-dev is
// present, FLEXIROB_HAVE_KDL). The KDL chain is built from our parsed RobotModel, so KDL and
// our kinematics see the same joint frames, axes and tip from the same URDF.
#include <kdl/chain.hpp>
#include <kdl/frames.hpp>
#include <kdl/jntarray.hpp>

#include <Eigen/Geometry>

#include "robot/robot_model.hpp"

namespace flexirob::bench::peers {

KDL::Frame toKdl(const Eigen::Isometry3d& X);
Eigen::Isometry3d fromKdl(const KDL::Frame& frame);
KDL::JntArray toKdl(const Eigen::VectorXd& q);
Eigen::VectorXd fromKdl(const KDL::JntArray& q);

/// One KDL segment per joint of the model (the joint placed at X_PJ in the parent body, its
/// axis turned into the parent frame, as kdl_parser does for a URDF joint) and a fixed segment
/// for the tip offset. The chain's end frame equals robot::tipPose(model, q) for every q.
KDL::Chain kdlChainFromModel(const robot::RobotModel& model);

}  // namespace flexirob::bench::peers
