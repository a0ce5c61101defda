#include "asg_sim/physics.hpp"

#include <BulletDynamics/Vehicle/btRaycastVehicle.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>

#include "asg_sim/meshes.hpp"

namespace asg_sim {

double VehicleState::yaw() const {
  const auto& q = orientation;
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}
double VehicleState::roll() const {
  const auto& q = orientation;
  return std::atan2(2.0 * (q.w() * q.x() + q.y() * q.z()), 1.0 - 2.0 * (q.x() * q.x() + q.y() * q.y()));
}
double VehicleState::pitch() const {
  const auto& q = orientation;
  return std::asin(std::clamp(2.0 * (q.w() * q.y() - q.z() * q.x()), -1.0, 1.0));
}
Eigen::Isometry3d VehicleState::pose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = orientation.toRotationMatrix();
  T.translation() = position;
  return T;
}

struct PhysicsWorld::Impl {
  // Creation order; torn down in reverse.
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<float> heights;
  std::unique_ptr<btHeightfieldTerrainShape> ground_shape;
  std::unique_ptr<btRigidBody> ground;
  std::vector<std::unique_ptr<btCollisionShape>> obstacle_shapes;
  std::vector<std::unique_ptr<btRigidBody>> obstacles;
  std::unique_ptr<btBoxShape> chassis_shape;
  std::unique_ptr<btDefaultMotionState> chassis_motion;
  std::unique_ptr<btRigidBody> chassis;
  std::unique_ptr<btDefaultVehicleRaycaster> raycaster;
  std::unique_ptr<btRaycastVehicle> vehicle;
  btRaycastVehicle::btVehicleTuning tuning;

  ~Impl() {
    if (vehicle) world.removeAction(vehicle.get());
    vehicle.reset();
    raycaster.reset();
    if (chassis) world.removeRigidBody(chassis.get());
    chassis.reset();
    chassis_motion.reset();
    chassis_shape.reset();
    for (auto it = obstacles.rbegin(); it != obstacles.rend(); ++it) world.removeRigidBody(it->get());
    obstacles.clear();
    obstacle_shapes.clear();
    if (ground) world.removeRigidBody(ground.get());
  }
};

PhysicsWorld::PhysicsWorld(const SceneSpec& spec, const std::vector<PlacedObstacle>& placed,
                           const VehicleParams& p)
    : impl_(new Impl), params_(p) {
  auto& w = impl_->world;
  w.setGravity(btVector3(0, 0, -9.81));

  // Ground: heightfield over the rendered area, sampled from the terrain at the rendered mesh's
  // vertices (the same cells), so the vehicle drives on the ground the camera sees.
  const auto& L = spec.landscape;
  const Terrain terrain(spec.terrain);
  const double lo = -L.border, hi = L.size + L.border;
  int n = std::max<int>(2, std::ceil(L.subdivisions * (hi - lo) / L.size) + 1);
  if (!terrain.flat()) n = std::min(n, kMaxTerrainCellsPerSide + 1);  // the rendered mesh's vertices
  const double cell = (hi - lo) / (n - 1);
  impl_->heights.resize(size_t(n) * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) impl_->heights[i * n + j] = terrain.height(lo + j * cell, lo + i * cell);
  const auto [hmin, hmax] = std::minmax_element(impl_->heights.begin(), impl_->heights.end());
  const double zmin = *hmin - 1.0, zmax = *hmax + 1.0;
  impl_->ground_shape.reset(new btHeightfieldTerrainShape(n, n, impl_->heights.data(), 1.0, zmin, zmax,
                                                          2, PHY_FLOAT, false));
  impl_->ground_shape->setLocalScaling(btVector3(cell, cell, 1.0));
  btTransform gt;
  gt.setIdentity();
  gt.setOrigin(btVector3((lo + hi) / 2, (lo + hi) / 2, (zmin + zmax) / 2));
  impl_->ground.reset(new btRigidBody(0.0, nullptr, impl_->ground_shape.get()));
  impl_->ground->setWorldTransform(gt);
  impl_->ground->setFriction(1.0);
  w.addRigidBody(impl_->ground.get());

  for (const auto& o : placed) {
    if (o.traversable) continue;  // driven over
    auto shape = std::make_unique<btCylinderShapeZ>(btVector3(o.radius, o.radius, o.height / 2));
    btTransform t;
    t.setIdentity();
    t.setOrigin(btVector3(o.pose.x, o.pose.y, o.z + o.height / 2));
    auto body = std::make_unique<btRigidBody>(0.0, nullptr, shape.get());
    body->setWorldTransform(t);
    body->setUserIndex(int(o.id));
    w.addRigidBody(body.get());
    impl_->obstacle_shapes.push_back(std::move(shape));
    impl_->obstacles.push_back(std::move(body));
  }

  // Vehicle
  const auto& op = spec.operational;
  impl_->chassis_shape.reset(
      new btBoxShape(btVector3(p.length / 2, p.width / 2, p.chassis_height / 2)));
  btVector3 inertia(0, 0, 0);
  impl_->chassis_shape->calculateLocalInertia(p.mass, inertia);
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(op.start_x, op.start_y,
                            terrain.height(op.start_x, op.start_y) + p.com_height));
  start.setRotation(btQuaternion(btVector3(0, 0, 1), op.start_yaw));
  impl_->chassis_motion.reset(new btDefaultMotionState(start));
  btRigidBody::btRigidBodyConstructionInfo info(p.mass, impl_->chassis_motion.get(),
                                                impl_->chassis_shape.get(), inertia);
  impl_->chassis.reset(new btRigidBody(info));
  impl_->chassis->setActivationState(DISABLE_DEACTIVATION);
  impl_->chassis->setDamping(p.linear_damping, 0.1);
  impl_->chassis->setUserIndex(-1);
  w.addRigidBody(impl_->chassis.get());

  impl_->raycaster.reset(new btDefaultVehicleRaycaster(&w));
  auto& tu = impl_->tuning;
  tu.m_suspensionStiffness = p.suspension_stiffness;
  tu.m_suspensionCompression = p.damping_compression;
  tu.m_suspensionDamping = p.damping_relaxation;
  tu.m_frictionSlip = p.friction_slip;
  tu.m_maxSuspensionTravelCm = 30.0;
  impl_->vehicle.reset(new btRaycastVehicle(tu, impl_->chassis.get(), impl_->raycaster.get()));
  impl_->vehicle->setCoordinateSystem(1, 2, 0);  // right y, up z, forward x
  w.addAction(impl_->vehicle.get());
  const btVector3 down(0, 0, -1), axle(0, -1, 0);
  const double connect_z = -(p.com_height - p.wheel_radius - p.suspension_rest + 0.082);  // rests with base_link on the ground
  for (int i = 0; i < 4; ++i) {
    const bool front = i < 2;
    const double x = front ? p.wheelbase / 2 : -p.wheelbase / 2;
    const double y = (i % 2 == 0) ? p.track / 2 : -p.track / 2;
    btWheelInfo& wheel = impl_->vehicle->addWheel(btVector3(x, y, connect_z), down, axle,
                                                  p.suspension_rest, p.wheel_radius, tu, front);
    wheel.m_rollInfluence = p.roll_influence;
  }
  impl_->vehicle->resetSuspension();
}

