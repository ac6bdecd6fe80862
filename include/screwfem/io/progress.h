// A one-line progress bar for long runs: simulated time / end time, steps per second of wall
// time and the estimated wall time left, redrawn in place ("\r") at most ten times a second.
#pragma once

#include <chrono>
#include <cstdio>

namespace screwfem {

class ProgressBar {
 public:
  // Draws nothing until Update; out is typically stderr.
  ProgressBar(std::FILE* out, double t_begin, double t_end);
  // Redraws if at least 0.1 s of wall time passed since the last redraw.
  void Update(double t, long steps);
  // Draws the final state and ends the line (once; later calls do nothing).
  void Finish(double t, long steps);

 private:
  using Clock = std::chrono::steady_clock;
  void Draw(double t, long steps);
  std::FILE* out_;
  double t_begin_, t_end_;
  Clock::time_point start_, last_draw_;
  bool drawn_ = false, finished_ = false;
};

}  // namespace screwfem
