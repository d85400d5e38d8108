#include "rbd_localization/map_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <vector>

namespace rbd_localization {

namespace {

std::string dirOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".")
                                    : (slash == 0 ? std::string("/") : path.substr(0, slash));
}

std::string stemOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = base.find_last_of('.');
  return dot == std::string::npos ? base : base.substr(0, dot);
}

bool readFile(const std::string& path, std::string* out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::ostringstream ss;
  ss << f.rdbuf();
  *out = ss.str();
  return static_cast<bool>(f) || f.eof();
}

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::string unquote(const std::string& s) {
  if (s.size() >= 2 && (s[0] == '"' || s[0] == '\'') && s.back() == s[0]) return s.substr(1, s.size() - 2);
  return s;
}

/// "key: value" lines of a flat YAML mapping (map_server's files); comments dropped.
std::map<std::string, std::string> flatYaml(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    out[trim(line.substr(0, colon))] = trim(line.substr(colon + 1));
  }
  return out;
}

bool parseDouble(const std::string& s, double* v) {
  char* end = nullptr;
  const std::string t = trim(s);
  *v = std::strtod(t.c_str(), &end);
  return !t.empty() && end && *end == '\0' && std::isfinite(*v);
}

bool parseTriple(const std::string& s, Eigen::Vector3d* v) {
  std::string t = trim(s);
  if (t.size() < 2 || t.front() != '[' || t.back() != ']') return false;
  t = t.substr(1, t.size() - 2);
  std::istringstream in(t);
  std::string part;
  int k = 0;
  while (std::getline(in, part, ',')) {
    if (k >= 3 || !parseDouble(part, &(*v)(k))) return false;
    ++k;
  }
  return k == 3;
}

/// Binary PGM (P5, maxval <= 255): width, height, pixels row-major from the top-left.
bool parsePgm(const std::string& data, int* w, int* h, std::vector<uint8_t>* px, std::string* error) {
  size_t pos = 0;
  auto token = [&](std::string* tok) {
    for (;;) {
      while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
      if (pos < data.size() && data[pos] == '#') {
        while (pos < data.size() && data[pos] != '\n') ++pos;
        continue;
      }
      break;
    }
    const size_t a = pos;
    while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
    *tok = data.substr(a, pos - a);
    return !tok->empty();
  };
  std::string magic, sw, sh, smax;
  if (!token(&magic) || magic != "P5") {
    *error = "not a binary PGM (P5); only P5 images are read";
    return false;
  }
  if (!token(&sw) || !token(&sh) || !token(&smax)) {
    *error = "PGM header truncated";
    return false;
  }
  *w = std::atoi(sw.c_str());
  *h = std::atoi(sh.c_str());
  const int maxval = std::atoi(smax.c_str());
  if (*w <= 0 || *h <= 0 || *w > 20000 || *h > 20000 || maxval <= 0 || maxval > 255) {
    *error =
        "PGM size " + sw + " x " + sh + " or maxval " + smax + " not supported (1..20000, maxval <= 255)";
    return false;
  }
  ++pos;  // the single whitespace after maxval
  const size_t n = static_cast<size_t>(*w) * *h;
  if (data.size() < pos + n) {
    *error = "PGM data truncated (" + std::to_string(data.size() - std::min(data.size(), pos)) + " of " +
             std::to_string(n) + " bytes)";
    return false;
  }
  px->assign(data.begin() + pos, data.begin() + pos + n);
  if (maxval != 255) {
    for (uint8_t& v : *px) v = static_cast<uint8_t>(std::lround(255.0 * v / maxval));
  }
  return true;
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

constexpr float kLongAgo = 1e6f;  // [s] age of loaded structure without a recorded age

}  // namespace

uint64_t fnv1a64(const std::string& data) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : data) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

bool writeFileAtomic(const std::string& path, const std::string& data, std::string* error) {
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    *error = "cannot create " + tmp + ": " + std::strerror(errno);
    return false;
  }
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error = "cannot write " + tmp + ": " + std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    *error = "cannot sync " + tmp + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    *error = "cannot rename " + tmp + " to " + path + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  const int dfd = ::open(dirOf(path).c_str(), O_RDONLY);
  if (dfd >= 0) {
    ::fsync(dfd);  // the rename itself reaches the disk
    ::close(dfd);
  }
  return true;
}

