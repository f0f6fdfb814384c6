#include "robot/sim/simulation.hpp"

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointLimitConstraint.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "robot/errors.hpp"

namespace flexirob::robot {
namespace {

constexpr std::array kSimulationParameters{
    ParameterDeclaration{"sim.substeps", 4.0, 1.0, 64.0, "",
                         "physics steps per 1 ms control cycle (the impedance law is evaluated in each)"},
    ParameterDeclaration{"sim.gravity", 9.81, 0.0, 20.0, "m/s^2", "gravitational acceleration along -z"},
    ParameterDeclaration{"sim.drift_damping", 0.5, 0.0, 50.0, "Nms/rad",
                         "added joint damping so that a released arm comes to rest (the LWR IV's; a lighter arm gets it in proportion to its joint inertia)"},
    ParameterDeclaration{"sim.stiffness", 300.0, 0.0, 5000.0, "Nm/rad",
                         "joint stiffness until the first command (hierarchical control, Tab. A.1)"},
    ParameterDeclaration{"sim.damping", 0.95, 0.0, 1.0, "",
                         "normalized joint damping until the first command (Tab. A.1)"},
};

// See stableSubsteps().
constexpr double kStableStepBound = 3.0;
// The drift damping acts at most at this rate [1/s] on a joint (d ≤ rate · M_jj): 0.5 Nms/rad on
// a link far lighter than the LWR IV's flange would be a time constant far under a physics step
// (2 µs on 1e-6 kg m²), which no affordable step count integrates. The LWR IV's and arm9's
// joints all have M_jj ≥ 2e-4 kg m², so theirs is the configured damping up to 0.8 Nms/rad
// (the default is 0.5).
constexpr double kMaxDriftRate = 4000.0;

// Bullet needs positive masses and inertias; links the URDF leaves without inertia get a token one.
constexpr double kMinMass = 1e-3;      // [kg]
constexpr double kMinInertia = 1e-6;   // [kg m²]

btVector3 toBt(const Eigen::Vector3d& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }

btQuaternion toBt(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w()));
}

// Principal axes (a rotation, columns) and moments of an inertia tensor.
void principalAxes(const Eigen::Matrix3d& I, Eigen::Matrix3d& R, Eigen::Vector3d& moments) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(0.5 * (I + I.transpose()));
  R = eigen.eigenvectors();
  if (R.determinant() < 0) R.col(2) = -R.col(2);
  moments = eigen.eigenvalues().cwiseMax(kMinInertia);
}

}  // namespace

std::span<const ParameterDeclaration> simulationParameters() { return kSimulationParameters; }

struct Simulation::Impl {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  btMultiBodyDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  std::unique_ptr<btMultiBody> body;
  std::vector<std::unique_ptr<btMultiBodyJointLimitConstraint>> limits;
  // Bullet solves a multibody constraint only in the simulation island of its links' colliders
  // (a link without one has island -1, and its limit stops were never solved: a 20 N push took
  // A2 0.15 rad through its stop). The colliders collide with nothing (group and mask 0): the
  // scene's contacts are CollisionWorld's business.
  btSphereShape collider_shape{btScalar(1e-3)};
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
  // Scratch of stableSubsteps(), sized once: the joint-space inertia matrix M(q) and what is
  // derived from it (the control thread steps the simulation and must not allocate).
  Eigen::MatrixXd mass_matrix, com_velocities, whitened, whitened_gram;
  Eigen::VectorXd damping;
  Eigen::LLT<Eigen::MatrixXd> mass_cholesky;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> whitened_eigen;

  explicit Impl(int dof)
      : mass_matrix(dof, dof),
        com_velocities(3, dof),
        whitened(dof, dof),
        whitened_gram(dof, dof),
        damping(dof),
        mass_cholesky(dof),
        whitened_eigen(dof) {}

  ~Impl() {
    for (auto& limit : limits) world.removeMultiBodyConstraint(limit.get());
    for (auto& collider : colliders) world.removeCollisionObject(collider.get());
    if (body) world.removeMultiBody(body.get());
  }
};