PhysicsWorld::~PhysicsWorld() = default;

void PhysicsWorld::setCommand(const Command& cmd) {
  auto clamp = [](double v, double lo, double hi) { return std::isfinite(v) ? std::clamp(v, lo, hi) : 0.0; };
  const double throttle = clamp(cmd.throttle, -1.0, 1.0);
  const double drive = throttle >= 0.0 ? throttle : throttle * params_.max_reverse_throttle;  // reverse gear
  const double brake = clamp(cmd.brake, 0.0, 1.0);
  steer_target_ = clamp(cmd.steering, -1.0, 1.0) * params_.max_steer;
  auto* v = impl_->vehicle.get();
  const double rolling = (throttle == 0.0 && brake == 0.0) ? params_.rolling_brake : 0.0;
  for (int i = 0; i < 4; ++i) {
    v->applyEngineForce(drive * params_.max_engine_force / 4.0, i);
    v->setBrake(brake * params_.max_brake + rolling, i);
  }
}

void PhysicsWorld::step(double dt, int substeps) {
  const double h = dt / substeps;
  for (int i = 0; i < substeps; ++i) {
    const double max_change = params_.max_steer_rate * h;
    steer_ += std::clamp(steer_target_ - steer_, -max_change, max_change);
    impl_->vehicle->setSteeringValue(steer_, 0);
    impl_->vehicle->setSteeringValue(steer_, 1);
    impl_->world.stepSimulation(h, 0);
  }
}

VehicleState PhysicsWorld::state() const {
  const btTransform& t = impl_->chassis->getWorldTransform();
  const btQuaternion q = t.getRotation();
  VehicleState s;
  s.orientation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
  const Eigen::Matrix3d R = s.orientation.toRotationMatrix();
  const btVector3& o = t.getOrigin();
  s.position = Eigen::Vector3d(o.x(), o.y(), o.z()) - R * Eigen::Vector3d(0, 0, params_.com_height);
  const btVector3& v = impl_->chassis->getLinearVelocity();
  const btVector3& w = impl_->chassis->getAngularVelocity();
  s.linear = R.transpose() * Eigen::Vector3d(v.x(), v.y(), v.z());
  s.angular = R.transpose() * Eigen::Vector3d(w.x(), w.y(), w.z());
  return s;
}

uint32_t PhysicsWorld::contactObstacle() const {
  auto& d = impl_->dispatcher;
  for (int i = 0; i < d.getNumManifolds(); ++i) {
    const btPersistentManifold* m = d.getManifoldByIndexInternal(i);
    const btCollisionObject* a = m->getBody0();
    const btCollisionObject* b = m->getBody1();
    const btCollisionObject* other = nullptr;
    if (a == impl_->chassis.get()) other = b;
    else if (b == impl_->chassis.get()) other = a;
    if (!other || other->getUserIndex() <= 0) continue;
    for (int c = 0; c < m->getNumContacts(); ++c)
      if (m->getContactPoint(c).getDistance() < 0.01) return uint32_t(other->getUserIndex());
  }
  return 0;
}

}  // namespace asg_sim
