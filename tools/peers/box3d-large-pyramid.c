// tools/peers/box3d-large-pyramid.c -- Box3D's large pyramid (erincatto/box3d shared/benchmarks.c,
// CreateLargePyramid) as physics.org runs it (#PYR4MD): rows of unit cubes (half-extent 0.5,
// density 100) in the plane z = 0, BASE at the bottom and one fewer in each row above, each row
// shifted by half a cube, every cube touching its neighbours; Box3D's ground box (half-extents
// 400, 1, 400 at y = -1, its top at y = 0); sleep off; one worker, 60 Hz with four substeps.
// Prints the process's CPU time per step over STEPS steps and the top cube's height at the end.
//
// Build (make bench-pyramid BOX3D_SRC=...): the C sources of $BOX3D_SRC/src compiled with
// -O2 -DNDEBUG, then cc -O2 box3d-large-pyramid.c -I$BOX3D_SRC/include with those objects.
// Usage: box3d-large-pyramid [BASE [STEPS]]   (100 and 200 by default)

#include <box3d/box3d.h>

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double cpu_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char** argv) {
  int base = argc > 1 ? atoi(argv[1]) : 100;
  int steps = argc > 2 ? atoi(argv[2]) : 200;
  b3WorldDef wd = b3DefaultWorldDef();
  wd.workerCount = 1;
  wd.enableSleep = false;
  b3WorldId world = b3CreateWorld(&wd);
  {
    b3BodyDef bd = b3DefaultBodyDef();
    bd.position = (b3Pos){0.0f, -1.0f, 0.0f};
    b3BodyId ground = b3CreateBody(world, &bd);
    b3BoxHull box = b3MakeBoxHull(400.0f, 1.0f, 400.0f);
    b3ShapeDef sd = b3DefaultShapeDef();
    b3CreateHullShape(ground, &sd, &box.base);
  }
  b3BodyDef bd = b3DefaultBodyDef();
  bd.type = b3_dynamicBody;
  b3ShapeDef sd = b3DefaultShapeDef();
  sd.density = 100.0f;
  float h = 0.5f;
  b3BoxHull box = b3MakeBoxHull(h, h, h);
  b3BodyId top = b3_nullBodyId;
  int count = 0;
  for (int i = 0; i < base; ++i) {
    float y = (2.0f * i + 1.0f) * h;
    for (int j = i; j < base; ++j) {
      float x = (i + 1.0f) * h + 2.0f * (j - i) * h - h * base;
      bd.position = (b3Pos){x, y, 0.0f};
      top = b3CreateBody(world, &bd);
      b3CreateHullShape(top, &sd, &box.base);
      ++count;
    }
  }
  double start = cpu_seconds();
  for (int s = 0; s < steps; ++s) b3World_Step(world, 1.0f / 60.0f, 4);
  double per = (cpu_seconds() - start) / steps;
  b3Pos p = b3Body_GetPosition(top);
  printf("box3d-large-pyramid: base %d cubes %d steps %d ms-per-step %.4f top-y %.4f top-x %.4f\n", base, count, steps,
         1000.0 * per, (double)p.y, (double)p.x);
  b3DestroyWorld(world);
  return 0;
}