Simulation::Simulation(const RobotModel& model, const Scene* scene, const ParameterSet& parameters)
    : model_(&model),
      cycle_time_(1e-3),
      substeps_(static_cast<int>(parameters.get("sim.substeps"))),
      gravity_(parameters.get("sim.gravity")),
      // Sized for the LWR IV: on a lighter arm 0.5 Nms/rad would be honey the interaction's
      // (scaled) pushes could not move through.
      drift_damping_(parameters.get("sim.drift_damping") * inertiaScaleToLwr(model)),
      impl_(std::make_unique<Impl>(model.dof())),
      kinematics_(model),
      jacobian_(3, model.dof()) {
  const int n = model.dof();
  q_.setZero(n);
  qd_.setZero(n);
  tau_.setZero(n);
  tau_ext_.setZero(n);
  gravity_torque_.setZero(n);
  inertia_diagonal_.setZero(n);
  effort_.setZero(n);
  for (int j = 0; j < n; ++j) effort_[j] = model.joints()[static_cast<std::size_t>(j)].limits.effort;
  command_.resize(n);
  command_.stiffness.setConstant(parameters.get("sim.stiffness") * inertiaScaleToLwr(model));  // as the drift damping
  command_.damping.setConstant(parameters.get("sim.damping"));

  // Each Bullet link frame sits at the body's centre of mass, turned to its principal axes.
  const auto& bodies = model.bodies();
  std::vector<Eigen::Matrix3d> R_BL(bodies.size());
  std::vector<Eigen::Vector3d> moments(bodies.size());
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Body& body = bodies[b];
    const bool massless = !(body.mass > kMinMass);
    masses_.push_back(massless ? kMinMass : body.mass);
    coms_.push_back(body.p_BCom);
    principalAxes(massless ? Eigen::Matrix3d(Eigen::Matrix3d::Identity() * kMinInertia) : body.I_BCom, R_BL[b], moments[b]);
    inertias_.push_back(R_BL[b] * moments[b].asDiagonal() * R_BL[b].transpose());
  }
  impl_->body = std::make_unique<btMultiBody>(n, btScalar(masses_[0]), toBt(moments[0]), true, false);
  btMultiBody& mb = *impl_->body;
  mb.setBaseWorldTransform(btTransform(toBt(R_BL[0]), toBt(coms_[0])));
  for (int j = 0; j < n; ++j) {
    const Joint& joint = model.joints()[static_cast<std::size_t>(j)];
    const std::size_t parent = static_cast<std::size_t>(j);
    const std::size_t child = static_cast<std::size_t>(j + 1);
    // Vectors in the parent link frame to vectors in this link frame, at q = 0.
    const Eigen::Matrix3d R_child_parent = R_BL[child].transpose() * joint.X_PJ.linear().transpose() * R_BL[parent];
    const Eigen::Vector3d axis_L = R_BL[child].transpose() * joint.axis_J;
    const Eigen::Vector3d parent_com_to_pivot = R_BL[parent].transpose() * (joint.X_PJ.translation() - coms_[parent]);
    const Eigen::Vector3d pivot_to_com = R_BL[child].transpose() * coms_[child];
    if (joint.type == JointType::kPrismatic) {
      mb.setupPrismatic(j, btScalar(masses_[child]), toBt(moments[child]), j - 1, toBt(R_child_parent), toBt(axis_L),
                        toBt(parent_com_to_pivot), toBt(pivot_to_com), true);
    } else {
      mb.setupRevolute(j, btScalar(masses_[child]), toBt(moments[child]), j - 1, toBt(R_child_parent), toBt(axis_L),
                       toBt(parent_com_to_pivot), toBt(pivot_to_com), true);
    }
  }
  mb.finalizeMultiDof();
  mb.setLinearDamping(0);
  mb.setAngularDamping(0);
  mb.setCanSleep(false);
  mb.setHasSelfCollision(false);
  mb.setMaxCoordinateVelocity(btScalar(100));
  impl_->world.setGravity(btVector3(0, 0, btScalar(-gravity_)));
  impl_->world.addMultiBody(&mb);
  for (int link = -1; link < n; ++link) {
    auto collider = std::make_unique<btMultiBodyLinkCollider>(&mb, link);
    collider->setCollisionShape(&impl_->collider_shape);
    collider->setActivationState(DISABLE_DEACTIVATION);
    impl_->world.addCollisionObject(collider.get(), 0, 0);
    if (link < 0) {
      mb.setBaseCollider(collider.get());
    } else {
      mb.getLink(link).m_collider = collider.get();
    }
    impl_->colliders.push_back(std::move(collider));
  }
  // The hardware limits stop the joints (the soft limits are the controllers' business).
  for (int j = 0; j < n; ++j) {
    const JointLimits& limits = model.joints()[static_cast<std::size_t>(j)].limits;
    if (!std::isfinite(limits.lower) || !std::isfinite(limits.upper)) continue;
    auto constraint = std::make_unique<btMultiBodyJointLimitConstraint>(&mb, j, btScalar(limits.lower), btScalar(limits.upper));
    impl_->world.addMultiBodyConstraint(constraint.get());
    impl_->limits.push_back(std::move(constraint));
  }

  const Scene empty;
  collision_ = std::make_unique<CollisionWorld>(model, scene != nullptr ? *scene : empty);
  contacts_.reserve(64);
  reset(model.midPosture());
}

