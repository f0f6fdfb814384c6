#include "robot/collision.hpp"

#include <btBulletCollisionCommon.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "robot/errors.hpp"
#include "robot/mesh.hpp"
#include "robot/mesh_solid.hpp"
#include "robot/scene.hpp"

namespace flexirob::robot {
namespace {

btVector3 toBt(const Eigen::Vector3d& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
Eigen::Vector3d toEigen(const btVector3& v) { return Eigen::Vector3d(double(v.x()), double(v.y()), double(v.z())); }

btTransform toBt(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond rotation(X.linear());
  return btTransform(btQuaternion(btScalar(rotation.x()), btScalar(rotation.y()), btScalar(rotation.z()), btScalar(rotation.w())),
                     toBt(Eigen::Vector3d(X.translation())));
}

// A pose whose z axis points from a to b (for capsules and cylinders along a segment).
Eigen::Isometry3d segmentPose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = 0.5 * (a + b);
  const Eigen::Vector3d direction = b - a;
  if (direction.norm() > 1e-12) {
    X.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), direction.normalized()).toRotationMatrix();
  }
  return X;
}

constexpr double kDefaultRadius = 0.05;  // [m] for links without a mass of their own

// Radius of a solid cylinder with the body's mass and smallest principal inertia. A mass the
// model assumed (no <inertial>) says nothing of the link's girth.
double capsuleRadius(const Body& body) {
  if (!(body.mass > 1e-6) || body.inertia_assumed) return kDefaultRadius;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(body.I_BCom, Eigen::EigenvaluesOnly);
  const double i_min = eigen.eigenvalues()[0];
  if (!(i_min > 0.0)) return kDefaultRadius;
  return std::clamp(std::sqrt(2.0 * i_min / body.mass), 0.01, 0.25);
}

// Whether the two revolute joints at the ends of `body` (the one into it and the one out of
// it) have axes that cross in one point, as at the shoulder, elbow and wrist of the LWR IV.
// The bodies before and after such a body only turn about that point relative to each other;
// whether they can meet is settled by the joint limits the arm's designers chose, which coarse
// collision hulls cannot resolve (the LWR's flange would "touch" its forearm hull past
// |A6| = 92 deg). Pairs folding over a body of non-zero length stay checked.
bool jointsAroundBodyIntersect(const RobotModel& model, int body) {
  if (body < 1 || body >= model.dof()) return false;
  const Joint& in = model.joints()[static_cast<std::size_t>(body - 1)];
  const Joint& out = model.joints()[static_cast<std::size_t>(body)];
  if (in.type == JointType::kPrismatic || out.type == JointType::kPrismatic) return false;
  // In the body's own frame: the incoming axis passes through its origin, the outgoing one
  // through the next joint's origin.
  const Eigen::Vector3d u = in.axis_J;
  const Eigen::Vector3d v = out.X_PJ.linear() * out.axis_J;
  const Eigen::Vector3d offset = out.X_PJ.translation();
  const Eigen::Vector3d normal = u.cross(v);
  if (normal.norm() < 1e-9) return false;  // parallel axes never cross in one point
  return std::abs(offset.dot(normal.normalized())) < 1e-6;  // coplanar and not parallel: they cross
}

}  // namespace

// Keeps unchecked self-collision pairs (adjacent, or touching at the reference posture) out of
// the broadphase, so that no narrow-phase work is spent on them.
struct PairFilter : btOverlapFilterCallback {
  const std::vector<char>* checked = nullptr;
  int bodies = 0;
  bool needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const override {
    if ((a->m_collisionFilterGroup & b->m_collisionFilterMask) == 0 ||
        (b->m_collisionFilterGroup & a->m_collisionFilterMask) == 0) {
      return false;
    }
    const auto* object_a = static_cast<const btCollisionObject*>(a->m_clientObject);
    const auto* object_b = static_cast<const btCollisionObject*>(b->m_clientObject);
    const int body_a = object_a->getUserIndex();
    const int body_b = object_b->getUserIndex();
    if (body_a < 0 || body_b < 0) return true;
    return (*checked)[static_cast<std::size_t>(body_a * bodies + body_b)] != 0;
  }
};

