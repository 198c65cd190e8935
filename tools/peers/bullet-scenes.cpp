// tools/peers/bullet-scenes.cpp -- the analytic scenes of physics.org (section "Engine beside
// engine", #P33R5X) run in Debian's Bullet, from the scene file; see scenes.h for the file,
// the command line and the record it writes.
//
// Build: g++ -O2 bullet-scenes.cpp $(pkg-config --cflags --libs bullet) -o bullet-scenes
//
// Knobs (KEY=VALUE after the fixed arguments), Bullet's defaults in brackets:
//   margin=M   collision margin of the static boxes [0.04]; 0 gives the cells' sharp edges
//   split=0|1  split impulse, which corrects overlap apart from the velocities [1]
//   erp2=F     the contacts' error reduction [0.2]
// Materials as this engine combines them (physics.org, "Prepare"): friction sqrt(mu_a mu_b)
// between balls and the ball's own against a box, restitution the larger of the two, rolling
// resistance the larger too; Bullet's rolling friction is a torque limit per unit normal
// impulse, so a ball's is its rolling resistance times its radius.  The restitution threshold
// is this engine's 1 m/s (Bullet's default 0.2).  Bodies sleep only when the run says so;
// no damping; one world step is stepSimulation(1/HZ, SUBSTEPS, 1/(HZ SUBSTEPS)).

#include <btBulletDynamicsCommon.h>

#include "scenes.h"

#include <algorithm>
#include <map>
#include <memory>

namespace {

bool is_static(const btCollisionObject* o) { return o->isStaticObject(); }

btScalar combine_friction(const btCollisionObject* a, const btCollisionObject* b) {
  if (is_static(a)) return b->getFriction();
  if (is_static(b)) return a->getFriction();
  return btSqrt(a->getFriction() * b->getFriction());
}

btScalar combine_restitution(const btCollisionObject* a, const btCollisionObject* b) {
  return std::max(a->getRestitution(), b->getRestitution());
}

btScalar combine_rolling(const btCollisionObject* a, const btCollisionObject* b) {
  return std::max(a->getRollingFriction(), b->getRollingFriction());
}

btScalar no_spinning(const btCollisionObject*, const btCollisionObject*) { return 0; }

void run_one(const SceneRun& run, const SceneArgs& args, std::vector<double>& out) {
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(run.gravity[0], run.gravity[1], run.gravity[2]));
  btContactSolverInfo& info = world.getSolverInfo();
  info.m_numIterations = args.iterations;
  info.m_splitImpulse = static_cast<int>(args.knob("split", 1));
  info.m_erp2 = args.knob("erp2", 0.2);
  info.m_restitutionVelocityThreshold = 1.0;
  const double margin = args.knob("margin", 0.04);

  auto add = [&](btCollisionShape* shape, double mass, const btVector3& at, const btVector3& v) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btTransform t;
    t.setIdentity();
    t.setOrigin(at);
    states.emplace_back(new btDefaultMotionState(t));
    btRigidBody::btRigidBodyConstructionInfo ci(mass, states.back().get(), shape, inertia);
    bodies.emplace_back(new btRigidBody(ci));
    btRigidBody* body = bodies.back().get();
    body->setLinearVelocity(v);
    if (!run.sleep) body->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(body);
    return body;
  };

  for (const SceneBox& b : run.boxes) {
    shapes.emplace_back(new btBoxShape(btVector3((b.x1 - b.x0) / 2, (b.y1 - b.y0) / 2, (b.z1 - b.z0) / 2)));
    shapes.back()->setMargin(margin);
    btRigidBody* box = add(shapes.back().get(), 0, btVector3((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, (b.z0 + b.z1) / 2),
                           btVector3(0, 0, 0));
    box->setFriction(1);
    box->setRestitution(0);
    box->setRollingFriction(0);
  }
  std::map<double, btCollisionShape*> spheres;
  std::vector<btRigidBody*> balls;
  for (const SceneBall& b : run.balls) {
    btCollisionShape*& sphere = spheres[b.r];
    if (!sphere) {
      shapes.emplace_back(new btSphereShape(b.r));
      sphere = shapes.back().get();
    }
    btRigidBody* body = add(sphere, b.m, btVector3(b.x, b.y, b.z), btVector3(b.vx, b.vy, b.vz));
    body->setFriction(b.mu);
    body->setRestitution(b.e);
    body->setRollingFriction(b.rho * b.r);
    body->setSpinningFriction(0);
    body->setAngularVelocity(btVector3(b.wx, b.wy, b.wz));
    balls.push_back(body);
  }

  const btScalar dt = 1.0 / args.hz;
  auto step = [&] { world.stepSimulation(dt, args.substeps, dt / args.substeps); };
  auto state = [&](size_t i, double* s) {
    const btRigidBody* b = balls[i];
    const btVector3& p = b->getCenterOfMassPosition();
    const btVector3& v = b->getLinearVelocity();
    const btVector3& w = b->getAngularVelocity();
    double values[9] = {p.x(), p.y(), p.z(), v.x(), v.y(), v.z(), w.x(), w.y(), w.z()};
    std::copy(values, values + 9, s);
  };
  scene_drive(run, args, step, state, out);
  for (auto& body : bodies) world.removeRigidBody(body.get());
}

}  // namespace

int main(int argc, char** argv) {
  const SceneArgs args = scene_args("bullet-scenes", argc, argv);
  gCalculateCombinedFrictionCallback = combine_friction;
  gCalculateCombinedRestitutionCallback = combine_restitution;
  gCalculateCombinedRollingFrictionCallback = combine_rolling;
  gCalculateCombinedSpinningFrictionCallback = no_spinning;
  std::vector<double> out;
  for (const SceneRun& run : read_scene("bullet-scenes", args)) run_one(run, args, out);
  scene_write("bullet-scenes", args, out);
  return 0;
}
