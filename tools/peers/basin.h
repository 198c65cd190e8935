// tools/peers/basin.h -- what the peers' basin drivers share: the scene of physics.org's
// make-basin-world (section "The basin", #B4S1NS), the command line, and the figures every
// driver prints (timing as measure-basin, #B3NCH5, and where the pile ended).
//
// Each driver builds the static boxes of basin_boxes and a sphere at every basin_spawn_point
// in its own engine, times each step into a BasinTimes, and reports a BasinPile of the ball
// centres.

#ifndef LUV_PEERS_BASIN_H
#define LUV_PEERS_BASIN_H

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

// The command line: [BALLS=3000] [STEPS=300] [FROM=120] [ITERATIONS=10].  Steps FROM..STEPS-1
// are timed; ITERATIONS is the peer's solver iteration count.
struct BasinArgs {
  int balls, steps, from, iterations;
};

inline int basin_count_arg(const char* program, int argc, char** argv, int n, int fallback) {
  if (argc <= n) return fallback;
  char* end = nullptr;
  long v = std::strtol(argv[n], &end, 10);
  if (*end != '\0' || v < 0) {
    std::fprintf(stderr, "%s: argument %d is not a count: %s\n", program, n, argv[n]);
    std::exit(2);
  }
  return static_cast<int>(v);
}

inline BasinArgs basin_args(const char* program, int argc, char** argv) {
  BasinArgs a = {basin_count_arg(program, argc, argv, 1, 3000), basin_count_arg(program, argc, argv, 2, 300),
                 basin_count_arg(program, argc, argv, 3, 120), basin_count_arg(program, argc, argv, 4, 10)};
  if (a.from >= a.steps) {
    std::fprintf(stderr, "%s: FROM (%d) must be below STEPS (%d)\n", program, a.from, a.steps);
    std::exit(2);
  }
  return a;
}

// basin-spawn-point's jitter: a fixed integer hash of (i, salt) mapped into [-0.025, 0.025]
inline float basin_jitter(uint64_t i, uint64_t salt) {
  uint64_t h = ((i * 7919u + salt * 104729u + 12345u) * 2654435761u) & 0xFFFFFFFFu;
  return 0.025f * (2.0f * (static_cast<float>((h >> 8) & 0xFFFFu) / 65535.0f) - 1.0f);
}

// The centre of the I-th ball: 14 x 14 per layer at 0.55 m from 0.5 m above the floor, jittered.
inline void basin_spawn_point(int i, float p[3]) {
  int layer = i / 196, k = i % 196, row = k / 14, col = k % 14;
  p[0] = 0.3f + 0.55f * col + basin_jitter(i, 1);
  p[1] = 0.5f + 0.55f * layer + basin_jitter(i, 2);
  p[2] = 0.3f + 0.55f * row + basin_jitter(i, 3);
}

// The static boxes, each [x0,x1] x [y0,y1] x [z0,z1]: the floor and the four walls one unit
// thick around the interior [0,8) x [0,8), 6 high, or 30 above 3000 balls.
struct BasinBox {
  float x0, y0, z0, x1, y1, z1;
};

inline std::vector<BasinBox> basin_boxes(int balls) {
  const float wall = balls > 3000 ? 30 : 6;
  return {{-8, -1, -8, 16, 0, 16},   // floor
          {-1, 0, -1, 9, wall, 0},   // z in [-1,0), x in [-1,9)
          {-1, 0, 8, 9, wall, 9},    // z in [8,9),  x in [-1,9)
          {-1, 0, 0, 0, wall, 8},    // x in [-1,0), z in [0,8)
          {8, 0, 0, 9, wall, 8}};    // x in [8,9),  z in [0,8)
}

// Milliseconds of each timed step, and their mean and median.
struct BasinTimes {
  std::vector<double> ms;

  template <typename Step>
  void time(Step step) {
    auto start = std::chrono::steady_clock::now();
    step();
    auto end = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(end - start).count());
  }
  double mean() const {
    double sum = 0;
    for (double t : ms) sum += t;
    return ms.empty() ? 0 : sum / ms.size();
  }
  double median() const {
    if (ms.empty()) return 0;
    std::vector<double> s(ms);
    std::sort(s.begin(), s.end());
    size_t n = s.size();
    return n % 2 ? s[n / 2] : (s[n / 2 - 1] + s[n / 2]) / 2;
  }
};

// Where the pile ended: mean and lowest centre height (0.25 for a ball resting on the floor),
// and the balls whose centre lies outside the interior [0,8] x [0,8] or below the floor's top.
struct BasinPile {
  int balls = 0, escaped = 0;
  double sum_y = 0, min_y = 1e30;

  void add(double x, double y, double z) {
    ++balls;
    sum_y += y;
    min_y = std::min(min_y, y);
    if (!(x >= 0 && x <= 8 && z >= 0 && z <= 8 && y >= 0)) ++escaped;
  }
  double mean_y() const { return balls ? sum_y / balls : 0.0; }
  double lowest_y() const { return balls ? min_y : 0.0; }
};

#endif
