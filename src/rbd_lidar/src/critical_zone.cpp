#include "rbd_lidar/critical_zone.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace rbd_lidar {

namespace {

// Four uint32 lanes (GCC/Clang vector extension).
typedef uint32_t V4u __attribute__((vector_size(16)));

// Margins of the candidate table: it covers the exact zone enlarged by kPad, and stays valid while
// the attitude moves less than kMaxTilt (kPad absorbs the resulting shift within a few metres).
constexpr double kPad = 0.04;
constexpr double kMaxTilt = 0.25 * M_PI / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Shrinks [lo, hi) (ranges in m) to the ranges where a * r + b < c.
void limit(double a, double b, double c, double* lo, double* hi) {
  if (a > 1e-12) {
    *hi = std::min(*hi, (c - b) / a);
  } else if (a < -1e-12) {
    *lo = std::max(*lo, (c - b) / a);
  } else if (b >= c) {
    *hi = -kInf;
  }
}

}  // namespace

CriticalZone::CriticalZone()
    : corners_(cornerAzimuths(zone_)), table_rotation_(Eigen::Matrix3d::Identity()) {}

std::array<double, 4> CriticalZone::cornerAzimuths(const ZoneParams& z) {
  return {{std::atan2(z.left, z.front), M_PI - std::atan2(z.left, z.back),
           -M_PI + std::atan2(z.right, z.back), -std::atan2(z.right, z.front)}};
}

Side CriticalZone::section(double azimuth, const std::array<double, 4>& c) {
  const double a = wrapAngle(azimuth);
  if (a >= c[3] && a <= c[0]) return FRONT;
  if (a > c[0] && a < c[1]) return LEFT;
  if (a < c[3] && a > c[2]) return RIGHT;
  return BACK;
}

bool CriticalZone::configure(const BeamModel& beams, const ZoneParams& zone, const SensorPose& pose,
                             std::string* error) {
  std::string why;
  if (!beams.valid(&why)) {
    if (error) *error = "beam model: " + why;
    return false;
  }
  const double sides[] = {zone.front,          zone.back,          zone.left,          zone.right,
                          zone.slowdown_front, zone.slowdown_back, zone.slowdown_left, zone.slowdown_right};
  for (double s : sides) {
    if (!std::isfinite(s) || s < 0.0 || s > 30.0) {
      if (error) *error = "zone distances must be finite and in [0, 30] m";
      return false;
    }
  }
  if (!std::isfinite(zone.blind_zone) || zone.blind_zone < 0.0 || !std::isfinite(zone.floor_clearance) ||
      !std::isfinite(zone.max_height) || !pose.level_from_sensor.allFinite() || !std::isfinite(pose.height)) {
    if (error) *error = "blind zone, height band or sensor pose not finite";
    return false;
  }
  if (beams != beams_) {
    beams_ = beams;
    trig_.build(beams_);
    table_valid_ = false;
  }
  zone_ = zone;
  pose_ = pose;
  corners_ = cornerAzimuths(zone_);

  // Does the table still cover the exact zone with some margin, and not too loosely?
  const std::array<double, 4> need{{zone.front + zone.slowdown_front, zone.left + zone.slowdown_left,
                                    zone.back + zone.slowdown_back, zone.right + zone.slowdown_right}};
  bool rebuild = !table_valid_ || zone.blind_zone != table_blind_;
  for (size_t i = 0; i < 4 && !rebuild; ++i) {
    const double slack = table_extent_[i] - need[i];
    rebuild = slack < kPad / 2 || slack > 3 * kPad;
  }
  if (!rebuild) {
    const Eigen::Matrix3d delta = table_rotation_.transpose() * pose.level_from_sensor;
    rebuild = Eigen::AngleAxisd(delta).angle() > kMaxTilt;
  }
  if (rebuild) {
    for (size_t i = 0; i < 4; ++i) table_extent_[i] = need[i] + kPad;
    table_rotation_ = pose.level_from_sensor;
    table_blind_ = zone.blind_zone;
    buildTable();
  }
  return true;
}