Simulation::~Simulation() = default;

void Simulation::reset(const Eigen::VectorXd& q) {
  model_->checkPosture(q);
  const Eigen::VectorXd lower = model_->lowerLimits();
  const Eigen::VectorXd upper = model_->upperLimits();
  for (int j = 0; j < model_->dof(); ++j) {
    if (q[j] < lower[j] - 1e-9 || q[j] > upper[j] + 1e-9) {
      std::ostringstream message;
      message << std::setprecision(4) << "joint '" << model_->joints()[static_cast<std::size_t>(j)].name
              << "': start value " << q[j] << " is outside the limits [" << lower[j] << ", " << upper[j] << "]";
      throw InputError(message.str());
    }
    impl_->body->setJointPos(j, btScalar(q[j]));
    impl_->body->setJointVel(j, 0);
  }
  impl_->body->clearForcesAndTorques();
  readJoints();
  command_.q_cmd = q_;
  computeModelTerms();
  time_ = 0.0;
  steps_ = 0;
  torque_saturations_ = 0;
  last_substeps_ = std::min(stableSubsteps(), kSubstepCap);
  substep_cap_reached_ = false;
  checked_stiffness_ = command_.stiffness;
  checked_damping_ = command_.damping;
  max_substeps_ = 0;
  monitor_.reset();
  collision_->update(q_);
  contacts_ = collision_->contacts();
  monitor_.observe(contacts_, time_);
}

void Simulation::readJoints() {
  for (int j = 0; j < model_->dof(); ++j) {
    q_[j] = double(impl_->body->getJointPos(j));
    qd_[j] = double(impl_->body->getJointVel(j));
  }
}

void Simulation::computeModelTerms() {
  kinematics_.update(q_);
  modelTerms(kinematics_, gravity_torque_, &inertia_diagonal_);
}

void Simulation::modelTerms(const Kinematics& kinematics, Eigen::VectorXd& gravity_torque,
                            Eigen::VectorXd* inertia_diagonal) const {
  const int n = model_->dof();
  gravity_torque.setZero(n);
  if (inertia_diagonal != nullptr) inertia_diagonal->setZero(n);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d axis = kinematics.axis_W(j);
    const Eigen::Vector3d origin = kinematics.X_WB(j + 1).translation();
    const bool prismatic = isPrismatic(j);
    for (int b = j + 1; b <= n; ++b) {
      const Eigen::Isometry3d& X_WB = kinematics.X_WB(b);
      const Eigen::Vector3d c_W = X_WB * coms_[static_cast<std::size_t>(b)];
      const double m = masses_[static_cast<std::size_t>(b)];
      // ∂c/∂q_j: the velocity of the body's centre of mass for a unit joint velocity.
      const Eigen::Vector3d v = prismatic ? axis : Eigen::Vector3d(axis.cross(c_W - origin));
      gravity_torque[j] += m * gravity_ * v.z();
      if (inertia_diagonal == nullptr) continue;
      (*inertia_diagonal)[j] += m * v.squaredNorm();
      if (!prismatic) {
        (*inertia_diagonal)[j] += axis.dot(X_WB.linear() * inertias_[static_cast<std::size_t>(b)] * X_WB.linear().transpose() * axis);
      }
    }
  }
}