bool saveMap(const OccupancyMap& map, double now, const Eigen::Vector3d& home, const std::string& dir,
             const std::string& name, std::string* error) {
  if (name.empty() || name.find('/') != std::string::npos) {
    *error = "map name must be a plain file name without '/', got '" + name + "'";
    return false;
  }
  const std::string prefix = (dir.empty() ? std::string(".") : dir) + "/" + name;
  const int w = map.width(), h = map.height();
  // PGM: row 0 is the top of the image, i.e. the map's highest y (origin = lower-left pixel).
  std::string pgm =
      "P5\n# RoboDog map (rbd_localization)\n" + std::to_string(w) + " " + std::to_string(h) + "\n255\n";
  const size_t header = pgm.size();
  pgm.resize(header + static_cast<size_t>(w) * h);
  for (int cy = 0; cy < h; ++cy) {
    for (int cx = 0; cx < w; ++cx) {
      int v = kPgmUnknown;
      if (map.isStatic(cx, cy, now)) {
        v = kPgmOccupied;
      } else if (map.logOdds(cx, cy) < 0.0f) {
        v = kPgmFree;
      }
      pgm[header + static_cast<size_t>(h - 1 - cy) * w + cx] = static_cast<char>(v);
    }
  }
  std::string yaml = "image: " + name + ".pgm\n";
  yaml += "resolution: " + num(map.params().resolution) + "\n";
  yaml += "origin: [" + num(map.originX()) + ", " + num(map.originY()) + ", 0.0]\n";
  yaml += "negate: 0\noccupied_thresh: " + num(kOccupiedThresh) + "\nfree_thresh: " + num(kFreeThresh) +
          "\nmode: trinary\n";

  std::string side = "RBDMAP 1\n";
  side += "width " + std::to_string(w) + "\nheight " + std::to_string(h) + "\n";
  side += "resolution " + num(map.params().resolution) + "\n";
  side += "origin " + num(map.originX()) + " " + num(map.originY()) + "\n";
  side += "home " + num(home.x()) + " " + num(home.y()) + " " + num(home.z()) + "\n";
  side += "pgm_fnv1a64 " + hex64(fnv1a64(pgm)) + "\n";
  side +=
      "data float32le log_odds then float32le occupied_age_s (NaN: not occupied), row-major from cell "
      "(0,0)\n";
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<float> block(2 * n);
  for (int cy = 0; cy < h; ++cy) {
    for (int cx = 0; cx < w; ++cx) {
      const size_t i = map.index(cx, cy);
      block[i] = map.logOdds(cx, cy);
      const float since = map.occupiedSince(cx, cy);
      block[n + i] =
          std::isfinite(since) ? static_cast<float>(now - since) : std::numeric_limits<float>::quiet_NaN();
    }
  }
  side.append(reinterpret_cast<const char*>(block.data()), block.size() * sizeof(float));

  return writeFileAtomic(prefix + ".rbdmap", side, error) && writeFileAtomic(prefix + ".pgm", pgm, error) &&
         writeFileAtomic(prefix + ".yaml", yaml, error);
}