struct CollisionWorld::Impl {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &configuration};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;  // owns every shape, children included
  // Triangle data of concave obstacle meshes (Bullet keeps pointers into it).
  std::vector<std::unique_ptr<btTriangleIndexVertexArray>> mesh_interfaces;
  std::vector<std::vector<btScalar>> mesh_vertices;
  std::vector<std::vector<int>> mesh_indices;
  std::vector<std::unique_ptr<btCollisionObject>> body_objects;      // index = body
  std::vector<std::unique_ptr<btCollisionObject>> obstacle_objects;  // index = obstacle
  std::vector<std::string> shape_source;
  std::vector<char> checked_pairs;  // bodies × bodies
  std::vector<char> table_exempt;   // per body: the base, and links on the table at the reference posture
  std::vector<char> fixed_gap;      // obstacles a gap no joint can change parts from the first link
  int table = -1;                   // obstacle index of the table top, -1 without one
  int bodies = 0;
  PairFilter filter;
  Kinematics kinematics;
  std::vector<Contact> contacts;

  explicit Impl(const RobotModel& model) : kinematics(model) {}

  template <typename Shape, typename... Args>
  Shape* make(Args&&... args) {
    auto shape = std::make_unique<Shape>(std::forward<Args>(args)...);
    Shape* raw = shape.get();
    shapes.push_back(std::move(shape));
    return raw;
  }

  // Primitive shape of a size given as in the URDF / the scene; nullptr for unusable sizes.
  btCollisionShape* primitive(Geometry::Kind kind, const Eigen::Vector3d& size) {
    switch (kind) {
      case Geometry::Kind::kBox:
        if ((size.array() <= 0).any()) return nullptr;
        return make<btBoxShape>(toBt(Eigen::Vector3d(0.5 * size)));
      case Geometry::Kind::kCylinder:
        if (size[0] <= 0 || size[1] <= 0) return nullptr;
        return make<btCylinderShapeZ>(btVector3(btScalar(size[0]), btScalar(size[0]), btScalar(0.5 * size[1])));
      case Geometry::Kind::kSphere:
        if (size[0] <= 0) return nullptr;
        return make<btSphereShape>(btScalar(size[0]));
      case Geometry::Kind::kMesh: return nullptr;
    }
    return nullptr;
  }

  // A link mesh as its convex hull (scale applied in the mesh's own frame).
  btCollisionShape* convexHull(const std::filesystem::path& file, const Eigen::Vector3d& scale) {
    const TriangleMesh mesh = transformedMesh(*loadMeshCached(file), Eigen::Isometry3d::Identity(), scale);
    if (mesh.empty()) return nullptr;
    auto* hull = make<btConvexHullShape>();
    for (const Eigen::Vector3f& v : mesh.vertices) hull->addPoint(btVector3(v.x(), v.y(), v.z()), false);
    hull->recalcLocalAabb();
    hull->optimizeConvexHull();
    hull->setMargin(0);
    return hull;
  }

  // An obstacle mesh (concave allowed), for a static object: the triangles of its solid, which
  // the point tests use too (simplified there when the file holds very many).
  btCollisionShape* triangleMesh(const MeshSolid& solid) {
    if (solid.triangles().empty()) return nullptr;
    auto& vertices = mesh_vertices.emplace_back();
    auto& indices = mesh_indices.emplace_back();
    vertices.reserve(solid.triangles().size() * 9);
    indices.reserve(solid.triangles().size() * 3);
    for (const auto& triangle : solid.triangles()) {
      for (const Eigen::Vector3d& corner : triangle) {
        indices.push_back(static_cast<int>(vertices.size() / 3));
        vertices.insert(vertices.end(), {btScalar(corner.x()), btScalar(corner.y()), btScalar(corner.z())});
      }
    }
    auto array = std::make_unique<btTriangleIndexVertexArray>(
        static_cast<int>(solid.triangles().size()), indices.data(), static_cast<int>(3 * sizeof(int)),
        static_cast<int>(vertices.size() / 3), vertices.data(), static_cast<int>(3 * sizeof(btScalar)));
    btCollisionShape* shape = make<btBvhTriangleMeshShape>(array.get(), true);
    mesh_interfaces.push_back(std::move(array));
    return shape;
  }
};

LinkCapsule linkCapsule(const RobotModel& model, int body) {
  const Body& link = model.bodies().at(static_cast<std::size_t>(body));
  LinkCapsule capsule;
  capsule.radius = capsuleRadius(link);
  capsule.b_B = body < model.dof() ? Eigen::Vector3d(model.joints()[static_cast<std::size_t>(body)].X_PJ.translation())
                                   : Eigen::Vector3d(model.X_LastBodyTip().translation());
  if ((capsule.b_B - capsule.a_B).norm() < capsule.radius) capsule.b_B = 2.0 * link.p_BCom;
  return capsule;
}

