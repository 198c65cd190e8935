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

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

namespace {

// basin-spawn-point's jitter: a fixed integer hash of (i, salt) mapped into [-0.025, 0.025]
float jitter(uint64_t i, uint64_t salt) {
  uint64_t h = ((i * 7919u + salt * 104729u + 12345u) * 2654435761u) & 0xFFFFFFFFu;
  return 0.025f * (2.0f * (static_cast<float>((h >> 8) & 0xFFFFu) / 65535.0f) - 1.0f);
}

btVector3 spawn_point(int i) {
  int layer = i / 196, k = i % 196, row = k / 14, col = k % 14;
  return btVector3(0.3f + 0.55f * col + jitter(i, 1),
                   0.5f + 0.55f * layer + jitter(i, 2),
                   0.3f + 0.55f * row + jitter(i, 3));
}

btScalar combine_friction(const btCollisionObject* a, const btCollisionObject* b) {
  return btSqrt(a->getFriction() * b->getFriction());
}

int arg(int argc, char** argv, int n, int fallback) {
  if (argc <= n) return fallback;
  char* end = nullptr;
  long v = std::strtol(argv[n], &end, 10);
  if (*end != '\0' || v < 0) {
    std::fprintf(stderr, "bullet-basin: argument %d is not a count: %s\n", n, argv[n]);
    std::exit(2);
  }
  return static_cast<int>(v);
}

}  // namespace

int main(int argc, char** argv) {
  const int balls = arg(argc, argv, 1, 3000);
  const int steps = arg(argc, argv, 2, 300);
  const int from = arg(argc, argv, 3, 120);
  const int iterations = arg(argc, argv, 4, 10);
  if (from >= steps) {
    std::fprintf(stderr, "bullet-basin: FROM (%d) must be below STEPS (%d)\n", from, steps);
    return 2;
  }

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

  // a static box covering [x0,x1] x [y0,y1] x [z0,z1]
  auto add_box = [&](float x0, float y0, float z0, float x1, float y1, float z1) {
    shapes.emplace_back(new btBoxShape(btVector3((x1 - x0) / 2, (y1 - y0) / 2, (z1 - z0) / 2)));
    add_body(shapes.back().get(), 0, btVector3((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2));
  };

  const float wall = balls > 3000 ? 30 : 6;
  add_box(-8, -1, -8, 16, 0, 16);       // floor
  add_box(-1, 0, -1, 9, wall, 0);       // z in [-1,0), x in [-1,9)
  add_box(-1, 0, 8, 9, wall, 9);        // z in [8,9),  x in [-1,9)
  add_box(-1, 0, 0, 0, wall, 8);        // x in [-1,0), z in [0,8)
  add_box(8, 0, 0, 9, wall, 8);         // x in [8,9),  z in [0,8)

  shapes.emplace_back(new btSphereShape(0.25f));
  btCollisionShape* sphere = shapes.back().get();
  std::vector<btRigidBody*> spheres;
  for (int i = 0; i < balls; ++i) spheres.push_back(add_body(sphere, 1.0f, spawn_point(i)));

  std::vector<double> times;
  for (int i = 0; i < steps; ++i) {
    auto start = std::chrono::steady_clock::now();
    world.stepSimulation(1 / 60.0f, 0);
    auto end = std::chrono::steady_clock::now();
    if (i >= from) times.push_back(std::chrono::duration<double, std::milli>(end - start).count());
  }

  double mean = 0;
  for (double t : times) mean += t;
  mean /= times.size();
  std::sort(times.begin(), times.end());
  size_t n = times.size();
  double median = n % 2 ? times[n / 2] : (times[n / 2 - 1] + times[n / 2]) / 2;

  int manifolds = dispatcher.getNumManifolds(), touching = 0, points = 0;
  for (int m = 0; m < manifolds; ++m) {
    int c = dispatcher.getManifoldByIndexInternal(m)->getNumContacts();
    points += c;
    if (c > 0) ++touching;
  }

  double sum_y = 0, min_y = balls ? 1e30 : 0;
  int escaped = 0;
  for (btRigidBody* b : spheres) {
    const btVector3& p = b->getCenterOfMassPosition();
    sum_y += p.y();
    min_y = std::min(min_y, static_cast<double>(p.y()));
    if (p.x() < 0 || p.x() > 8 || p.z() < 0 || p.z() > 8 || p.y() < 0) ++escaped;
  }

  std::printf("bullet balls=%d steps=%d from=%d iterations=%d mean_ms=%.3f median_ms=%.3f "
              "manifolds=%d touching=%d points=%d mean_y=%.3f min_y=%.3f escaped=%d\n",
              balls, steps, from, iterations, mean, median, manifolds, touching, points,
              balls ? sum_y / balls : 0.0, min_y, escaped);
  return 0;
}
