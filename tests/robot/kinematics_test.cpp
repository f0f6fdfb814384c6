#include "robot/kinematics.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "robot/resources.hpp"

namespace flexirob::robot {
namespace {

constexpr double kPi = std::numbers::pi;

// The standard DH tables of DESIGN.md section 4, evaluated independently of the URDF:
// T_i = Rz(q_i) Tz(d_i) Rx(alpha_i) (a = 0).
struct DhTable {
  std::vector<double> d;
  std::vector<double> alpha;
};

const DhTable kLwr4{{0.3105, 0, 0.4, 0, 0.39, 0, 0.078}, {kPi / 2, -kPi / 2, -kPi / 2, kPi / 2, kPi / 2, -kPi / 2, 0}};
const DhTable kArm9{{0.3105, 0, 0.4, 0, 0.4, 0, 0.39, 0, 0.078},
                    {kPi / 2, -kPi / 2, -kPi / 2, kPi / 2, -kPi / 2, kPi / 2, kPi / 2, -kPi / 2, 0}};

Eigen::Matrix4d dhForward(const DhTable& table, const Eigen::VectorXd& q) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (std::size_t i = 0; i < table.d.size(); ++i) {
    const double ct = std::cos(q[static_cast<Eigen::Index>(i)]);
    const double st = std::sin(q[static_cast<Eigen::Index>(i)]);
    const double ca = std::cos(table.alpha[i]);
    const double sa = std::sin(table.alpha[i]);
    Eigen::Matrix4d A;
    A << ct, -st * ca, st * sa, 0,  //
        st, ct * ca, -ct * sa, 0,   //
        0, sa, ca, table.d[i],      //
        0, 0, 0, 1;
    T = T * A;
  }
  return T;
}

Eigen::VectorXd randomPosture(const RobotModel& model, std::mt19937& engine) {
  Eigen::VectorXd q(model.dof());
  for (int j = 0; j < model.dof(); ++j) {
    const auto& limits = model.joints()[static_cast<std::size_t>(j)].limits;
    std::uniform_real_distribution<double> uniform(limits.lower, limits.upper);
    q[j] = uniform(engine);
  }
  return q;
}

class BuiltinRobot : public ::testing::TestWithParam<std::string> {
 protected:
  RobotModel model_ = RobotModel::fromUrdfFile(resolveRobotPath(GetParam()));
  const DhTable& dh() const { return GetParam() == "lwr4" ? kLwr4 : kArm9; }
};

TEST_P(BuiltinRobot, StraightUpReachesTheSumOfItsSegmentLengths) {
  const Eigen::Isometry3d X_WT = tipPose(model_, Eigen::VectorXd::Zero(model_.dof()));
  double height = 0;
  for (double d : dh().d) height += d;
  EXPECT_NEAR(X_WT.translation().z(), height, 1e-12);
  EXPECT_NEAR(X_WT.translation().head<2>().norm(), 0.0, 1e-12);
  EXPECT_TRUE(X_WT.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

TEST_P(BuiltinRobot, TipPoseMatchesTheIndependentDhChain) {
  std::mt19937 engine(7);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::VectorXd q = randomPosture(model_, engine);
    const Eigen::Matrix4d expected = dhForward(dh(), q);
    const Eigen::Isometry3d X_WT = tipPose(model_, q);
    ASSERT_TRUE(X_WT.matrix().isApprox(expected, 1e-10)) << "q = " << q.transpose() << "\n"
                                                         << X_WT.matrix() << "\nvs\n" << expected;
  }
}

TEST_P(BuiltinRobot, PositiveA2TiltsTheStretchedArmTowardsMinusX) {
  // A2's axis is -y at q1 = 0 (alpha_1 = +pi/2), so +90 deg turns the arm's z axis into -x.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model_.dof());
  q[1] = kPi / 2;
  const Eigen::Vector3d p = tipPose(model_, q).translation();
  double reach = 0;
  for (std::size_t i = 1; i < dh().d.size(); ++i) reach += dh().d[i];
  EXPECT_LT((p - Eigen::Vector3d(-reach, 0, 0.3105)).norm(), 1e-9) << p.transpose();
}

TEST_P(BuiltinRobot, JacobianMatchesFiniteDifferences) {
  std::mt19937 engine(11);
  Kinematics kinematics(model_);
  Matrix6Xd J_WT;
  const double h = 1e-6;
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::VectorXd q = randomPosture(model_, engine);
    kinematics.update(q);
    kinematics.tipJacobian(J_WT);
    for (int j = 0; j < model_.dof(); ++j) {
      Eigen::VectorXd plus = q;
      Eigen::VectorXd minus = q;
      plus[j] += h;
      minus[j] -= h;
      const Eigen::Isometry3d X_plus = tipPose(model_, plus);
      const Eigen::Isometry3d X_minus = tipPose(model_, minus);
      const Eigen::Vector3d linear = (X_plus.translation() - X_minus.translation()) / (2 * h);
      // Angular velocity: the rotation vector of R(q+h) R(q-h)^T over 2h (world-aligned).
      const Eigen::AngleAxisd delta(X_plus.linear() * X_minus.linear().transpose());
      const Eigen::Vector3d angular = delta.axis() * delta.angle() / (2 * h);
      EXPECT_LT((J_WT.block<3, 1>(0, j) - linear).norm(), 1e-7) << "joint " << j;
      EXPECT_LT((J_WT.block<3, 1>(3, j) - angular).norm(), 1e-7) << "joint " << j;
    }
  }
}

TEST_P(BuiltinRobot, PositionJacobianIsTheLinearPartOfTheTipJacobian) {
  std::mt19937 engine(3);
  Kinematics kinematics(model_);
  kinematics.update(randomPosture(model_, engine));
  Matrix6Xd J_WT;
  Matrix3Xd Jp_WT;
  kinematics.tipJacobian(J_WT);
  kinematics.tipPositionJacobian(Jp_WT);
  EXPECT_TRUE(Jp_WT.isApprox(J_WT.topRows<3>(), 1e-14));
}

TEST_P(BuiltinRobot, PointJacobianOfABodyPointMatchesFiniteDifferences) {
  std::mt19937 engine(5);
  Kinematics kinematics(model_);
  const Eigen::VectorXd q = randomPosture(model_, engine);
  kinematics.update(q);
  const int body = 3;
  const Eigen::Vector3d p_B(0.05, -0.02, 0.1);  // a point fixed on body 3
  const Eigen::Vector3d p_W = kinematics.X_WB(body) * p_B;
  Matrix3Xd Jp;
  kinematics.pointJacobian(body, p_W, Jp);
  const double h = 1e-6;
  Kinematics probe(model_);
  for (int j = 0; j < model_.dof(); ++j) {
    Eigen::VectorXd plus = q;
    Eigen::VectorXd minus = q;
    plus[j] += h;
    minus[j] -= h;
    probe.update(plus);
    const Eigen::Vector3d p_plus = probe.X_WB(body) * p_B;
    probe.update(minus);
    const Eigen::Vector3d p_minus = probe.X_WB(body) * p_B;
    EXPECT_LT((Jp.col(j) - (p_plus - p_minus) / (2 * h)).norm(), 1e-7) << "joint " << j;
  }
  EXPECT_TRUE(Jp.rightCols(model_.dof() - body).isZero()) << "later joints do not move body 3";
}

INSTANTIATE_TEST_SUITE_P(Robots, BuiltinRobot, ::testing::Values("lwr4", "arm9"));

TEST(Kinematics, RefusesAPostureOfTheWrongSize) {
  const auto model = RobotModel::fromUrdfFile(resolveRobotPath("lwr4"));
  Kinematics kinematics(model);
  EXPECT_ANY_THROW(kinematics.update(Eigen::VectorXd::Zero(9)));
}

}  // namespace
}  // namespace flexirob::robot