CollisionWorld::CollisionWorld(const RobotModel& model, const Scene& scene)
    : model_(&model), impl_(std::make_unique<Impl>(model)) {
  Impl& impl = *impl_;
  const auto& bodies = model.bodies();
  impl.bodies = static_cast<int>(bodies.size());
  // Self-collision pairs: first every non-adjacent pair; those touching at the reference
  // posture are dropped below.
  impl.checked_pairs.assign(static_cast<std::size_t>(impl.bodies * impl.bodies), 0);
  for (int a = 0; a < impl.bodies; ++a) {
    for (int b = a + 2; b < impl.bodies; ++b) {
      const bool unchecked = b == a + 2 && jointsAroundBodyIntersect(model, a + 1);
      impl.checked_pairs[static_cast<std::size_t>(a * impl.bodies + b)] = unchecked ? 0 : 1;
      impl.checked_pairs[static_cast<std::size_t>(b * impl.bodies + a)] = unchecked ? 0 : 1;
    }
  }
  impl.filter.checked = &impl.checked_pairs;
  impl.filter.bodies = impl.bodies;
  impl.world.getPairCache()->setOverlapFilterCallback(&impl.filter);
  // Robot links: group 1 collides with obstacles (group 2), the table (group 8) and links; the
  // base (group 4) collides with links only.
  for (int b = 0; b < impl.bodies; ++b) {
    const Body& body = bodies[static_cast<std::size_t>(b)];
    auto* compound = impl.make<btCompoundShape>();
    std::string source = "urdf";
    for (const Geometry& geometry : body.collisions) {
      btCollisionShape* child = nullptr;
      try {
        child = geometry.kind == Geometry::Kind::kMesh ? impl.convexHull(geometry.mesh_file, geometry.mesh_scale)
                                                       : impl.primitive(geometry.kind, geometry.size);
      } catch (const InputError& error) {
        // The importer's words name a file; which link of the robot it belongs to is ours to say.
        throw InputError("link '" + geometry.source_link + "' of robot '" + model.name() + "': " + error.what());
      }
      if (child != nullptr) compound->addChildShape(toBt(geometry.X_BG), child);
    }
    if (compound->getNumChildShapes() == 0) {
      source = "capsule";
      const LinkCapsule capsule = linkCapsule(model, b);
      const double length = (capsule.b_B - capsule.a_B).norm();
      btCollisionShape* child = nullptr;
      if (length < 1e-6) {
        child = impl.make<btSphereShape>(btScalar(capsule.radius));
      } else {
        child = impl.make<btCapsuleShapeZ>(btScalar(capsule.radius), btScalar(length));
      }
      compound->addChildShape(toBt(segmentPose(capsule.a_B, capsule.b_B)), child);
    }
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(compound);
    object->setUserIndex(b);
    object->setUserIndex2(-1);
    const int group = b == 0 ? 4 : 1;
    const int mask = b == 0 ? 1 : (1 | 2 | 4 | 8);
    impl.world.addCollisionObject(object.get(), group, mask);
    impl.body_objects.push_back(std::move(object));
    impl.shape_source.push_back(source);
  }
  // Obstacles: static, group 2, collide with links only.
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    const Obstacle& obstacle = scene.obstacles[k];
    btCollisionShape* shape = nullptr;
    switch (obstacle.shape) {
      case Obstacle::Shape::kBox: shape = impl.primitive(Geometry::Kind::kBox, obstacle.size); break;
      case Obstacle::Shape::kCylinder: shape = impl.primitive(Geometry::Kind::kCylinder, obstacle.size); break;
      case Obstacle::Shape::kSphere: shape = impl.primitive(Geometry::Kind::kSphere, obstacle.size); break;
      case Obstacle::Shape::kMesh: shape = impl.triangleMesh(*meshSolidOf(obstacle)); break;
    }
    if (shape == nullptr) {
      throw InputError("obstacle '" + obstacle.name + "': unsupported shape or non-positive size");
    }
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(shape);
    object->setWorldTransform(toBt(obstacle.X_WO));
    object->setUserIndex(-1);
    object->setUserIndex2(static_cast<int>(k));
    impl.world.addCollisionObject(object.get(), 2, 1);
    impl.obstacle_objects.push_back(std::move(object));
    obstacle_names_.push_back(obstacle.name);
  }
  impl.table_exempt.assign(static_cast<std::size_t>(impl.bodies), 0);
  impl.table_exempt[0] = 1;
  if (scene.table) {
    // A slab under z = 0 wider than anything the arm can reach (Scene::table).
    double reach = model.X_LastBodyTip().translation().norm();
    for (const auto& joint : model.joints()) reach += joint.X_PJ.translation().norm();
    const double half_width = reach + 1.0;
    // As thick as it is wide: a link pushed far below z = 0 is still inside the slab and its
    // depth is measured from the top face, never out through a nearer bottom face.
    const double thickness = half_width;
    btCollisionShape* slab = impl.primitive(Geometry::Kind::kBox, Eigen::Vector3d(2 * half_width, 2 * half_width, thickness));
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(slab);
    object->setWorldTransform(toBt(Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.5 * thickness))));
    object->setUserIndex(-1);
    impl.table = static_cast<int>(impl.obstacle_objects.size());
    object->setUserIndex2(impl.table);
    impl.world.addCollisionObject(object.get(), 8, 1);
    impl.obstacle_objects.push_back(std::move(object));
    const bool taken = std::find(obstacle_names_.begin(), obstacle_names_.end(), "table") != obstacle_names_.end();
    obstacle_names_.emplace_back(taken ? "table (z = 0)" : "table");
  }
  impl.contacts.reserve(64);

  update(model.midPosture());
  bool dropped = false;
  for (const Contact& contact : contacts()) {
    if (contact.isSelfCollision()) {
      impl.checked_pairs[static_cast<std::size_t>(contact.body * impl.bodies + contact.other_body)] = 0;
      impl.checked_pairs[static_cast<std::size_t>(contact.other_body * impl.bodies + contact.body)] = 0;
      dropped = true;
    }
  }
  if (impl.table >= 0) {
    // Like the base, a link no joint can raise or lower (every joint before it turns about a
    // vertical axis or slides along a horizontal one, a rail) keeps its height: it stands on the table in every posture or never
    // reaches it, and a gap to it that no motion can widen must not count as clearance. The
    // first moving link also stands on the table when it lies on (or within 1 cm of) it at the
    // reference posture, as a link reaching down to the mounting plate does; a link further
    // along the chain that the reference posture happens to put into the table does not.
    const auto& joints = model.joints();
    bool height_fixed = true;
    for (int b = 1; b < impl.bodies; ++b) {
      const Joint& joint = joints[static_cast<std::size_t>(b - 1)];
      const Eigen::Vector3d axis_W = impl.kinematics.X_WB(b).linear() * joint.axis_J;
      const bool keeps_height = joint.type == JointType::kPrismatic ? std::abs(axis_W.z()) < 1e-9 : std::abs(axis_W.z()) > 1.0 - 1e-9;
      height_fixed = height_fixed && keeps_height;
      if (height_fixed || (b == 1 && distance(b, impl.table, 0.02) < 0.01)) {
        impl.table_exempt[static_cast<std::size_t>(b)] = 1;
        dropped = true;
      }
    }
  }
  // A gap between the first link and an obstacle that its joint cannot change (a link round
  // about its own axis beside a fixture flush with the base, a tilted mount's first link over
  // the table) is no clearance a posture could win or lose: looked at over the joint's range.
  impl.fixed_gap.assign(static_cast<std::size_t>(obstacleCount()), 0);
  if (impl.bodies > 1 && model.joints().front().type != JointType::kPrismatic) {
    const double low = model.sampleLowerLimits()[0], high = model.sampleUpperLimits()[0];  // one turn if unbounded
    constexpr int kAngles = 24;
    constexpr double kNear = 0.1;  // [m] farther gaps never count against a clearance
    constexpr double kUnchanged = 0.005;  // [m] a link not quite round about its axis
    Eigen::VectorXd q = model.midPosture();
    std::vector<double> least(static_cast<std::size_t>(obstacleCount()), std::numeric_limits<double>::infinity());
    std::vector<double> most(least.size(), -std::numeric_limits<double>::infinity());
    for (int i = 0; i <= kAngles; ++i) {
      q[0] = low + (high - low) * i / kAngles;
      update(q);
      for (int k = 0; k < obstacleCount(); ++k) {
        if (k == impl.table && impl.table_exempt[1] != 0) continue;
        const double gap = distance(1, k, kNear);
        least[static_cast<std::size_t>(k)] = std::min(least[static_cast<std::size_t>(k)], gap);
        most[static_cast<std::size_t>(k)] = std::max(most[static_cast<std::size_t>(k)], gap);
      }
    }
    for (std::size_t k = 0; k < least.size(); ++k) {
      if (least[k] > 0.0 && least[k] < kNear && most[k] - least[k] < kUnchanged) impl.fixed_gap[k] = 1;
    }
    update(model.midPosture());
  }
  if (dropped) {
    // Re-adding the links rebuilds their broadphase pairs through the filter.
    for (int b = 0; b < impl.bodies; ++b) {
      btCollisionObject* object = impl.body_objects[static_cast<std::size_t>(b)].get();
      const int group = object->getBroadphaseHandle()->m_collisionFilterGroup;
      int mask = object->getBroadphaseHandle()->m_collisionFilterMask;
      if (impl.table_exempt[static_cast<std::size_t>(b)] != 0) mask &= ~8;
      impl.world.removeCollisionObject(object);
      impl.world.addCollisionObject(object, group, mask);
    }
  }
}