bool loadMap(const std::string& yaml_path, const OccupancyMap::Params& params, double now,
             std::unique_ptr<OccupancyMap>* out, MapFileInfo* info, std::string* error) {
  *info = MapFileInfo();
  std::string text;
  if (!readFile(yaml_path, &text)) {
    *error = "cannot read map file " + yaml_path;
    return false;
  }
  const auto kv = flatYaml(text);
  for (const char* key : {"image", "resolution", "origin"}) {
    if (!kv.count(key)) {
      *error = yaml_path + ": missing key '" + key + "'";
      return false;
    }
  }
  double res = 0.0, occ_t = kOccupiedThresh, free_t = kFreeThresh, negate = 0.0;
  Eigen::Vector3d origin;
  if (!parseDouble(kv.at("resolution"), &res) || res <= 0.0 || !parseTriple(kv.at("origin"), &origin)) {
    *error = yaml_path + ": resolution must be > 0 and origin [x, y, yaw]";
    return false;
  }
  if (std::fabs(origin.z()) > 1e-9) {
    *error = yaml_path + ": rotated map origins (yaw != 0) are not supported";
    return false;
  }
  if ((kv.count("occupied_thresh") && !parseDouble(kv.at("occupied_thresh"), &occ_t)) ||
      (kv.count("free_thresh") && !parseDouble(kv.at("free_thresh"), &free_t)) ||
      (kv.count("negate") && !parseDouble(kv.at("negate"), &negate)) || !(free_t < occ_t)) {
    *error =
        yaml_path + ": occupied_thresh, free_thresh, negate must be numbers, free_thresh < occupied_thresh";
    return false;
  }
  const std::string mode = kv.count("mode") ? unquote(kv.at("mode")) : "trinary";
  if (mode != "trinary" && mode != "scale") {
    *error = yaml_path + ": mode '" + mode + "' not supported (trinary or scale)";
    return false;
  }
  std::string image = unquote(kv.at("image"));
  if (image.empty()) {
    *error = yaml_path + ": empty image";
    return false;
  }
  if (image[0] != '/') image = dirOf(yaml_path) + "/" + image;
  std::string pgm;
  if (!readFile(image, &pgm)) {
    *error = "cannot read map image " + image;
    return false;
  }
  int w = 0, h = 0;
  std::vector<uint8_t> px;
  std::string perr;
  if (!parsePgm(pgm, &w, &h, &px, &perr)) {
    *error = image + ": " + perr;
    return false;
  }
  OccupancyMap::Params p = params;
  p.resolution = res;
  p.grow = false;
  out->reset(new OccupancyMap(p, w, h, origin.x(), origin.y()));
  OccupancyMap& m = **out;
  const float clamp = static_cast<float>(p.clamp_log_odds);
  for (int row = 0; row < h; ++row) {
    for (int cx = 0; cx < w; ++cx) {
      const double x = px[static_cast<size_t>(row) * w + cx];
      const double occ = negate != 0.0 ? x / 255.0 : (255.0 - x) / 255.0;
      const int cy = h - 1 - row;
      if (occ > occ_t) {
        m.setCell(cx, cy, clamp, static_cast<float>(now) - kLongAgo);
      } else if (occ < free_t) {
        m.setCell(cx, cy, -clamp, std::numeric_limits<float>::quiet_NaN());
      }
    }
  }

  // The sidecar, if it belongs to this PGM: exact log-odds and ages, and the home pose.
  const std::string side_path = dirOf(yaml_path) + "/" + stemOf(image) + ".rbdmap";
  std::string side;
  if (!readFile(side_path, &side)) {
    info->note = "no " + side_path + ": cells from the PGM";
  } else {
    const size_t data_line = side.find("\ndata ");
    const size_t data_start =
        data_line == std::string::npos ? std::string::npos : side.find('\n', data_line + 1);
    std::map<std::string, std::string> head;
    if (data_start != std::string::npos) {
      std::istringstream in(side.substr(0, data_line));
      std::string line;
      while (std::getline(in, line)) {
        const size_t sp = line.find(' ');
        if (sp != std::string::npos) head[line.substr(0, sp)] = trim(line.substr(sp + 1));
      }
    }
    const size_t n = static_cast<size_t>(w) * h;
    double sres = 0.0;
    Eigen::Vector3d home = Eigen::Vector3d::Zero();
    std::istringstream so(head.count("origin") ? head["origin"] : ""),
        sh(head.count("home") ? head["home"] : "");
    double sox = 0.0, soy = 0.0;
    so >> sox >> soy;
    sh >> home.x() >> home.y() >> home.z();
    if (data_start == std::string::npos || head["RBDMAP"] != "1") {
      info->note = side_path + " is not a version 1 sidecar: cells from the PGM";
    } else if (head["pgm_fnv1a64"] != hex64(fnv1a64(pgm))) {
      info->note = side_path + " belongs to another version of " + image + " (edited?): cells from the PGM";
    } else if (head["width"] != std::to_string(w) || head["height"] != std::to_string(h) ||
               !parseDouble(head["resolution"], &sres) || std::fabs(sres - res) > 1e-9 || !so ||
               std::fabs(sox - origin.x()) > 1e-6 || std::fabs(soy - origin.y()) > 1e-6) {
      *error = yaml_path + " does not match " + side_path +
               " (resolution/origin/size differ: files of different saves, an interrupted save?)";
      return false;
    } else if (side.size() - (data_start + 1) != 2 * n * sizeof(float)) {
      info->note = side_path + " data has the wrong length: cells from the PGM";
    } else {
      std::vector<float> block(2 * n);
      std::memcpy(block.data(), side.data() + data_start + 1, block.size() * sizeof(float));
      for (int cy = 0; cy < h; ++cy) {
        for (int cx = 0; cx < w; ++cx) {
          const size_t i = m.index(cx, cy);
          const float age = block[n + i];
          m.setCell(
              cx, cy, block[i],
              std::isfinite(age) ? static_cast<float>(now) - age : std::numeric_limits<float>::quiet_NaN());
        }
      }
      info->exact = true;
      if (sh) {
        info->has_home = true;
        info->home = home;
      }
    }
  }
  m.updateDistanceField();
  return true;
}

}  // namespace rbd_localization
