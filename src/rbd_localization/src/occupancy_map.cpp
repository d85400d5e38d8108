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

int initialCells(const OccupancyMap::Params& p) {
  return std::max(8, static_cast<int>(std::ceil(p.size / p.resolution)));
}

/// Whether beam k (points in scan order, sensor frame) meets its surface steeper than asin(sin_min).
/// The surface direction comes from the neighbours on the same surface as point k: a neighbour
/// counts when it lies within 0.05 r + 0.05 of it (half the span two neighbours may have). Both
/// neighbours on it: the chord between them; one (point k at a depth step, e.g. the edge of an
/// object with the wall behind): the chord from point k to it; none (a surface grazed so flat that
/// its points lie far apart, or an isolated return): the surface is unknown and the beam does not
/// clear. Before, a depth step on either side made the beam not clear, so the beams along an
/// object's silhouette never cleared what they passed (issue 29: a visitor's flank in front of a
/// bin stayed a wall).
bool beamClears(const Points2d& points, size_t k, double sin_min) {
  const Eigen::Vector2d& p = points[k];
  const double r = p.norm();
  if (r <= 1e-6) return false;
  const double near = 0.05 * r + 0.05;
  const bool has_prev = k > 0 && (points[k - 1] - p).norm() <= near;
  const bool has_next = k + 1 < points.size() && (points[k + 1] - p).norm() <= near;
  Eigen::Vector2d tangent;
  if (has_prev && has_next) {
    tangent = points[k + 1] - points[k - 1];
  } else if (has_prev) {
    tangent = p - points[k - 1];
  } else if (has_next) {
    tangent = points[k + 1] - p;
  } else {
    return false;
  }
  const double span = tangent.norm();
  if (span <= 1e-6) return false;
  return std::fabs(p.x() * tangent.y() - p.y() * tangent.x()) / (r * span) >= sin_min;
}

}  // namespace

OccupancyMap::OccupancyMap() : OccupancyMap(Params()) {}

OccupancyMap::OccupancyMap(const Params& params)
    : OccupancyMap(params, initialCells(params), initialCells(params),
                   -0.5 * initialCells(params) * params.resolution,
                   -0.5 * initialCells(params) * params.resolution) {}

OccupancyMap::OccupancyMap(const Params& params, int width, int height, double origin_x, double origin_y)
    : params_(params),
      width_(std::max(1, width)),
      height_(std::max(1, height)),
      origin_x_(origin_x),
      origin_y_(origin_y) {
  const size_t n = static_cast<size_t>(width_) * height_;
  log_odds_.assign(n, 0.0f);
  occupied_since_.assign(n, std::numeric_limits<float>::quiet_NaN());
  distance_.assign(n, static_cast<float>(params_.max_distance));
}

size_t OccupancyMap::memoryBytes() const {
  return (log_odds_.capacity() + occupied_since_.capacity() + distance_.capacity()) * sizeof(float);
}

bool OccupancyMap::cellOf(const Eigen::Vector2d& p, int* cx, int* cy) const {
  const double fx = (p.x() - origin_x_) / params_.resolution;
  const double fy = (p.y() - origin_y_) / params_.resolution;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < width_ && fy < height_)) return false;
  *cx = static_cast<int>(fx);
  *cy = static_cast<int>(fy);
  return true;
}

bool OccupancyMap::isStatic(int cx, int cy, double now) const {
  const float since = occupiedSince(cx, cy);
  return occupied(cx, cy) && std::isfinite(since) && now - since >= params_.static_time;
}

void OccupancyMap::setCell(int cx, int cy, float log_odds, float occupied_since) {
  const size_t i = index(cx, cy);
  log_odds_[i] = log_odds;
  occupied_since_[i] = occupied(cx, cy) ? occupied_since : std::numeric_limits<float>::quiet_NaN();
}

bool OccupancyMap::growToContain(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const double res = params_.resolution;
  const double m = std::max(params_.grow_margin, res);
  // New bounds snapped to the existing cell lattice (cells keep their world position).
  int add_l = 0, add_b = 0, add_r = 0, add_t = 0;
  if (lo.x() < origin_x_) add_l = static_cast<int>(std::ceil((origin_x_ - lo.x() + m) / res));
  if (lo.y() < origin_y_) add_b = static_cast<int>(std::ceil((origin_y_ - lo.y() + m) / res));
  if (hi.x() >= origin_x_ + width_ * res) {
    add_r = static_cast<int>(std::ceil((hi.x() - (origin_x_ + width_ * res) + m) / res));
  }
  if (hi.y() >= origin_y_ + height_ * res) {
    add_t = static_cast<int>(std::ceil((hi.y() - (origin_y_ + height_ * res) + m) / res));
  }
  if (add_l + add_b + add_r + add_t == 0) return true;
  const int nw = width_ + add_l + add_r, nh = height_ + add_b + add_t;
  if (nw * res > params_.max_size || nh * res > params_.max_size) return false;
  const size_t n = static_cast<size_t>(nw) * nh;
  std::vector<float> lo_new(n, 0.0f), since_new(n, std::numeric_limits<float>::quiet_NaN());
  for (int y = 0; y < height_; ++y) {
    const size_t src = index(0, y), dst = static_cast<size_t>(y + add_b) * nw + add_l;
    std::copy(log_odds_.begin() + src, log_odds_.begin() + src + width_, lo_new.begin() + dst);
    std::copy(occupied_since_.begin() + src, occupied_since_.begin() + src + width_, since_new.begin() + dst);
  }
  log_odds_.swap(lo_new);
  occupied_since_.swap(since_new);
  width_ = nw;
  height_ = nh;
  origin_x_ -= add_l * res;
  origin_y_ -= add_b * res;
  std::vector<float>(n, static_cast<float>(params_.max_distance)).swap(distance_);
  updateDistanceField();
  return true;
}