void CriticalZone::buildTable() {
  const size_t rows = beams_.rows(), cols = static_cast<size_t>(beams_.columns);
  table_.resize(rows * cols);
  const Eigen::Matrix3d& rot = table_rotation_;
  const double n = beams_.beam_origin;
  // The height band is not in the table: it depends on the (often changing) sensor height and
  // only matters for the few candidates; the exact test applies it.
  const double front = table_extent_[0], left = table_extent_[1], back = table_extent_[2],
               right = table_extent_[3];
  const double blind_mm = std::max(1.0, std::ceil(table_blind_ * 1000.0 - 1e-9));
  for (size_t u = 0; u < rows; ++u) {
    const double cp = trig_.cos_alt[u], sp = trig_.sin_alt[u];
    for (size_t c = 0; c < cols; ++c) {
      double ca, sa;
      trig_.azimuth(u, c, &ca, &sa);
      const Eigen::Vector3d d = rot * Eigen::Vector3d(ca * cp, sa * cp, sp);
      const Eigen::Vector3d o =
          rot * Eigen::Vector3d(n * ca * (1 - cp), n * sa * (1 - cp), beams_.lidar_z - n * sp);
      double lo = 0.0, hi = kInf;
      limit(d.x(), o.x(), front, &lo, &hi);
      limit(-d.x(), -o.x(), back, &lo, &hi);
      limit(d.y(), o.y(), left, &lo, &hi);
      limit(-d.y(), -o.y(), right, &lo, &hi);
      // Candidates: lo_mm <= r < hi_mm (the table errs on the inclusive side).
      const double lo_mm = std::max(blind_mm, std::floor(lo * 1000.0));
      const double hi_mm = std::min(lo_mm + 65535.0, std::ceil(hi * 1000.0) + 1.0);
      Interval& iv = table_[u * cols + c];
      if (!(hi_mm > lo_mm) || lo_mm > 65535.0) {
        iv.lo = 0;
        iv.span = 0;
      } else {
        iv.lo = static_cast<uint16_t>(lo_mm);
        iv.span = static_cast<uint16_t>(hi_mm - lo_mm);
      }
    }
  }
  table_valid_ = true;
  ++builds_;
  if (debug_) {
    *debug_ << "rbd_lidar: candidate table rebuilt (" << rows << "x" << cols << ", extents F" << front << " L"
            << left << " B" << back << " R" << right << " m)\n";
  }
}

Eigen::Vector3d CriticalZone::sensorPoint(uint32_t index, uint32_t range_mm) const {
  const size_t cols = static_cast<size_t>(beams_.columns);
  return trig_.point(beams_, index / cols, index % cols, range_mm * 1e-3);
}

Eigen::Vector3d CriticalZone::levelPoint(uint32_t index, uint32_t range_mm) const {
  Eigen::Vector3d p = pose_.level_from_sensor * sensorPoint(index, range_mm);
  p.z() += pose_.height;
  return p;
}

void CriticalZone::evaluate(const uint32_t* range_mm, ZoneResult* out) const {
  evaluateStrided(reinterpret_cast<const uint8_t*>(range_mm), sizeof(uint32_t), out);
}

void CriticalZone::Scratch::reserve(size_t pixels, size_t rows) {
  if (index.size() < pixels) {
    index.resize(pixels);
    range.resize(pixels);
    cos_col.resize(pixels);
    sin_col.resize(pixels);
    x.resize(pixels);
    y.resize(pixels);
    h.resize(pixels);
  }
  if (row_first.size() < rows) row_first.resize(rows);
}