CollisionWorld::~CollisionWorld() {
  if (!impl_) return;
  for (auto& object : impl_->body_objects) impl_->world.removeCollisionObject(object.get());
  for (auto& object : impl_->obstacle_objects) impl_->world.removeCollisionObject(object.get());
}

const std::string& CollisionWorld::bodyName(int body) const { return model_->bodies()[static_cast<std::size_t>(body)].name; }

bool CollisionWorld::selfPairChecked(int body_a, int body_b) const {
  if (body_a < 0 || body_b < 0 || body_a >= impl_->bodies || body_b >= impl_->bodies) return false;
  return impl_->checked_pairs[static_cast<std::size_t>(body_a * impl_->bodies + body_b)] != 0;
}

const std::string& CollisionWorld::bodyShapeSource(int body) const {
  return impl_->shape_source[static_cast<std::size_t>(body)];
}

const std::string& CollisionWorld::otherName(const Contact& contact) const {
  return contact.isSelfCollision() ? bodyName(contact.other_body) : obstacleName(contact.obstacle);
}

void CollisionWorld::update(const Eigen::VectorXd& q) {
  impl_->kinematics.update(q);
  for (int b = 0; b < impl_->bodies; ++b) {
    impl_->body_objects[static_cast<std::size_t>(b)]->setWorldTransform(toBt(impl_->kinematics.X_WB(b)));
  }
  impl_->world.updateAabbs();
}

