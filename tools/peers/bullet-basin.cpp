// tools/peers/bullet-basin.cpp -- the basin scene of physics.org (section "The basin",
// #B4S1NS) built in Bullet, stepped and timed like measure-basin (#B3NCH5).
//
// Build: g++ -O2 bullet-basin.cpp $(pkg-config --cflags --libs bullet) -o bullet-basin
// Usage: bullet-basin [BALLS=3000] [STEPS=300] [FROM=120] [ITERATIONS=10]
//
// Prints one line:
//   bullet balls=N steps=S from=F iterations=I mean_ms=.. median_ms=.. manifolds=..
//          touching=.. points=.. mean_y=.. min_y=.. escaped=..
// mean_ms and median_ms: milliseconds per stepSimulation over steps FROM..STEPS-1 (steady_clock);
// manifolds: Bullet's persistent manifolds after the last step, touching: those holding at least
// one point, points: contact points in them; mean_y, min_y: mean and lowest height of the ball
// centres (0.25 for a ball resting on the floor); escaped: balls whose centre lies outside the
// interior [0,8] x [0,8] or below the floor's top (y < 0).
//
// The scene, as make-basin-world builds it (y up): a floor box x, z in [-8,16], y in [-1,0];
// walls one unit thick around the interior [0,8) x [0,8), from y = 0 to 6 (30 above 3000 balls);
// balls of radius 0.25 m, mass 1 kg, friction 0.6, restitution 0, rolling friction 0, on the
// lattice and jitter of basin-spawn-point; nothing sleeps; gravity (0,-9.81,0); one thread;
// stepSimulation(1/60, 0): one 1/60 s step, no internal substeps.  Friction combines as
// sqrt(a b), as in our engine, with the static boxes at 0.6, so every contact has friction 0.6
// (Bullet's default would be the product: 0.36 between balls).

#include <btBulletDynamicsCommon.h>

#include "basin.h"

#include <cstdio>
#include <memory>
#include <vector>

namespace {

btVector3 spawn_point(int i) {
  float p[3];
  basin_spawn_point(i, p);
  return btVector3(p[0], p[1], p[2]);
}

btScalar combine_friction(const btCollisionObject* a, const btCollisionObject* b) {
  return btSqrt(a->getFriction() * b->getFriction());
}

}  // namespace

int main(int argc, char** argv) {
  const BasinArgs args = basin_args("bullet-basin", argc, argv);
  const int balls = args.balls, steps = args.steps, from = args.from, iterations = args.iterations;

  gCalculateCombinedFrictionCallback = combine_friction;

  // declared before the world, so that they outlive it
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btMotionState>> states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;

  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, -9.81f, 0));
  world.getSolverInfo().m_numIterations = iterations;

  auto add_body = [&](btCollisionShape* shape, btScalar mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btTransform t;
    t.setIdentity();
    t.setOrigin(at);
    states.emplace_back(new btDefaultMotionState(t));
    btRigidBody::btRigidBodyConstructionInfo info(mass, states.back().get(), shape, inertia);
    info.m_friction = 0.6f;
    info.m_restitution = 0.0f;
    info.m_rollingFriction = 0.0f;
    bodies.emplace_back(new btRigidBody(info));
    btRigidBody* body = bodies.back().get();
    body->setSleepingThresholds(0, 0);
    body->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(body);
    return body;
  };

  // the floor and walls: static boxes
  for (const BasinBox& b : basin_boxes(balls)) {
    shapes.emplace_back(new btBoxShape(btVector3((b.x1 - b.x0) / 2, (b.y1 - b.y0) / 2, (b.z1 - b.z0) / 2)));
    add_body(shapes.back().get(), 0, btVector3((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, (b.z0 + b.z1) / 2));
  }

  shapes.emplace_back(new btSphereShape(0.25f));
  btCollisionShape* sphere = shapes.back().get();
  std::vector<btRigidBody*> spheres;
  for (int i = 0; i < balls; ++i) spheres.push_back(add_body(sphere, 1.0f, spawn_point(i)));

  BasinTimes times;
  for (int i = 0; i < steps; ++i) {
    if (i >= from)
      times.time([&] { world.stepSimulation(1 / 60.0f, 0); });
    else
      world.stepSimulation(1 / 60.0f, 0);
  }

  int manifolds = dispatcher.getNumManifolds(), touching = 0, points = 0;
  for (int m = 0; m < manifolds; ++m) {
    int c = dispatcher.getManifoldByIndexInternal(m)->getNumContacts();
    points += c;
    if (c > 0) ++touching;
  }

  BasinPile pile;
  for (btRigidBody* b : spheres) {
    const btVector3& p = b->getCenterOfMassPosition();
    pile.add(p.x(), p.y(), p.z());
  }

  std::printf("bullet balls=%d steps=%d from=%d iterations=%d mean_ms=%.3f median_ms=%.3f "
              "manifolds=%d touching=%d points=%d mean_y=%.3f min_y=%.3f escaped=%d\n",
              balls, steps, from, iterations, times.mean(), times.median(), manifolds, touching,
              points, pile.mean_y(), pile.lowest_y(), pile.escaped);
  return 0;
}
