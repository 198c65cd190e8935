// tools/peers/scenes.h -- what the peers' scene harnesses share: reading the scene file that
// physics.org writes (section "Engine beside engine", #P33R5X), the command line, and writing
// the trajectory each run leaves, which the page measures.
//
// The harnesses measure nothing: they build a run's static boxes and balls in their engine,
// step it, time the steps, and record what the page's measurement reads.  Every error is
// computed by the page, from the same kind of record this engine's runs leave.
//
// The scene file, one directive a line, words separated by spaces:
//   scene NAME                 the runs that follow, up to the next scene line, are NAME's
//   run                        a run begins
//   gravity GX GY GZ           m/s^2
//   seconds S                  simulated seconds to step
//   sleep 0|1                  whether bodies may sleep
//   record-all 0|1             whether every ball's centre is recorded each step
//   box X0 Y0 Z0 X1 Y1 Z1      a static box, its corners
//   ball X Y Z R M E MU RHO VX VY VZ WX WY WZ LIFT WATCH
//                              a ball: centre, radius, mass, restitution, friction, rolling
//                              resistance, velocity, spin; LIFT 1 puts its centre the engine's own
//                              resting overlap (SLOP, below) lower; WATCH 1 records it each step
//   param KEY VALUE            read by the page's measurement only
//   end                        the run ends
//
// The command line: HARNESS SCENES NAME HZ SUBSTEPS ITERATIONS SLOP OUT [KEY=VALUE...]
// runs every run of scene NAME at HZ steps a second, each of SUBSTEPS substeps (or internal
// steps), the solver at ITERATIONS, and writes OUT.  The KEY=VALUE words are the peer's own
// knobs.
//
// OUT, little-endian doubles, for each run in order:
//   frames, watched, balls, wall seconds of the steps, record-all
//   then per frame (the first before any step): time, each watched ball's x y z vx vy vz wx wy
//   wz, and with record-all every ball's x y z
//   then every ball's x y z vx vy vz after the last step.

#ifndef LUV_PEERS_SCENES_H
#define LUV_PEERS_SCENES_H

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

struct SceneBox {
  double x0, y0, z0, x1, y1, z1;
};

struct SceneBall {
  double x, y, z, r, m, e, mu, rho, vx, vy, vz, wx, wy, wz;
  int lift, watch;
};

struct SceneRun {
  double gravity[3] = {0, -9.81, 0};
  double seconds = 1;
  int sleep = 0, record_all = 0;
  std::vector<SceneBox> boxes;
  std::vector<SceneBall> balls;
};

struct SceneArgs {
  std::string scenes, name, out;
  int hz, substeps, iterations;
  double slop;
  std::map<std::string, std::string> knobs;

  double knob(const char* key, double fallback) const {
    auto it = knobs.find(key);
    return it == knobs.end() ? fallback : std::strtod(it->second.c_str(), nullptr);
  }
};

[[noreturn]] inline void scene_fail(const char* program, const std::string& why) {
  std::fprintf(stderr, "%s: %s\n", program, why.c_str());
  std::exit(2);
}

inline SceneArgs scene_args(const char* program, int argc, char** argv) {
  if (argc < 8)
    scene_fail(program, "usage: SCENES NAME HZ SUBSTEPS ITERATIONS SLOP OUT [KEY=VALUE...]");
  SceneArgs a;
  a.scenes = argv[1];
  a.name = argv[2];
  a.hz = std::atoi(argv[3]);
  a.substeps = std::atoi(argv[4]);
  a.iterations = std::atoi(argv[5]);
  a.slop = std::strtod(argv[6], nullptr);
  a.out = argv[7];
  if (a.hz <= 0 || a.substeps <= 0 || a.iterations <= 0) scene_fail(program, "HZ, SUBSTEPS and ITERATIONS must be positive");
  for (int i = 8; i < argc; ++i) {
    const char* eq = std::strchr(argv[i], '=');
    if (!eq) scene_fail(program, std::string("not KEY=VALUE: ") + argv[i]);
    a.knobs[std::string(argv[i], static_cast<size_t>(eq - argv[i]))] = eq + 1;
  }
  return a;
}