namespace {

struct ClosestCollector : btCollisionWorld::ContactResultCallback {
  double distance = std::numeric_limits<double>::infinity();
  btVector3 on_first, on_second;
  const btCollisionObject* first = nullptr;
  btScalar addSingleResult(btManifoldPoint& point, const btCollisionObjectWrapper* a, int, int,
                           const btCollisionObjectWrapper*, int, int) override {
    if (double(point.getDistance()) < distance) {
      distance = double(point.getDistance());
      const bool a_first = a->getCollisionObject() == first;
      on_first = a_first ? point.getPositionWorldOnA() : point.getPositionWorldOnB();
      on_second = a_first ? point.getPositionWorldOnB() : point.getPositionWorldOnA();
    }
    return 0;
  }
};

}  // namespace

const std::vector<Contact>& CollisionWorld::contacts() {
  // Cached pair algorithms make repeated queries cheap. Their persistent manifolds would carry
  // contact points of earlier postures into this one (Bullet refreshes a kept point by its old
  // normal), so a marginal contact would depend on what was asked before: each query starts
  // from empty manifolds.
  btDispatcher& dispatcher = *impl_->world.getDispatcher();
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) dispatcher.getManifoldByIndexInternal(m)->clearManifold();
  impl_->world.performDiscreteCollisionDetection();
  impl_->contacts.clear();
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
    int deepest = -1;
    for (int p = 0; p < manifold->getNumContacts(); ++p) {
      if (manifold->getContactPoint(p).getDistance() < 0 &&
          (deepest < 0 || manifold->getContactPoint(p).getDistance() < manifold->getContactPoint(deepest).getDistance())) {
        deepest = p;
      }
    }
    if (deepest < 0) continue;
    const btManifoldPoint& point = manifold->getContactPoint(deepest);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    // The robot side first; for two links, the lower index first.
    bool swap = a->getUserIndex() < 0 || (b->getUserIndex() >= 0 && b->getUserIndex() < a->getUserIndex());
    if (swap) std::swap(a, b);
    Contact contact;
    contact.body = a->getUserIndex();
    contact.depth = -double(point.getDistance());
    contact.p_W = toEigen(swap ? point.getPositionWorldOnB() : point.getPositionWorldOnA());
    if (b->getUserIndex() >= 0) {
      contact.other_body = b->getUserIndex();
      if (!selfPairChecked(contact.body, contact.other_body)) continue;
    } else {
      contact.obstacle = b->getUserIndex2();
    }
    bool merged = false;
    for (Contact& existing : impl_->contacts) {
      if (existing.body == contact.body && existing.other_body == contact.other_body && existing.obstacle == contact.obstacle) {
        if (contact.depth > existing.depth) existing = contact;
        merged = true;
        break;
      }
    }
    if (!merged) impl_->contacts.push_back(contact);
  }
  // The manifolds' order is that in which the broadphase met the pairs, i.e. history; the
  // deepest contact first is the one worth naming (a tie: the lower link, then the obstacle).
  std::sort(impl_->contacts.begin(), impl_->contacts.end(), [](const Contact& a, const Contact& b) {
    return std::tie(b.depth, a.body, a.obstacle, a.other_body) < std::tie(a.depth, b.body, b.obstacle, b.other_body);
  });
  return impl_->contacts;
}

