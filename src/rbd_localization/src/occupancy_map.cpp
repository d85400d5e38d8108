#include "rbd_localization/occupancy_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rbd_localization {

namespace {

// 1-D squared Euclidean distance transform (lower envelope of parabolas, Felzenszwalb &
// Huttenlocher 2012). Empty samples hold kFar, a large finite value.
constexpr double kFar = 1e12;

void edt1d(const std::vector<double>& f, std::vector<double>* d, std::vector<int>* v,
           std::vector<double>* z) {
  const int n = static_cast<int>(f.size());
  int k = 0;
  (*v)[0] = 0;
  (*z)[0] = -std::numeric_limits<double>::infinity();
  (*z)[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s = ((f[q] + double(q) * q) - (f[(*v)[k]] + double((*v)[k]) * (*v)[k])) / (2.0 * (q - (*v)[k]));
    while (s <= (*z)[k]) {
      --k;
      s = ((f[q] + double(q) * q) - (f[(*v)[k]] + double((*v)[k]) * (*v)[k])) / (2.0 * (q - (*v)[k]));
    }
    ++k;
    (*v)[k] = q;
    (*z)[k] = s;
    (*z)[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while ((*z)[k + 1] < q) ++k;
    const double dq = q - (*v)[k];
    (*d)[q] = dq * dq + f[(*v)[k]];
  }
}

}  // namespace

OccupancyMap::OccupancyMap() : OccupancyMap(Params()) {}

OccupancyMap::OccupancyMap(const Params& params) : params_(params) {
  width_ = std::max(8, static_cast<int>(std::ceil(params_.size / params_.resolution)));
  origin_ = -0.5 * width_ * params_.resolution;
  log_odds_.assign(static_cast<size_t>(width_) * width_, 0.0f);
  distance_.assign(log_odds_.size(), static_cast<float>(params_.max_distance));
}

bool OccupancyMap::cellOf(const Eigen::Vector2d& p, int* cx, int* cy) const {
  const double fx = (p.x() - origin_) / params_.resolution;
  const double fy = (p.y() - origin_) / params_.resolution;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < width_ && fy < width_)) return false;
  *cx = static_cast<int>(fx);
  *cy = static_cast<int>(fy);
  return true;
}

void OccupancyMap::insertScan(const Eigen::Isometry2d& map_from_sensor, const Points2d& points,
                              double weight) {
  const float clamp = static_cast<float>(params_.clamp_log_odds);
  const float hit = static_cast<float>(params_.hit_log_odds * weight);
  const float miss = static_cast<float>(params_.miss_log_odds * weight);
  int sx, sy;
  if (!cellOf(map_from_sensor.translation(), &sx, &sy)) return;
  for (const Eigen::Vector2d& ps : points) {
    const Eigen::Vector2d pm = map_from_sensor * ps;
    // Beam end in cells (may lie outside; then the walk stops at the border).
    const double ex = (pm.x() - origin_) / params_.resolution;
    const double ey = (pm.y() - origin_) / params_.resolution;
    if (!std::isfinite(ex) || !std::isfinite(ey)) continue;
    const int tx = static_cast<int>(std::floor(ex));
    const int ty = static_cast<int>(std::floor(ey));
    // Bresenham from the sensor cell to the end cell, clearing all but the last.
    int x = sx, y = sy;
    const int dx = std::abs(tx - sx), dy = -std::abs(ty - sy);
    const int stx = sx < tx ? 1 : -1, sty = sy < ty ? 1 : -1;
    int err = dx + dy;
    while (!(x == tx && y == ty)) {
      if (x < 0 || y < 0 || x >= width_ || y >= width_) break;
      float& c = log_odds_[static_cast<size_t>(y) * width_ + x];
      c = std::max(-clamp, c + miss);
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x += stx;
      }
      if (e2 <= dx) {
        err += dx;
        y += sty;
      }
    }
    if (tx >= 0 && ty >= 0 && tx < width_ && ty < width_) {
      float& c = log_odds_[static_cast<size_t>(ty) * width_ + tx];
      c = std::min(clamp, c + hit);
    }
  }
}

int OccupancyMap::occupiedCount() const {
  const float t = static_cast<float>(params_.occupied_log_odds);
  return static_cast<int>(std::count_if(log_odds_.begin(), log_odds_.end(), [t](float v) { return v > t; }));
}

void OccupancyMap::updateDistanceField() {
  const int n = width_;
  const float t = static_cast<float>(params_.occupied_log_odds);
  std::vector<double> grid(log_odds_.size());
  for (size_t i = 0; i < grid.size(); ++i) grid[i] = log_odds_[i] > t ? 0.0 : kFar;
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int x = 0; x < n; ++x) {  // columns
    for (int y = 0; y < n; ++y) f[y] = grid[static_cast<size_t>(y) * n + x];
    edt1d(f, &d, &v, &z);
    for (int y = 0; y < n; ++y) grid[static_cast<size_t>(y) * n + x] = d[y];
  }
  const double max_d = params_.max_distance;
  const double res = params_.resolution;
  for (int y = 0; y < n; ++y) {  // rows
    std::copy(grid.begin() + static_cast<size_t>(y) * n, grid.begin() + static_cast<size_t>(y + 1) * n,
              f.begin());
    edt1d(f, &d, &v, &z);
    for (int x = 0; x < n; ++x) {
      const double dist = d[x] >= 0.5 * kFar ? max_d : std::sqrt(d[x]) * res;
      distance_[static_cast<size_t>(y) * n + x] = static_cast<float>(std::min(dist, max_d));
    }
  }
}

bool OccupancyMap::distance(const Eigen::Vector2d& p, double* d, Eigen::Vector2d* gradient) const {
  // Samples sit at cell centres; bilinear interpolation between the four around p.
  const double fx = (p.x() - origin_) / params_.resolution - 0.5;
  const double fy = (p.y() - origin_) / params_.resolution - 0.5;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < width_ - 1 && fy < width_ - 1)) {
    *d = params_.max_distance;
    gradient->setZero();
    return false;
  }
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const double ax = fx - x0, ay = fy - y0;
  const size_t i = static_cast<size_t>(y0) * width_ + x0;
  const double d00 = distance_[i], d10 = distance_[i + 1];
  const double d01 = distance_[i + width_], d11 = distance_[i + width_ + 1];
  *d = (1 - ay) * ((1 - ax) * d00 + ax * d10) + ay * ((1 - ax) * d01 + ax * d11);
  (*gradient)(0) = ((1 - ay) * (d10 - d00) + ay * (d11 - d01)) / params_.resolution;
  (*gradient)(1) = ((1 - ax) * (d01 - d00) + ax * (d11 - d10)) / params_.resolution;
  return true;
}

std::vector<int8_t> OccupancyMap::toOccupancyData() const {
  std::vector<int8_t> out(log_odds_.size());
  for (size_t i = 0; i < log_odds_.size(); ++i) {
    const float l = log_odds_[i];
    if (l == 0.0f) {
      out[i] = -1;
    } else {
      const double p = 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(l)));
      out[i] = static_cast<int8_t>(std::lround(100.0 * p));
    }
  }
  return out;
}

}  // namespace rbd_localization
