#include "screwfem/io/progress.h"

#include <algorithm>
#include <cmath>

namespace screwfem {

namespace {

// "1h02m", "3m05s", "12.3s"
void FormatDuration(double seconds, char* buf, std::size_t size) {
  if (!std::isfinite(seconds) || seconds < 0.0) {
    std::snprintf(buf, size, "?");
  } else if (seconds >= 3600.0) {
    const long s = std::lround(seconds);
    std::snprintf(buf, size, "%ldh%02ldm", s / 3600, (s / 60) % 60);
  } else if (seconds >= 60.0) {
    const long s = std::lround(seconds);
    std::snprintf(buf, size, "%ldm%02lds", s / 60, s % 60);
  } else {
    std::snprintf(buf, size, "%.1fs", seconds);
  }
}

}  // namespace

ProgressBar::ProgressBar(std::FILE* out, double t_begin, double t_end)
    : out_(out), t_begin_(t_begin), t_end_(t_end), start_(Clock::now()), last_draw_(start_) {}

void ProgressBar::Update(double t, long steps) {
  const Clock::time_point now = Clock::now();
  if (finished_ || (drawn_ && now - last_draw_ < std::chrono::milliseconds(100))) return;
  last_draw_ = now;
  Draw(t, steps);
}

void ProgressBar::Finish(double t, long steps) {
  if (finished_) return;
  Draw(t, steps);
  std::fputc('\n', out_);
  std::fflush(out_);
  finished_ = true;
}

void ProgressBar::Draw(double t, long steps) {
  constexpr int kWidth = 30;
  const double span = t_end_ - t_begin_;
  const double fraction = span > 0.0 ? std::clamp((t - t_begin_) / span, 0.0, 1.0) : 1.0;
  const double wall = std::chrono::duration<double>(Clock::now() - start_).count();
  const double rate = wall > 0.0 ? static_cast<double>(steps) / wall : 0.0;
  const double left = fraction > 0.0 ? wall * (1.0 - fraction) / fraction : NAN;
  char bar[kWidth + 1];
  const int filled = static_cast<int>(fraction * kWidth);
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  char eta[32];
  FormatDuration(left, eta, sizeof eta);
  std::fprintf(out_, "\r[%s] %3.0f%%  t = %.4g / %.4g s  %.0f steps/s  %s left   ", bar,
               100.0 * fraction, t, t_end_, rate, eta);
  std::fflush(out_);
  drawn_ = true;
}

}  // namespace screwfem