// The runs of scene NAME in the file, in order; LIFT already applied with SLOP.
inline std::vector<SceneRun> read_scene(const char* program, const SceneArgs& args) {
  std::ifstream in(args.scenes);
  if (!in) scene_fail(program, "cannot read " + args.scenes);
  std::vector<SceneRun> runs;
  std::string line, current;
  SceneRun run;
  bool open = false;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string word;
    if (!(words >> word)) continue;
    if (word == "scene") {
      words >> current;
    } else if (current != args.name) {
      continue;
    } else if (word == "run") {
      run = SceneRun();
      open = true;
    } else if (word == "gravity") {
      words >> run.gravity[0] >> run.gravity[1] >> run.gravity[2];
    } else if (word == "seconds") {
      words >> run.seconds;
    } else if (word == "sleep") {
      words >> run.sleep;
    } else if (word == "record-all") {
      words >> run.record_all;
    } else if (word == "box") {
      SceneBox b;
      words >> b.x0 >> b.y0 >> b.z0 >> b.x1 >> b.y1 >> b.z1;
      run.boxes.push_back(b);
    } else if (word == "ball") {
      SceneBall b;
      words >> b.x >> b.y >> b.z >> b.r >> b.m >> b.e >> b.mu >> b.rho >> b.vx >> b.vy >> b.vz >> b.wx >> b.wy >> b.wz >> b.lift >> b.watch;
      if (b.lift) b.y -= args.slop;
      run.balls.push_back(b);
    } else if (word == "end") {
      if (open) runs.push_back(run);
      open = false;
    } else if (word != "param") {
      scene_fail(program, "unknown directive in " + args.scenes + ": " + word);
    }
    if (words.fail()) scene_fail(program, "bad numbers in " + args.scenes + ": " + line);
  }
  if (runs.empty()) scene_fail(program, "no runs of scene " + args.name + " in " + args.scenes);
  return runs;
}

// One run's record, written after the steps.  The engine fills position, velocity and angular
// velocity of ball i through its State callback.
struct SceneRecord {
  std::vector<double> data;
  int frames = 0, watched = 0, balls = 0;
  double wall = 0;
  int record_all = 0;

  template <typename State>
  void frame(const SceneRun& run, double time, State state) {
    ++frames;
    data.push_back(time);
    double s[9];
    for (size_t i = 0; i < run.balls.size(); ++i)
      if (run.balls[i].watch) {
        state(i, s);
        data.insert(data.end(), s, s + 9);
      }
    if (run.record_all)
      for (size_t i = 0; i < run.balls.size(); ++i) {
        state(i, s);
        data.insert(data.end(), s, s + 3);
      }
  }

  template <typename State>
  void finish(const SceneRun& run, State state, std::vector<double>& out) {
    watched = 0;
    for (const SceneBall& b : run.balls) watched += b.watch;
    balls = static_cast<int>(run.balls.size());
    double header[5] = {double(frames), double(watched), double(balls), wall, double(run.record_all)};
    out.insert(out.end(), header, header + 5);
    out.insert(out.end(), data.begin(), data.end());
    double s[9];
    for (int i = 0; i < balls; ++i) {
      state(i, s);
      out.insert(out.end(), s, s + 6);
    }
  }
};

// Step RUN for its seconds: STEP() advances one step (its time is added to the record's wall),
// STATE(i, s) reads ball i.  Appends the run's record to OUT.
template <typename Step, typename State>
void scene_drive(const SceneRun& run, const SceneArgs& args, Step step, State state, std::vector<double>& out) {
  SceneRecord record;
  const double dt = 1.0 / args.hz;
  const long steps = std::lround(run.seconds * args.hz);
  record.frame(run, 0.0, state);
  for (long k = 1; k <= steps; ++k) {
    auto start = std::chrono::steady_clock::now();
    step();
    auto end = std::chrono::steady_clock::now();
    record.wall += std::chrono::duration<double>(end - start).count();
    record.frame(run, k * dt, state);
  }
  record.finish(run, state, out);
}

inline void scene_write(const char* program, const SceneArgs& args, const std::vector<double>& out) {
  std::FILE* f = std::fopen(args.out.c_str(), "wb");
  if (!f || std::fwrite(out.data(), sizeof(double), out.size(), f) != out.size() || std::fclose(f) != 0)
    scene_fail(program, "cannot write " + args.out);
}

#endif
