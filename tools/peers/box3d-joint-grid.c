// tools/peers/box3d-joint-grid.c -- Box3D's joint grid (erincatto/box3d shared/benchmarks.c,
// CreateJointGrid) as physics.org runs it (#J0GR1D): N x N spheres of radius 0.4, one apart in a
// vertical plane, each joined to the one above and the one to its left by spherical joints at
// anchors 0.5 m from the centres; the top row static, sphere-sphere collision filtered out, sleep
// off; one worker, 60 Hz with four substeps.  Prints the process's CPU time per step over STEPS
// steps and the lowest corner's height at the end.
//
// Build (make bench-joint-grid BOX3D_SRC=...): the C sources of $BOX3D_SRC/src compiled with
// -O2 -DNDEBUG, then cc -O2 box3d-joint-grid.c -I$BOX3D_SRC/include with those objects.
// Usage: box3d-joint-grid [N [STEPS]]   (100 and 100 by default)

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
  int n = argc > 1 ? atoi(argv[1]) : 100;
  int steps = argc > 2 ? atoi(argv[2]) : 100;
  b3WorldDef wd = b3DefaultWorldDef();
  wd.workerCount = 1;
  wd.enableSleep = false;
  b3WorldId world = b3CreateWorld(&wd);
  b3BodyId* grid = malloc(sizeof(b3BodyId) * n * n);
  b3ShapeDef sd = b3DefaultShapeDef();
  sd.filter.categoryBits = 2;
  sd.filter.maskBits = ~2u;
  b3Sphere ball = {{0.0f, 0.0f, 0.0f}, 0.4f};
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < n; ++i) {
      b3BodyDef bd = b3DefaultBodyDef();
      bd.type = i == 0 ? b3_staticBody : b3_dynamicBody;
      bd.enableSleep = false;
      bd.position.x = (float)k;
      bd.position.y = (float)-i;
      bd.position.z = 0.0f;
      b3BodyId body = b3CreateBody(world, &bd);
      b3CreateSphereShape(body, &sd, &ball);
      grid[k * n + i] = body;
      b3SphericalJointDef jd = b3DefaultSphericalJointDef();
      if (i > 0) {
        jd.base.bodyIdA = grid[k * n + i - 1];
        jd.base.bodyIdB = body;
        jd.base.localFrameA.p = (b3Vec3){0.0f, -0.5f, 0.0f};
        jd.base.localFrameB.p = (b3Vec3){0.0f, 0.5f, 0.0f};
        b3CreateSphericalJoint(world, &jd);
      }
      if (k > 0) {
        jd.base.bodyIdA = grid[(k - 1) * n + i];
        jd.base.bodyIdB = body;
        jd.base.localFrameA.p = (b3Vec3){0.5f, 0.0f, 0.0f};
        jd.base.localFrameB.p = (b3Vec3){-0.5f, 0.0f, 0.0f};
        b3CreateSphericalJoint(world, &jd);
      }
    }
  }
  double start = cpu_seconds();
  for (int s = 0; s < steps; ++s) b3World_Step(world, 1.0f / 60.0f, 4);
  double per = (cpu_seconds() - start) / steps;
  b3Pos corner = b3Body_GetPosition(grid[(n - 1) * n + n - 1]);
  printf("box3d-joint-grid: n %d steps %d ms-per-step %.4f corner-y %.4f\n", n, steps, 1000.0 * per, (double)corner.y);
  free(grid);
  b3DestroyWorld(world);
  return 0;
}
