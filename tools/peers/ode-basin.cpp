// tools/peers/ode-basin.cpp -- the basin scene of physics.org (section "The basin", #B4S1NS)
// built in the Open Dynamics Engine (ODE), stepped and timed like measure-basin (#B3NCH5) and
// like tools/peers/bullet-basin.cpp.
//
// Build: g++ -O2 ode-basin.cpp $(pkg-config --cflags --libs ode) -o ode-basin
// Usage: ode-basin [BALLS=3000] [STEPS=300] [FROM=120] [ITERATIONS=10]
//
// Prints one line:
//   ode balls=N steps=S from=F iterations=I precision=P space=K mean_ms=.. median_ms=..
//       contacts=.. mean_y=.. min_y=.. escaped=..
// precision: single or double, as ODE's headers were built (Debian's libode-dev 0.16.2 is
// double: its ode/precision.h defines dDOUBLE); space: the broad phase (below); mean_ms and
// median_ms: milliseconds per full step -- dSpaceCollide, dWorldQuickStep, dJointGroupEmpty --
// over steps FROM..STEPS-1 (steady_clock); contacts: contact joints created in the last step;
// mean_y, min_y: mean and lowest height of the ball centres (0.25 for a ball resting on the
// floor); escaped: balls whose centre lies outside the interior [0,8] x [0,8] or below the
// floor's top (y < 0).
//
// The scene, as make-basin-world builds it (y up): a floor box x, z in [-8,16], y in [-1,0];
// walls one unit thick around the interior [0,8) x [0,8), from y = 0 to 6 (30 above 3000 balls),
// all static geoms without bodies; balls of radius 0.25 m, mass 1 kg (dMassSetSphereTotal), on
// the lattice and jitter of basin-spawn-point; gravity (0,-9.81,0); no auto-disable (nothing
// sleeps); one thread (no threading implementation attached to the world); 60 Hz.
//
// ODE used as one usually drives it for piles:
//   - broad phase: a dHashSpace with ODE's default levels (cells 2^-3 .. 2^10), not a
//     dQuadTreeSpace, which splits only x and y (ODE's z-up plane) and so suits this y-up
//     scene badly;
//   - dSpaceCollide with a near callback that skips pairs of static geoms and calls
//     dCollide(o1, o2, 4, ...): sphere-sphere and sphere-box give at most one contact each;
//     every contact becomes a dJointCreateContact in one dJointGroup, emptied after the step;
//   - contact surface: mode dContactApprox1 (friction pyramid scaled by the normal force),
//     mu 0.6, no dContactBounce (restitution 0), no soft_erp/soft_cfm of its own;
//   - world: dWorldSetERP 0.2, dWorldSetCFM 1e-5 (ODE's defaults for single precision; the
//     double build's default CFM is 1e-10), contact max correcting velocity and contact
//     surface layer left at ODE's defaults (unbounded, 0);
//   - dWorldQuickStep(world, 1/60) with dWorldSetQuickStepNumIterations(ITERATIONS), 10 by
//     default, like Bullet's 10 solver iterations; dWorldSetAutoDisableFlag(0).

#include <ode/ode.h>

#include "basin.h"

#include <cstdio>
#include <vector>

namespace {

const int kMaxContacts = 4;  // per pair; sphere-sphere and sphere-box produce at most 1

struct Scene {
  dWorldID world;
  dJointGroupID contacts;
  int created;  // contact joints created in this step
};

void near_callback(void* data, dGeomID o1, dGeomID o2) {
  Scene* scene = static_cast<Scene*>(data);
  dBodyID b1 = dGeomGetBody(o1), b2 = dGeomGetBody(o2);
  if (!b1 && !b2) return;  // floor and walls: static against static
  dContactGeom geoms[kMaxContacts];
  int n = dCollide(o1, o2, kMaxContacts, geoms, sizeof(dContactGeom));
  for (int i = 0; i < n; ++i) {
    dContact c = {};
    c.surface.mode = dContactApprox1;
    c.surface.mu = 0.6;
    c.geom = geoms[i];
    dJointID j = dJointCreateContact(scene->world, scene->contacts, &c);
    dJointAttach(j, b1, b2);
  }
  scene->created += n;
}

}  // namespace

int main(int argc, char** argv) {
  const BasinArgs args = basin_args("ode-basin", argc, argv);
  const int balls = args.balls, steps = args.steps, from = args.from, iterations = args.iterations;

  dInitODE2(0);
  dWorldID world = dWorldCreate();
  dWorldSetGravity(world, 0, -9.81, 0);
  dWorldSetERP(world, 0.2);
  dWorldSetCFM(world, 1e-5);
  dWorldSetAutoDisableFlag(world, 0);
  dWorldSetQuickStepNumIterations(world, iterations);

  const char* space_name = "hash";
  dSpaceID space = dHashSpaceCreate(0);
  Scene scene = {world, dJointGroupCreate(0), 0};

  // the floor and walls: static boxes without bodies
  for (const BasinBox& b : basin_boxes(balls)) {
    dGeomID g = dCreateBox(space, b.x1 - b.x0, b.y1 - b.y0, b.z1 - b.z0);
    dGeomSetPosition(g, (b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, (b.z0 + b.z1) / 2);
  }

  std::vector<dBodyID> spheres;
  dMass mass;
  dMassSetSphereTotal(&mass, 1.0, 0.25);
  for (int i = 0; i < balls; ++i) {
    float p[3];
    basin_spawn_point(i, p);
    dBodyID b = dBodyCreate(world);
    dBodySetMass(b, &mass);
    dBodySetPosition(b, p[0], p[1], p[2]);
    dGeomSetBody(dCreateSphere(space, 0.25), b);
    spheres.push_back(b);
  }

  auto step = [&] {
    scene.created = 0;
    dSpaceCollide(space, &scene, near_callback);
    dWorldQuickStep(world, 1 / 60.0);
    dJointGroupEmpty(scene.contacts);
  };
  BasinTimes times;
  for (int i = 0; i < steps; ++i) {
    if (i >= from)
      times.time(step);
    else
      step();
  }

  BasinPile pile;
  for (dBodyID b : spheres) {
    const dReal* p = dBodyGetPosition(b);
    pile.add(p[0], p[1], p[2]);
  }

#ifdef dDOUBLE
  const char* precision = "double";
#else
  const char* precision = "single";
#endif
  std::printf("ode balls=%d steps=%d from=%d iterations=%d precision=%s space=%s mean_ms=%.3f "
              "median_ms=%.3f contacts=%d mean_y=%.3f min_y=%.3f escaped=%d\n",
              balls, steps, from, iterations, precision, space_name, times.mean(), times.median(),
              scene.created, pile.mean_y(), pile.lowest_y(), pile.escaped);

  dJointGroupDestroy(scene.contacts);
  dSpaceDestroy(space);
  dWorldDestroy(world);
  dCloseODE();
  return 0;
}
