// tools/peers/box3d-basin.cpp -- the basin of physics.org (make-basin-world, #B4S1NS) in Box3D
// (github.com/erincatto/box3d, built from the source BOX3D_SRC names, single precision), on
// WORKERS workers of Box3D's own scheduler, for make bench-peers (#B3NCHW).
//
// Command line: [BALLS=3000] [STEPS=300] [FROM=120] [WORKERS=1]; steps FROM..STEPS-1 are timed.
// Box3D is Box2D v3's soft step in 3D, as this engine's step is: four substeps at 60 Hz, one
// relax per substep, sleep off, friction 0.6 mixed as sqrt(mu_a mu_b) (the floor and walls are
// static box hulls whose friction callback gives the ball's own), no restitution.  With
// WORKERS above 1 and no task callbacks, Box3D makes its threads and runs its own scheduler.
//
// Build (make bench-peers BOX3D_SRC=...): the C sources of $BOX3D_SRC/src compiled with -O2
// -DNDEBUG, then g++ -O2 box3d-basin.cpp -I$BOX3D_SRC/include with those objects, -lpthread.

#include <box3d/box3d.h>

#include "basin.h"

#include <cmath>

namespace {

float mix_friction(float a, uint64_t ida, float b, uint64_t idb) {
  if (ida == 1) return b;
  if (idb == 1) return a;
  return std::sqrt(a * b);
}

}  // namespace

int main(int argc, char** argv) {
  const BasinArgs args = basin_args("box3d-basin", argc, argv);
  const int balls = args.balls, steps = args.steps, from = args.from;
  // the fourth argument, the peers' iterations, is here the count of workers
  const int workers = args.iterations < 1 ? 1 : args.iterations;

  b3WorldDef def = b3DefaultWorldDef();
  def.gravity = {0.0f, -9.81f, 0.0f};
  def.restitutionThreshold = 1.0f;
  def.enableSleep = false;
  def.workerCount = static_cast<uint32_t>(workers);
  def.frictionCallback = mix_friction;
  b3WorldId world = b3CreateWorld(&def);

  for (const BasinBox& b : basin_boxes(balls)) {
    b3BodyDef bd = b3DefaultBodyDef();
    bd.type = b3_staticBody;
    bd.position = {(b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2, (b.z0 + b.z1) / 2};
    b3BodyId body = b3CreateBody(world, &bd);
    b3BoxHull hull = b3MakeBoxHull((b.x1 - b.x0) / 2, (b.y1 - b.y0) / 2, (b.z1 - b.z0) / 2);
    b3ShapeDef sd = b3DefaultShapeDef();
    sd.baseMaterial.friction = 1.0f;
    sd.baseMaterial.restitution = 0.0f;
    sd.baseMaterial.userMaterialId = 1;
    b3CreateHullShape(body, &sd, &hull.base);
  }

  std::vector<b3BodyId> spheres;
  const float r = 0.25f;
  for (int i = 0; i < balls; ++i) {
    float p[3];
    basin_spawn_point(i, p);
    b3BodyDef bd = b3DefaultBodyDef();
    bd.type = b3_dynamicBody;
    bd.position = {p[0], p[1], p[2]};
    b3BodyId body = b3CreateBody(world, &bd);
    b3Sphere sphere = {{0, 0, 0}, r};
    b3ShapeDef sd = b3DefaultShapeDef();
    sd.density = 1.0f / (4.0f / 3.0f * 3.14159265f * r * r * r);
    sd.baseMaterial.friction = 0.6f;
    sd.baseMaterial.restitution = 0.0f;
    b3CreateSphereShape(body, &sd, &sphere);
    b3Body_EnableSleep(body, false);
    spheres.push_back(body);
  }

  auto step = [&] { b3World_Step(world, 1.0f / 60.0f, 4); };
  BasinTimes times;
  for (int i = 0; i < steps; ++i) {
    if (i >= from)
      times.time(step);
    else
      step();
  }

  BasinPile pile;
  for (b3BodyId b : spheres) {
    b3Pos p = b3Body_GetPosition(b);
    pile.add(p.x, p.y, p.z);
  }
  b3Counters counters = b3World_GetCounters(world);
  std::printf("box3d balls=%d steps=%d from=%d workers=%d mean_ms=%.3f median_ms=%.3f contacts=%d "
              "mean_y=%.3f min_y=%.3f escaped=%d\n",
              balls, steps, from, workers, times.mean(), times.median(), counters.contactCount,
              pile.mean_y(), pile.lowest_y(), pile.escaped);
  b3DestroyWorld(world);
  return 0;
}
