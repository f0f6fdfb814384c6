#include "app/cli/bench/peers/kdl_chain.hpp"

#include <kdl/joint.hpp>
#include <kdl/segment.hpp>

namespace flexirob::bench::peers {

KDL::Frame toKdl(const Eigen::Isometry3d& X) {
  const Eigen::Matrix3d& R = X.linear();
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(X.translation().x(), X.translation().y(), X.translation().z()));
}

Eigen::Isometry3d fromKdl(const KDL::Frame& frame) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = frame.M(r, c);
    X.translation()[r] = frame.p(r);
  }
  return X;
}

KDL::JntArray toKdl(const Eigen::VectorXd& q) {
  KDL::JntArray array(static_cast<unsigned int>(q.size()));
  array.data = q;
  return array;
}

Eigen::VectorXd fromKdl(const KDL::JntArray& q) { return q.data; }

KDL::Chain kdlChainFromModel(const robot::RobotModel& model) {
  KDL::Chain chain;
  const auto& joints = model.joints();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const robot::Joint& joint = joints[j];
    const Eigen::Vector3d origin_P = joint.X_PJ.translation();
    const Eigen::Vector3d axis_P = joint.X_PJ.linear() * joint.axis_J;
    const KDL::Joint::JointType type =
        joint.type == robot::JointType::kPrismatic ? KDL::Joint::TransAxis : KDL::Joint::RotAxis;
    const KDL::Joint kdl_joint(joint.name, KDL::Vector(origin_P.x(), origin_P.y(), origin_P.z()),
                               KDL::Vector(axis_P.x(), axis_P.y(), axis_P.z()), type);
    chain.addSegment(KDL::Segment(model.bodies()[j + 1].name, kdl_joint, toKdl(joint.X_PJ)));
  }
  chain.addSegment(KDL::Segment(model.tipLink() + "_tip", KDL::Joint(KDL::Joint::Fixed), toKdl(model.X_LastBodyTip())));
  return chain;
}

}  // namespace flexirob::bench::peers
