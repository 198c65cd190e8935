// tools/peers/box3d-scenes.cpp -- the analytic scenes of physics.org (section "Engine beside
// engine", #P33R5X) run in Box3D (github.com/erincatto/box3d, built from the source that
// BOX3D_SRC names, single precision, one worker), from the scene file; see scenes.h for the
// file, the command line and the record it writes.
//
// Build (make report-peers BOX3D_SRC=...): the C sources of $BOX3D_SRC/src compiled with
// -O2 -DNDEBUG, then g++ -O2 box3d-scenes.cpp -I$BOX3D_SRC/include with those objects.
//
// Box3D is Box2D v3's soft step in 3D, as this engine's step is: SUBSTEPS are its substeps,
// ITERATIONS is ignored (it relaxes once per substep).  Materials: Box3D mixes friction as
// sqrt(mu_a mu_b), restitution as the larger and rolling resistance as the larger times the
// radius, as this engine does; a box's material is set to give the ball's own (friction 1 is
// not that: sqrt(mu 1) = sqrt(mu), so the friction callback returns the ball's alone when the
// other is a box, marked by the user material id 1).  The restitution threshold is this
// engine's 1 m/s.  Sleep only when the run says so.  Boxes are static box hulls.

#include <box3d/box3d.h>

#include "scenes.h"

#include <algorithm>
#include <cmath>

namespace {

float mix_friction(float a, uint64_t ida, float b, uint64_t idb) {
  if (ida == 1) return b;
  if (idb == 1) return a;
  return std::sqrt(a * b);
}

float mix_restitution(float a, uint64_t, float b, uint64_t) { return std::max(a, b); }

void run_one(const SceneRun& run, const SceneArgs& args, std::vector<double>& out) {
  b3WorldDef def = b3DefaultWorldDef();
  def.gravity = {float(run.gravity[0]), float(run.gravity[1]), float(run.gravity[2])};
  def.restitutionThreshold = 1.0f;
  def.enableSleep = run.sleep != 0;
  def.workerCount = 1;
  def.frictionCallback = mix_friction;
  def.restitutionCallback = mix_restitution;
  b3WorldId world = b3CreateWorld(&def);

  for (const SceneBox& b : run.boxes) {
    b3BodyDef bd = b3DefaultBodyDef();
    bd.type = b3_staticBody;
    bd.position = {float((b.x0 + b.x1) / 2), float((b.y0 + b.y1) / 2), float((b.z0 + b.z1) / 2)};
    b3BodyId body = b3CreateBody(world, &bd);
    b3BoxHull hull = b3MakeBoxHull(float((b.x1 - b.x0) / 2), float((b.y1 - b.y0) / 2), float((b.z1 - b.z0) / 2));
    b3ShapeDef sd = b3DefaultShapeDef();
    sd.baseMaterial.friction = 1.0f;
    sd.baseMaterial.restitution = 0.0f;
    sd.baseMaterial.rollingResistance = 0.0f;
    sd.baseMaterial.userMaterialId = 1;
    b3CreateHullShape(body, &sd, &hull.base);
  }
  std::vector<b3BodyId> balls;
  for (const SceneBall& s : run.balls) {
    b3BodyDef bd = b3DefaultBodyDef();
    bd.type = b3_dynamicBody;
    bd.position = {float(s.x), float(s.y), float(s.z)};
    bd.linearVelocity = {float(s.vx), float(s.vy), float(s.vz)};
    bd.angularVelocity = {float(s.wx), float(s.wy), float(s.wz)};
    b3BodyId body = b3CreateBody(world, &bd);
    b3Sphere sphere = {{0, 0, 0}, float(s.r)};
    b3ShapeDef sd = b3DefaultShapeDef();
    sd.density = float(s.m / (4.0 / 3.0 * M_PI * s.r * s.r * s.r));
    sd.baseMaterial.friction = float(s.mu);
    sd.baseMaterial.restitution = float(s.e);
    sd.baseMaterial.rollingResistance = float(s.rho);
    b3CreateSphereShape(body, &sd, &sphere);
    if (!run.sleep) b3Body_EnableSleep(body, false);
    balls.push_back(body);
  }
  const float dt = 1.0f / args.hz;
  auto step = [&] { b3World_Step(world, dt, args.substeps); };
  auto state = [&](size_t i, double* s) {
    b3Pos p = b3Body_GetPosition(balls[i]);
    b3Vec3 v = b3Body_GetLinearVelocity(balls[i]);
    b3Vec3 w = b3Body_GetAngularVelocity(balls[i]);
    double values[9] = {p.x, p.y, p.z, v.x, v.y, v.z, w.x, w.y, w.z};
    std::copy(values, values + 9, s);
  };
  scene_drive(run, args, step, state, out);
  b3DestroyWorld(world);
}

}  // namespace

int main(int argc, char** argv) {
  const SceneArgs args = scene_args("box3d-scenes", argc, argv);
  std::vector<double> out;
  for (const SceneRun& run : read_scene("box3d-scenes", args)) run_one(run, args, out);
  scene_write("box3d-scenes", args, out);
  return 0;
}