std::string Simulation::describe(const GravityLoad& load) const {
  if (load.joint < 0) return "no joint with an effort limit";
  const char* unit = isPrismatic(load.joint) ? " N" : " Nm";
  // One decimal below 10 as printed (9.97 prints as 10, not 10.0).
  const auto decimals = [](double value) { return value < 9.95 ? 1 : 0; };
  std::ostringstream text;
  text << std::fixed << std::setprecision(decimals(load.torque)) << "joint '"
       << model_->joints()[static_cast<std::size_t>(load.joint)].name << "' to hold " << load.torque << unit
       // Rounded away from 100 %, so that an overload never reads as exactly the limit.
       << " against gravity, " << std::setprecision(0)
       << (load.ratio > 1.0 ? std::ceil(100.0 * load.ratio) : std::floor(100.0 * load.ratio)) << " % of its effort limit of "
       << std::setprecision(decimals(load.effort)) << load.effort << unit;
  return text.str();
}

Simulation::GravityLoad Simulation::gravityLoad(const Eigen::VectorXd& q) const {
  if (q.size() != model_->dof()) throw InputError("gravityLoad: expected " + std::to_string(model_->dof()) + " joint values");
  Kinematics kinematics(*model_);
  kinematics.update(q);
  Eigen::VectorXd gravity_torque;
  modelTerms(kinematics, gravity_torque, nullptr);
  GravityLoad load;
  for (int j = 0; j < model_->dof(); ++j) {
    if (effort_[j] <= 0.0) continue;
    const double ratio = std::abs(gravity_torque[j]) / effort_[j];
    if (load.joint < 0 || ratio > load.ratio) load = {j, std::abs(gravity_torque[j]), effort_[j], ratio};
  }
  return load;
}

double Simulation::driftDamping(double joint_inertia) const { return std::min(drift_damping_, kMaxDriftRate * joint_inertia); }

