// tools/peers/ode-scenes.cpp -- the analytic scenes of physics.org (section "Engine beside
// engine", #P33R5X) run in Debian's Open Dynamics Engine (0.16, double precision), from the
// scene file; see scenes.h for the file, the command line and the record it writes.
//
// Build: g++ -O2 ode-scenes.cpp $(pkg-config --cflags --libs ode) -o ode-scenes
//
// Knobs (KEY=VALUE after the fixed arguments), ODE's defaults in brackets:
//   solver=quick|step  dWorldQuickStep with ITERATIONS iterations, or dWorldStep, the big
//                      matrix solver that ignores ITERATIONS [quick]
//   erp=F cfm=F        the world's error reduction and constraint force mixing [0.2, 1e-10]
// Each contact: dContactApprox1 (a friction pyramid scaled by the normal force) with mu as this
// engine combines it (sqrt(mu_a mu_b) between balls, the ball's own against a box);
// dContactBounce with the larger restitution and bounce_vel 1 m/s, this engine's restitution
// threshold; dContactRolling with rho = rho2 = the larger rolling resistance times the ball's
// radius (ODE's rolling friction is a torque per unit normal force), rhoN 0 (no spin friction).
// A box is a geom without a body.  Auto-disable (sleep) only when the run says so.  A world
// step is SUBSTEPS steps of 1/(HZ SUBSTEPS), each with its own collision.

#include <ode/ode.h>

#include "scenes.h"

#include <algorithm>
#include <cmath>

namespace {

struct Scene {
  dWorldID world;
  dJointGroupID contacts;
  const std::vector<SceneBall>* balls;
};

void near_callback(void* data, dGeomID o1, dGeomID o2) {
  Scene* scene = static_cast<Scene*>(data);
  dBodyID b1 = dGeomGetBody(o1), b2 = dGeomGetBody(o2);
  if (!b1 && !b2) return;
  dContactGeom geoms[4];
  int n = dCollide(o1, o2, 4, geoms, sizeof(dContactGeom));
  if (n == 0) return;
  const SceneBall* a = b1 ? &(*scene->balls)[reinterpret_cast<size_t>(dGeomGetData(o1))] : nullptr;
  const SceneBall* b = b2 ? &(*scene->balls)[reinterpret_cast<size_t>(dGeomGetData(o2))] : nullptr;
  double mu = a && b ? std::sqrt(a->mu * b->mu) : (a ? a->mu : b->mu);
  double e = std::max(a ? a->e : 0.0, b ? b->e : 0.0);
  double rho = std::max(a ? a->rho * a->r : 0.0, b ? b->rho * b->r : 0.0);
  for (int i = 0; i < n; ++i) {
    dContact c;
    std::memset(&c, 0, sizeof c);
    c.surface.mode = dContactApprox1 | dContactBounce;
    c.surface.mu = mu;
    c.surface.bounce = e;
    c.surface.bounce_vel = 1.0;
    if (rho > 0) {
      c.surface.mode |= dContactRolling | dContactAxisDep;
      c.surface.mu2 = mu;
      c.surface.rho = c.surface.rho2 = rho;
      c.surface.rhoN = 0;
    }
    c.geom = geoms[i];
    dJointID j = dJointCreateContact(scene->world, scene->contacts, &c);
    dJointAttach(j, b1, b2);
  }
}

void run_one(const SceneRun& run, const SceneArgs& args, std::vector<double>& out) {
  dWorldID world = dWorldCreate();
  dWorldSetGravity(world, run.gravity[0], run.gravity[1], run.gravity[2]);
  dWorldSetERP(world, args.knob("erp", 0.2));
  dWorldSetCFM(world, args.knob("cfm", 1e-10));
  dWorldSetAutoDisableFlag(world, run.sleep);
  dWorldSetQuickStepNumIterations(world, args.iterations);
  const bool quick = !(args.knobs.count("solver") && args.knobs.at("solver") == "step");
  dSpaceID space = dHashSpaceCreate(0);
  Scene scene = {world, dJointGroupCreate(0), &run.balls};
  for (const SceneBox& b : run.boxes) {
    dGeomID g = dCreateBox(space, b.x1 - b.x0, b.y1 - b.y0, b.z1 - b.z0);
    dGeomSetPosition(g, (b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, (b.z0 + b.z1) / 2);
  }
  std::vector<dBodyID> balls;
  for (size_t i = 0; i < run.balls.size(); ++i) {
    const SceneBall& s = run.balls[i];
    dMass mass;
    dMassSetSphereTotal(&mass, s.m, s.r);
    dBodyID b = dBodyCreate(world);
    dBodySetMass(b, &mass);
    dBodySetPosition(b, s.x, s.y, s.z);
    dBodySetLinearVel(b, s.vx, s.vy, s.vz);
    dBodySetAngularVel(b, s.wx, s.wy, s.wz);
    dGeomID g = dCreateSphere(space, s.r);
    dGeomSetData(g, reinterpret_cast<void*>(i));
    dGeomSetBody(g, b);
    balls.push_back(b);
  }
  const double h = 1.0 / (args.hz * args.substeps);
  auto step = [&] {
    for (int k = 0; k < args.substeps; ++k) {
      dSpaceCollide(space, &scene, near_callback);
      if (quick)
        dWorldQuickStep(world, h);
      else
        dWorldStep(world, h);
      dJointGroupEmpty(scene.contacts);
    }
  };
  auto state = [&](size_t i, double* s) {
    const dReal* p = dBodyGetPosition(balls[i]);
    const dReal* v = dBodyGetLinearVel(balls[i]);
    const dReal* w = dBodyGetAngularVel(balls[i]);
    double values[9] = {p[0], p[1], p[2], v[0], v[1], v[2], w[0], w[1], w[2]};
    std::copy(values, values + 9, s);
  };
  scene_drive(run, args, step, state, out);
  dJointGroupDestroy(scene.contacts);
  dSpaceDestroy(space);
  dWorldDestroy(world);
}

}  // namespace

int main(int argc, char** argv) {
  const SceneArgs args = scene_args("ode-scenes", argc, argv);
  dInitODE2(0);
  std::vector<double> out;
  for (const SceneRun& run : read_scene("ode-scenes", args)) run_one(run, args, out);
  scene_write("ode-scenes", args, out);
  dCloseODE();
  return 0;
}