bool OccupancyMap::insertScan(const Eigen::Isometry2d& map_from_sensor, const Points2d& points,
                              const Insert& how) {
  const float clamp = static_cast<float>(params_.clamp_log_odds);
  const float thr = static_cast<float>(params_.occupied_log_odds);
  const float hit = static_cast<float>(params_.hit_log_odds * how.weight);
  const float miss = static_cast<float>(params_.miss_log_odds * how.weight);
  const float now = static_cast<float>(how.time);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (params_.grow && !points.empty()) {
    Eigen::Vector2d lo = map_from_sensor.translation(), hi = lo;
    for (const Eigen::Vector2d& ps : points) {
      const Eigen::Vector2d pm = map_from_sensor * ps;
      if (!pm.allFinite()) continue;
      lo = lo.cwiseMin(pm);
      hi = hi.cwiseMax(pm);
    }
    growToContain(lo, hi);  // when refused (max_size) the grid stays and far beams only clear
  }
  bool changed = false;
  int sx, sy;
  if (!cellOf(map_from_sensor.translation(), &sx, &sy)) return false;
  const double margin_cells = std::max(0.0, how.end_margin) / params_.resolution;
  const double sin_min = std::sin(std::max(0.0, how.min_incidence));
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector2d& ps = points[k];
    const Eigen::Vector2d pm = map_from_sensor * ps;
    bool clear = true;
    if (sin_min > 0.0) clear = beamClears(points, k, sin_min);
    // Beam end in cells (may lie outside; then the walk stops at the border).
    const double ex = (pm.x() - origin_x_) / params_.resolution;
    const double ey = (pm.y() - origin_y_) / params_.resolution;
    if (!std::isfinite(ex) || !std::isfinite(ey)) continue;
    const int tx = static_cast<int>(std::floor(ex));
    const int ty = static_cast<int>(std::floor(ey));
    // Bresenham from the sensor cell to the end cell, clearing all but the last (and, with an
    // end margin, all but the last margin_cells before it).
    int x = sx, y = sy;
    const int dx = std::abs(tx - sx), dy = -std::abs(ty - sy);
    const int stx = sx < tx ? 1 : -1, sty = sy < ty ? 1 : -1;
    int err = dx + dy;
    while (clear && !(x == tx && y == ty)) {
      if (x < 0 || y < 0 || x >= width_ || y >= height_) break;
      if (margin_cells > 0.0 && std::hypot(tx - x, ty - y) <= margin_cells) break;
      const size_t i = index(x, y);
      float& c = log_odds_[i];
      const bool was = c > thr;
      c = std::max(-clamp, c + miss);
      if (was && c <= thr) {
        occupied_since_[i] = nan;
        changed = true;
      }
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
    if (how.hits && tx >= 0 && ty >= 0 && tx < width_ && ty < height_) {
      const size_t i = index(tx, ty);
      float& c = log_odds_[i];
      const bool was = c > thr;
      c = std::min(clamp, c + hit);
      if (!was && c > thr) {
        occupied_since_[i] = now;
        changed = true;
      }
    }
  }
  return changed;
}

int OccupancyMap::occupiedCount() const {
  const float t = static_cast<float>(params_.occupied_log_odds);
  return static_cast<int>(std::count_if(log_odds_.begin(), log_odds_.end(), [t](float v) { return v > t; }));
}

void OccupancyMap::updateDistanceField() {
  const int w = width_, h = height_;
  const float t = static_cast<float>(params_.occupied_log_odds);
  std::vector<double> grid(log_odds_.size());
  for (size_t i = 0; i < grid.size(); ++i) grid[i] = log_odds_[i] > t ? 0.0 : kFar;
  const int n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  f.resize(h);
  d.resize(h);
  for (int x = 0; x < w; ++x) {  // columns
    for (int y = 0; y < h; ++y) f[y] = grid[index(x, y)];
    edt1d(f, &d, &v, &z);
    for (int y = 0; y < h; ++y) grid[index(x, y)] = d[y];
  }
  const double max_d = params_.max_distance;
  const double res = params_.resolution;
  f.resize(w);
  d.resize(w);
  for (int y = 0; y < h; ++y) {  // rows
    std::copy(grid.begin() + index(0, y), grid.begin() + index(0, y) + w, f.begin());
    edt1d(f, &d, &v, &z);
    for (int x = 0; x < w; ++x) {
      const double dist = d[x] >= 0.5 * kFar ? max_d : std::sqrt(d[x]) * res;
      distance_[index(x, y)] = static_cast<float>(std::min(dist, max_d));
    }
  }
}

bool OccupancyMap::distance(const Eigen::Vector2d& p, double* d, Eigen::Vector2d* gradient) const {
  // Samples sit at cell centres; bilinear interpolation between the four around p.
  const double fx = (p.x() - origin_x_) / params_.resolution - 0.5;
  const double fy = (p.y() - origin_y_) / params_.resolution - 0.5;
  if (!(fx >= 0.0 && fy >= 0.0 && fx < width_ - 1 && fy < height_ - 1)) {
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