double CollisionWorld::distance(int body, int obstacle, double max_distance) {
  if (body <= 0 || body >= impl_->bodies || obstacle < 0 || obstacle >= obstacleCount() ||
      (obstacle == impl_->table && impl_->table_exempt[static_cast<std::size_t>(body)] != 0)) {
    return std::numeric_limits<double>::infinity();
  }
  ClosestCollector collector;
  collector.m_closestDistanceThreshold = btScalar(max_distance);
  collector.first = impl_->body_objects[static_cast<std::size_t>(body)].get();
  impl_->world.contactPairTest(impl_->body_objects[static_cast<std::size_t>(body)].get(),
                               impl_->obstacle_objects[static_cast<std::size_t>(obstacle)].get(), collector);
  return collector.distance;
}

double CollisionWorld::selfClearance(int min_separation, double max_distance) {
  double closest = std::numeric_limits<double>::infinity();
  for (int a = 0; a < impl_->bodies; ++a) {
    for (int b = a + std::max(2, min_separation); b < impl_->bodies; ++b) {
      if (!selfPairChecked(a, b)) continue;
      ClosestCollector collector;
      collector.m_closestDistanceThreshold = btScalar(max_distance);
      collector.first = impl_->body_objects[static_cast<std::size_t>(a)].get();
      impl_->world.contactPairTest(impl_->body_objects[static_cast<std::size_t>(a)].get(),
                                   impl_->body_objects[static_cast<std::size_t>(b)].get(), collector);
      closest = std::min(closest, collector.distance);
    }
  }
  return closest;
}

Clearance CollisionWorld::clearance(double max_distance) {
  Clearance best;
  best.distance = std::numeric_limits<double>::infinity();
  for (int b = 1; b < impl_->bodies; ++b) {
    for (int k = 0; k < obstacleCount(); ++k) {
      if (k == impl_->table && impl_->table_exempt[static_cast<std::size_t>(b)] != 0) continue;
      if (b == 1 && impl_->fixed_gap[static_cast<std::size_t>(k)] != 0) continue;
      ClosestCollector collector;
      collector.m_closestDistanceThreshold = btScalar(max_distance);
      collector.first = impl_->body_objects[static_cast<std::size_t>(b)].get();
      impl_->world.contactPairTest(impl_->body_objects[static_cast<std::size_t>(b)].get(),
                                   impl_->obstacle_objects[static_cast<std::size_t>(k)].get(), collector);
      if (collector.distance < best.distance) {
        best.distance = collector.distance;
        best.body = b;
        best.obstacle = k;
        best.p_body_W = toEigen(collector.on_first);
        best.p_obstacle_W = toEigen(collector.on_second);
      }
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------
void CollisionMonitor::observe(const std::vector<Contact>& contacts, double time) {
  next_.clear();
  for (const Contact& contact : contacts) {
    const std::pair<int, int> key{contact.body, contact.isSelfCollision() ? contact.other_body : -(contact.obstacle + 1)};
    next_.push_back(key);
    if (std::find(touching_.begin(), touching_.end(), key) == touching_.end()) {
      ++event_count_;
      if (log_.size() < 1000) log_.push_back(Event{time, contact});
    }
  }
  if (!contacts.empty()) ++colliding_steps_;
  touching_.swap(next_);
}

void CollisionMonitor::reset() {
  touching_.clear();
  next_.clear();
  log_.clear();
  event_count_ = 0;
  colliding_steps_ = 0;
}

}  // namespace flexirob::robot