int Simulation::stableSubsteps() {
  // Bullet integrates semi-implicitly (velocity first, then position with the new velocity). For
  // M q̈ = −K q − D q̇ with damping proportional to stiffness that is stable while
  // 2 h c + h² ω² < 4 in every mode, with ω² and c the largest eigenvalues of M⁻¹K and M⁻¹D;
  // D_jj = 2ζ sqrt(K_jj M_jj) is not exactly proportional, so the bound taken from the two
  // largest eigenvalues is an estimate, and the step keeps a margin of a quarter below that
  // bound, 2 h c + h² ω² ≤ B = 3 (the LWR IV's flange alone needs 2.6 at the default 4 substeps;
  // arm9's wrist, where two of its axes come close to parallel, needed more than 4, and its
  // torques saturated there).
  const int n = model_->dof();
  Impl& scratch = *impl_;
  Eigen::MatrixXd& M = scratch.mass_matrix;
  M.setZero();
  for (int b = 1; b <= n; ++b) {
    const Eigen::Isometry3d& X_WB = kinematics_.X_WB(b);
    const Eigen::Vector3d c_W = X_WB * coms_[static_cast<std::size_t>(b)];
    const Eigen::Matrix3d I_W = X_WB.linear() * inertias_[static_cast<std::size_t>(b)] * X_WB.linear().transpose();
    const double m = masses_[static_cast<std::size_t>(b)];
    // Joints 0..b-1 move body b; column j is ∂c_b/∂q_j.
    for (int j = 0; j < b; ++j) {
      const Eigen::Vector3d axis = kinematics_.axis_W(j);
      scratch.com_velocities.col(j) = isPrismatic(j) ? axis : Eigen::Vector3d(axis.cross(c_W - kinematics_.X_WB(j + 1).translation()));
    }
    for (int i = 0; i < b; ++i) {
      for (int j = 0; j <= i; ++j) {
        double m_ij = m * scratch.com_velocities.col(i).dot(scratch.com_velocities.col(j));
        if (!isPrismatic(i) && !isPrismatic(j)) m_ij += kinematics_.axis_W(i).dot(I_W * kinematics_.axis_W(j));
        M(i, j) += m_ij;
        if (i != j) M(j, i) += m_ij;
      }
    }
  }
  const int configured = substeps_;
  // Not positive definite (a NaN posture, or inertias too small to tell apart): no count can be
  // justified, so the most.
  scratch.mass_cholesky.compute(M);
  if (scratch.mass_cholesky.info() != Eigen::Success) return kSubstepCap + 1;
  // λ_max(M⁻¹A) for a diagonal A ≥ 0 is λ_max(Wᵀ W) with W = L⁻¹ A^½, M = L Lᵀ.
  const auto largestEigenvalue = [&scratch](const Eigen::VectorXd& diagonal) {
    scratch.whitened.setZero();
    scratch.whitened.diagonal() = diagonal.cwiseMax(0.0).cwiseSqrt();
    scratch.mass_cholesky.matrixL().solveInPlace(scratch.whitened);
    scratch.whitened_gram.noalias() = scratch.whitened.transpose() * scratch.whitened;
    scratch.whitened_eigen.compute(scratch.whitened_gram, Eigen::EigenvaluesOnly);
    return scratch.whitened_eigen.info() == Eigen::Success ? scratch.whitened_eigen.eigenvalues().maxCoeff()
                                                           : std::numeric_limits<double>::infinity();
  };
  for (int j = 0; j < n; ++j) {
    scratch.damping[j] = 2.0 * command_.damping[j] * std::sqrt(command_.stiffness[j] * M(j, j)) + driftDamping(M(j, j));
  }
  const double omega_squared = largestEigenvalue(command_.stiffness);
  const double c = largestEigenvalue(scratch.damping);
  // The positive root of h² ω² + 2 h c = B, written so that ω = 0 needs no special case.
  const double step_bound = kStableStepBound / (c + std::sqrt(c * c + kStableStepBound * omega_squared));
  if (std::isnan(step_bound)) return kSubstepCap + 1;
  if (step_bound >= cycle_time_ / configured) return configured;  // also an infinite bound: ω = c = 0
  return static_cast<int>(std::min<double>(kSubstepCap + 1, std::ceil(cycle_time_ / step_bound)));
}

const Eigen::MatrixXd& Simulation::jointSpaceInertia() const { return impl_->mass_matrix; }

CommandStatus Simulation::writeCommand(const JointImpedanceCommand& command) {
  const int n = model_->dof();
  if (command.q_cmd.size() != n || command.stiffness.size() != n || command.damping.size() != n ||
      !command.q_cmd.allFinite() || !command.stiffness.allFinite() || !command.damping.allFinite() ||
      (command.stiffness.array() < 0).any() || (command.damping.array() < 0).any()) {
    return CommandStatus::kRejected;
  }
  for (int j = 0; j < n; ++j) {
    const JointLimits& limits = model_->joints()[static_cast<std::size_t>(j)].limits;
    if (command.q_cmd[j] < limits.lower || command.q_cmd[j] > limits.upper) return CommandStatus::kRejected;
  }
  command_.q_cmd = command.q_cmd;
  command_.stiffness = command.stiffness;
  command_.damping = command.damping;
  return CommandStatus::kAccepted;
}