void CriticalZone::evaluateStrided(const uint8_t* range_bytes, size_t stride, ZoneResult* out) const {
  ZoneResult& res = *out;
  res.counts = {{0, 0, 0, 0}};
  const float inf = std::numeric_limits<float>::infinity();
  res.min_distance = {{inf, inf, inf, inf}};
  res.critical.clear();
  res.critical_side.clear();
  res.speed_scale = 1.0f;
  res.valid_returns = 0;
  if (!table_valid_) return;

  // Scratch buffers live per thread; take plain references once (a thread_local in a shared
  // library costs a TLS lookup per access). Sized for the worst case (every pixel a candidate).
  const size_t rows = beams_.rows(), cols = static_cast<size_t>(beams_.columns);
  thread_local Scratch scratch_buffer;
  Scratch& sb = scratch_buffer;
  sb.reserve(rows * cols + 8, rows + 1);
  uint32_t* cand = sb.index.data();
  uint32_t* cand_r = sb.range.data();
  float* cand_cc = sb.cos_col.data();
  float* cand_sc = sb.sin_col.data();
  size_t* row_first = sb.row_first.data();
  const double *cos_col = trig_.cos_col.data(), *sin_col = trig_.sin_col.data();

  // Pass 1: candidates from the table (one subtract-and-compare per pixel), valid-return count.
  const Interval* table = table_.data();
  size_t found = 0;
  uint32_t valid = 0;
  V4u valid_lanes = {0, 0, 0, 0};
  const uint8_t* src = range_bytes;
  for (size_t u = 0; u < rows; ++u) {
    row_first[u] = found;
    const Interval* row_table = table + u * cols;
    const uint32_t first = static_cast<uint32_t>(u * cols);
    auto append = [&](size_t col, uint32_t r) {
      cand[found] = first + static_cast<uint32_t>(col);
      cand_r[found] = r;
      cand_cc[found] = static_cast<float>(cos_col[col]);
      cand_sc[found] = static_cast<float>(sin_col[col]);
      ++found;
    };
    // Blocks of 8 pixels: the interval test makes a bit mask, and only blocks with a candidate
    // (a few percent, clustered) store anything.
    size_t c = 0;
    static_assert(sizeof(Interval) == sizeof(uint32_t), "one table entry is one uint32");
    if (stride == sizeof(uint32_t)) {
      // Contiguous range image: the interval test of 8 pixels in two 4-lane vectors (GCC/Clang
      // vector extensions: SSE2 on x86, NEON on the Jetson). A table entry read as one uint32 holds
      // lo in its low and span in its high half (little-endian, as both targets are).
      for (; c + 8 <= cols; c += 8, src += 8 * sizeof(uint32_t)) {
        V4u r0, r1, t0, t1;
        std::memcpy(&r0, src, 16);
        std::memcpy(&r1, src + 16, 16);
        std::memcpy(&t0, row_table + c, 16);
        std::memcpy(&t1, row_table + c + 4, 16);
        const V4u low = {0xFFFFu, 0xFFFFu, 0xFFFFu, 0xFFFFu};
        const V4u hit0 = reinterpret_cast<V4u>((r0 - (t0 & low)) < (t0 >> 16));
        const V4u hit1 = reinterpret_cast<V4u>((r1 - (t1 & low)) < (t1 >> 16));
        valid_lanes -= reinterpret_cast<V4u>(r0 != 0) + reinterpret_cast<V4u>(r1 != 0);
        const V4u any = hit0 | hit1;
        uint64_t any_lo, any_hi;
        std::memcpy(&any_lo, &any, 8);
        std::memcpy(&any_hi, reinterpret_cast<const uint8_t*>(&any) + 8, 8);
        if ((any_lo | any_hi) == 0) continue;
        for (unsigned j = 0; j < 8; ++j) {
          uint32_t r;
          std::memcpy(&r, src + j * sizeof(uint32_t), sizeof(r));
          if (static_cast<uint32_t>(r - row_table[c + j].lo) < row_table[c + j].span) {
            append(c + j, r);
          }
        }
      }
    }
    for (; c + 8 <= cols; c += 8, src += 8 * stride) {
      uint32_t r8[8];
      unsigned mask = 0;
      for (unsigned j = 0; j < 8; ++j) {
        std::memcpy(&r8[j], src + j * stride, sizeof(uint32_t));
        valid += r8[j] != 0;
        mask |=
            static_cast<unsigned>(static_cast<uint32_t>(r8[j] - row_table[c + j].lo) < row_table[c + j].span)
            << j;
      }
      while (mask != 0) {
        const unsigned j = static_cast<unsigned>(__builtin_ctz(mask));
        mask &= mask - 1;
        append(c + j, r8[j]);
      }
    }
    for (; c < cols; ++c, src += stride) {
      uint32_t r;
      std::memcpy(&r, src, sizeof(r));
      valid += r != 0;
      if (static_cast<uint32_t>(r - row_table[c].lo) < row_table[c].span) {
        append(c, r);
      }
    }
  }
  row_first[rows] = found;
  res.valid_returns = valid + valid_lanes[0] + valid_lanes[1] + valid_lanes[2] + valid_lanes[3];

  // Pass 2a: level-frame points of the candidates, row by row (contiguous arrays and per-row
  // constants: the compiler vectorises it). With cc, sc the column's cos/sin and the row's
  // azimuth/altitude folded into the constants, x = hz (cc px + sc qx) + r02 sz (y, h alike),
  // hz = rm cos(alt) + k1 and sz = rm sin(alt) + k2 (the BeamModel of sensorPoint, rotated).
  const Eigen::Matrix3d& R = pose_.level_from_sensor;
  const float r02 = static_cast<float>(R(0, 2)), r12 = static_cast<float>(R(1, 2)),
              r22 = static_cast<float>(R(2, 2));
  const double n = beams_.beam_origin, lz = beams_.lidar_z;
  const float height = static_cast<float>(pose_.height);
  float* __restrict xs = sb.x.data();
  float* __restrict ys = sb.y.data();
  float* __restrict hs = sb.h.data();
  for (size_t u = 0; u < rows; ++u) {
    const size_t k0 = row_first[u], k1 = row_first[u + 1];
    if (k0 == k1) continue;
    const double a = trig_.cos_az0[u], b = trig_.sin_az0[u];
    const double cos_alt = trig_.cos_alt[u], sin_alt = trig_.sin_alt[u];
    const float cp = static_cast<float>(cos_alt * 1e-3), sp = static_cast<float>(sin_alt * 1e-3);
    const float o1 = static_cast<float>(n * (1 - cos_alt)), o2 = static_cast<float>(lz - n * sin_alt);
    const float px = static_cast<float>(R(0, 0) * a + R(0, 1) * b),
                qx = static_cast<float>(R(0, 1) * a - R(0, 0) * b);
    const float py = static_cast<float>(R(1, 0) * a + R(1, 1) * b),
                qy = static_cast<float>(R(1, 1) * a - R(1, 0) * b);
    const float ph = static_cast<float>(R(2, 0) * a + R(2, 1) * b),
                qh = static_cast<float>(R(2, 1) * a - R(2, 0) * b);
    const uint32_t* __restrict rr = cand_r + k0;
    const float* __restrict cc = cand_cc + k0;
    const float* __restrict sc = cand_sc + k0;
    float* __restrict x = xs + k0;
    float* __restrict y = ys + k0;
    float* __restrict h = hs + k0;
    const size_t m = k1 - k0;
    for (size_t k = 0; k < m; ++k) {
      // Candidate ranges are below lo + span < 2^17 mm: the signed conversion (which vectorises,
      // unlike the unsigned one) is exact.
      const float rm = static_cast<float>(static_cast<int32_t>(rr[k] & 0x7FFFFFFFu));
      const float hz = rm * cp + o1, sz = rm * sp + o2;
      x[k] = hz * (cc[k] * px + sc[k] * qx) + r02 * sz;
      y[k] = hz * (cc[k] * py + sc[k] * qy) + r12 * sz;
      h[k] = hz * (cc[k] * ph + sc[k] * qh) + r22 * sz + height;
    }
  }

  // Pass 2b: exact test of the candidates in the level frame.
  const ZoneParams& z = zone_;
  const uint32_t blind_mm = static_cast<uint32_t>(std::max(0.0, std::ceil(z.blind_zone * 1000.0 - 1e-9)));
  // Everything the loop reads lives in locals: the byte-sized stores below may alias any member.
  const float lim0 = static_cast<float>(z.front), lim1 = static_cast<float>(z.left),
              lim2 = static_cast<float>(z.back), lim3 = static_cast<float>(z.right);
  const float inv0 = 1.0f / std::max(lim0, 1e-9f), inv1 = 1.0f / std::max(lim1, 1e-9f),
              inv2 = 1.0f / std::max(lim2, 1e-9f), inv3 = 1.0f / std::max(lim3, 1e-9f);
  const float out0 = static_cast<float>(z.front + z.slowdown_front),
              out1 = static_cast<float>(z.left + z.slowdown_left),
              out2 = static_cast<float>(z.back + z.slowdown_back),
              out3 = static_cast<float>(z.right + z.slowdown_right);
  const float floor_clearance = static_cast<float>(z.floor_clearance),
              max_height = static_cast<float>(z.max_height);
  thread_local std::vector<float> lambda_buffer;
  std::vector<float>& lambdas = lambda_buffer;
  lambdas.resize(found);
  res.critical.resize(found);
  res.critical_side.resize(found);
  float* lam = lambdas.data();
  uint32_t* crit = res.critical.data();
  uint8_t* crit_side = res.critical_side.data();
  size_t n_lam = 0, n_crit = 0;
  uint32_t n0 = 0, n1 = 0, n2 = 0, n3 = 0;
  float md0 = inf, md1 = inf, md2 = inf, md3 = inf;
  for (size_t k = 0; k < found; ++k) {
    const float h = hs[k];
    if (cand_r[k] < blind_mm || !(h > floor_clearance && h < max_height)) continue;
    // Signed perpendicular distance towards each side: front x, left y, back -x, right -y.
    const float t0 = xs[k], t1 = ys[k], t2 = -t0, t3 = -t1;
    if (!(t0 < out0 && t1 < out1 && t2 < out2 && t3 < out3)) continue;
    // Section = the side whose limit the ray from the LiDAR meets first: largest toward / limit
    // (the same split as the corner azimuths phi1..phi4). Branch-free; the per-side minima and
    // counts stay in registers.
    const float q1 = t1 * inv1, q2 = t2 * inv2, q3 = t3 * inv3;
    float best = t0 * inv0, dist = t0;
    unsigned side = 0;
    side = q1 > best ? 1u : side;
    dist = q1 > best ? t1 : dist;
    best = std::max(best, q1);
    side = q2 > best ? 2u : side;
    dist = q2 > best ? t2 : dist;
    best = std::max(best, q2);
    side = q3 > best ? 3u : side;
    dist = q3 > best ? t3 : dist;
    md0 = side == 0 ? std::min(md0, dist) : md0;
    md1 = side == 1 ? std::min(md1, dist) : md1;
    md2 = side == 2 ? std::min(md2, dist) : md2;
    md3 = side == 3 ? std::min(md3, dist) : md3;
    if (t0 < lim0 && t1 < lim1 && t2 < lim2 && t3 < lim3) {
      n0 += side == 0;
      n1 += side == 1;
      n2 += side == 2;
      n3 += side == 3;
      crit[n_crit] = cand[k];
      crit_side[n_crit] = static_cast<uint8_t>(side);
      ++n_crit;  // lambda 0: counted by n_crit, not stored
    } else {
      // Slowdown band: how far into the band, 0 at the stop zone, 1 at its outer edge.
      float lambda = 0.0f;
      const float excess[4] = {t0 - lim0, t1 - lim1, t2 - lim2, t3 - lim3};
      const double slow[4] = {z.slowdown_front, z.slowdown_left, z.slowdown_back, z.slowdown_right};
      for (int s = 0; s < 4; ++s) {
        if (excess[s] > 0.0f)
          lambda = std::max(lambda, slow[s] > 0 ? static_cast<float>(excess[s] / slow[s]) : 1.0f);
      }
      lam[n_lam++] = std::min(1.0f, lambda);
    }
  }
  res.critical.resize(n_crit);
  res.critical_side.resize(n_crit);
  lambdas.resize(n_lam);
  const uint32_t counts[4] = {n0, n1, n2, n3};
  const float min_dist[4] = {md0, md1, md2, md3};
  for (int s = 0; s < 4; ++s) {
    res.counts[s] = counts[s];
    res.min_distance[s] = min_dist[s];
  }
  // Speed scale: the point_threshold-th smallest lambda, so that single noisy returns do not brake.
  // Stop-zone points have lambda 0 and are only counted (n_crit); the slowdown-band lambdas are
  // stored.
  const size_t k = std::max<size_t>(1, z.point_threshold);
  if (n_crit >= k) {
    res.speed_scale = 0.0f;
  } else if (n_crit + lambdas.size() >= k) {
    const size_t j = k - 1 - n_crit;
    std::nth_element(lambdas.begin(), lambdas.begin() + j, lambdas.end());
    res.speed_scale = lambdas[j];
  }
}

}  // namespace rbd_lidar