void Simulation::setHandForce(int body, const Eigen::Vector3d& p_W, const Eigen::Vector3d& F_W) {
  if (body < 1 || body > model_->dof()) {
    throw InputError("hand: expected a body index in [1, " + std::to_string(model_->dof()) + "], got " + std::to_string(body));
  }
  if (!p_W.allFinite() || !F_W.allFinite()) throw InputError("hand: point and force must be finite");
  hand_body_ = body;
  hand_p_B_ = kinematics_.X_WB(body).inverse() * p_W;
  hand_F_W_ = F_W;
}

void Simulation::clearHandForce() {
  hand_body_ = -1;
  hand_F_W_.setZero();
}

void Simulation::step() {
  const int n = model_->dof();
  // The posture moves little in 10 ms; a new command's gains take effect at once.
  if (steps_ % kSubstepCheckCycles == 0 || (command_.stiffness.array() != checked_stiffness_.array()).any() ||
      (command_.damping.array() != checked_damping_.array()).any()) {
    checked_stiffness_ = command_.stiffness;
    checked_damping_ = command_.damping;
    last_substeps_ = stableSubsteps();
    if (last_substeps_ > kSubstepCap) {
      substep_cap_reached_ = true;
      last_substeps_ = kSubstepCap;
    }
  }
  const int substeps = last_substeps_;
  max_substeps_ = std::max(max_substeps_, substeps);
  const double h = cycle_time_ / substeps;
  btMultiBody& mb = *impl_->body;
  for (int s = 0; s < substeps; ++s) {
    if (s > 0) {
      readJoints();
      computeModelTerms();
    }
    mb.clearForcesAndTorques();
    // The joint impedance law, gravity compensated (App. A.3).
    for (int j = 0; j < n; ++j) {
      const double k = command_.stiffness[j];
      const double d = 2.0 * command_.damping[j] * std::sqrt(k * inertia_diagonal_[j]) + driftDamping(inertia_diagonal_[j]);
      double tau = gravity_torque_[j] + k * (command_.q_cmd[j] - q_[j]) - d * qd_[j];
      if (effort_[j] > 0.0 && std::abs(tau) > effort_[j]) {
        tau = std::copysign(effort_[j], tau);
        ++torque_saturations_;
      }
      tau_[j] = tau;
      mb.addJointTorque(j, btScalar(tau));
    }
    // The hand pushes at its point: a force at the centre of mass plus its moment.
    if (hand_body_ > 0) {
      const Eigen::Isometry3d& X_WB = kinematics_.X_WB(hand_body_);
      const Eigen::Vector3d p_W = X_WB * hand_p_B_;
      const Eigen::Vector3d c_W = X_WB * coms_[static_cast<std::size_t>(hand_body_)];
      mb.addLinkForce(hand_body_ - 1, toBt(hand_F_W_));
      mb.addLinkTorque(hand_body_ - 1, toBt(Eigen::Vector3d((p_W - c_W).cross(hand_F_W_))));
    }
    impl_->world.stepSimulation(btScalar(h), 0, btScalar(h));
  }
  readJoints();
  computeModelTerms();
  time_ += cycle_time_;
  ++steps_;
  collision_->update(q_);
  const std::vector<Contact>& contacts = collision_->contacts();
  contacts_.assign(contacts.begin(), contacts.end());
  monitor_.observe(contacts_, time_);
}

void Simulation::readState(RobotState& state) const {
  const int n = model_->dof();
  if (state.q.size() != n) state.resize(n);
  state.time = time_;
  state.q = q_;
  state.qd = qd_;
  state.q_cmd = command_.q_cmd;
  state.X_WT = kinematics_.X_WT();
  state.in_contact = !contacts_.empty();
  // τ_ext as the robot estimates it: the hand's force mapped through the contact's Jacobian.
  if (hand_body_ > 0) {
    kinematics_.pointJacobian(hand_body_, kinematics_.X_WB(hand_body_) * hand_p_B_, jacobian_);
    state.tau_ext.noalias() = jacobian_.transpose() * hand_F_W_;
  } else {
    state.tau_ext.setZero();
  }
}

}  // namespace flexirob::robot
