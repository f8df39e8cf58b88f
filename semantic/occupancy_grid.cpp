#include "semantic/occupancy_grid.hpp"

// ROS map_server maps, CARMEN laser logs, and the grid a robot's scans make.

#include <yaml-cpp/yaml.h>
#include <zlib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>

#include "semantic/cloud_formats.hpp"

namespace rise::semantic {

namespace {

using formats::fail_byte;
using formats::fail_line;

constexpr double kPi = 3.14159265358979323846;

// --- ROS map_server -------------------------------------------------------

int line_of(const YAML::Node& node) { return node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

template <typename T>
T yaml_value(const std::string& path, const YAML::Node& map, const char* key, std::optional<T> fallback) {
  const YAML::Node node = map[key];
  if (!node) {
    if (fallback) return *fallback;
    fail_line(path, static_cast<size_t>(line_of(map)), std::string(key) + ": missing");
  }
  if (!node.IsScalar()) fail_line(path, static_cast<size_t>(line_of(node)), std::string(key) + ": expected a value");
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail_line(path, static_cast<size_t>(line_of(node)), std::string(key) + ": not a valid value: '" + node.Scalar() + "'");
  }
}

enum class MapMode { Trinary, Scale, Raw };

}  // namespace

OccupancyGrid read_ros_map(const std::string& yaml_path, const std::string& image_path) {
  const std::string text = formats::read_file(yaml_path);
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail_line(yaml_path, static_cast<size_t>(e.mark.line + 1), e.msg);
  }
  if (!doc.IsMap()) fail_line(yaml_path, 1, "expected map_server's keys (image, resolution, origin, ...)");

  OccupancyGrid grid;
  grid.resolution_m = yaml_value<double>(yaml_path, doc, "resolution", std::nullopt);
  if (!(grid.resolution_m > 0) || !std::isfinite(grid.resolution_m))
    fail_line(yaml_path, static_cast<size_t>(line_of(doc["resolution"])), "resolution: must be > 0");

  const YAML::Node origin = doc["origin"];
  if (!origin) fail_line(yaml_path, static_cast<size_t>(line_of(doc)), "origin: missing");
  if (!origin.IsSequence() || origin.size() != 3)
    fail_line(yaml_path, static_cast<size_t>(line_of(origin)), "origin: expected [x, y, yaw]");
  double xyyaw[3];
  for (size_t i = 0; i < 3; ++i) {
    try {
      xyyaw[i] = origin[i].as<double>();
    } catch (const YAML::Exception&) {
      fail_line(yaml_path, static_cast<size_t>(line_of(origin[i])), "origin: not a number: '" + origin[i].Scalar() + "'");
    }
    if (!std::isfinite(xyyaw[i]))
      fail_line(yaml_path, static_cast<size_t>(line_of(origin[i])), "origin: not a finite number: '" + origin[i].Scalar() + "'");
  }
  if (xyyaw[2] != 0)
    fail_line(yaml_path, static_cast<size_t>(line_of(origin)),
              "origin: yaw " + std::to_string(xyyaw[2]) + " rad: only unrotated maps are supported (map_server ignores yaw)");
  grid.origin_m = {xyyaw[0], xyyaw[1]};

  const bool negate = yaml_value<int>(yaml_path, doc, "negate", 0) != 0;
  const double occupied_thresh = yaml_value<double>(yaml_path, doc, "occupied_thresh", std::nullopt);
  const double free_thresh = yaml_value<double>(yaml_path, doc, "free_thresh", std::nullopt);
  if (!(free_thresh <= occupied_thresh))
    fail_line(yaml_path, static_cast<size_t>(line_of(doc["free_thresh"])), "free_thresh: above occupied_thresh");
  const std::string mode_name = yaml_value<std::string>(yaml_path, doc, "mode", std::string("trinary"));
  MapMode mode = MapMode::Trinary;
  if (mode_name == "scale") mode = MapMode::Scale;
  else if (mode_name == "raw") mode = MapMode::Raw;
  else if (mode_name != "trinary")
    fail_line(yaml_path, static_cast<size_t>(line_of(doc["mode"])), "mode: '" + mode_name + "' is not trinary, scale or raw");

  std::string image = image_path;
  if (image.empty()) {
    const std::string named = yaml_value<std::string>(yaml_path, doc, "image", std::nullopt);
    const std::filesystem::path p(named);
    image = p.is_absolute() ? named : (std::filesystem::path(yaml_path).parent_path() / p).string();
    if (!std::filesystem::exists(image))
      fail_line(yaml_path, static_cast<size_t>(line_of(doc["image"])),
                "image: " + image + ": cannot open: " + std::strerror(ENOENT));
  }
  const std::string bytes = formats::read_file(image);
  cv::Mat img;
  try {
    img = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data())),
                       cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
  }
  if (img.empty()) throw std::runtime_error(image + ": not an image OpenCV can decode (PGM, PNG, ...)");
  if (img.depth() != CV_8U && img.depth() != CV_16U)
    throw std::runtime_error(image + ": only 8- and 16-bit images are maps");
  const double max_value = img.depth() == CV_8U ? 255.0 : 65535.0;
  // map_server averages the colour channels; an alpha channel is not a colour.
  const int colours = img.channels() == 4 ? 3 : img.channels() == 2 ? 1 : img.channels();
  cv::Mat f;
  img.convertTo(f, CV_64F);

  grid.width = img.cols;
  grid.height = img.rows;
  grid.cells.assign(static_cast<size_t>(grid.width) * static_cast<size_t>(grid.height), CellState::Unknown);
  for (int r = 0; r < img.rows; ++r) {
    const double* row = f.ptr<double>(r);
    for (int c = 0; c < img.cols; ++c) {
      double v = 0;
      for (int k = 0; k < colours; ++k) v += row[c * img.channels() + k];
      v /= colours;
      if (negate) v = max_value - v;
      double p = (max_value - v) / max_value;  // occupancy probability
      if (mode == MapMode::Raw) {
        if (v > 100) continue;  // unknown
        p = v / 100.0;
      }
      CellState s = CellState::Unknown;
      if (p > occupied_thresh) s = CellState::Occupied;
      else if (p < free_thresh) s = CellState::Free;
      grid.at(c, img.rows - 1 - r) = s;
    }
  }
  return grid;
}

// --- CARMEN logs ----------------------------------------------------------

namespace {

// The whole file, gunzipped when it is gzip (zlib reads plain files as they are).
std::string read_maybe_gz(const std::string& path) {
  gzFile gz = gzopen(path.c_str(), "rb");
  if (gz == nullptr) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::string out;
  char buf[1 << 16];
  for (;;) {
    const int n = gzread(gz, buf, sizeof buf);
    if (n <= 0) break;
    out.append(buf, static_cast<size_t>(n));
  }
  int err = Z_OK;
  const char* msg = gzerror(gz, &err);
  const std::string why = msg != nullptr ? msg : "";
  gzclose(gz);
  if (err != Z_OK && err != Z_STREAM_END)
    fail_byte(path, out.size(), "gzip data: " + (why.empty() ? std::string("truncated or corrupt") : why));
  return out;
}

// CARMEN's bearings for an old-format laser line (see the header).
double carmen_step(size_t n) { return (n == 181 || n == 361) ? kPi / static_cast<double>(n - 1) : kPi / static_cast<double>(n); }

}  // namespace

std::vector<LaserScan2D> read_carmen_log(const std::string& path) { return parse_carmen_log(path, read_maybe_gz(path)); }

std::vector<LaserScan2D> parse_carmen_log(const std::string& path, std::string_view text) {
  std::vector<LaserScan2D> scans;
  std::vector<size_t> flaser;  // indices of FLASER scans: their max range is decided at the end
  std::optional<double> front_laser_max;
  float largest = 0;

  formats::Lines lines{text};
  std::string_view line;
  while (lines.next(line)) {
    const auto w = formats::words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const size_t ln = lines.number;
    // from_chars reads "nan" and "inf" too: no file of ours means them.
    auto num = [&](size_t i, const char* what) {
      const double v = formats::number<double>(w[i], path, ln, what);
      if (!std::isfinite(v)) fail_line(path, ln, std::string(what) + ": not a finite number: '" + std::string(w[i]) + "'");
      return v;
    };
    auto need = [&](size_t count, const std::string& what) {
      if (w.size() < count)
        fail_line(path, ln, std::string(w[0]) + ": " + what + ": " + std::to_string(count) + " fields expected, " +
                                std::to_string(w.size()) + " found");
    };
    auto count_at = [&](size_t i, const char* what) {
      const int n = formats::number<int>(w[i], path, ln, what);
      if (n < 0 || n > 100000) fail_line(path, ln, std::string(w[0]) + ": " + what + ": " + std::to_string(n) + " out of range");
      return static_cast<size_t>(n);
    };
    auto ranges = [&](LaserScan2D& s, size_t first, size_t n) {
      s.ranges.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const double r = num(first + i, "range");
        if (!(r >= 0) || r > 1e5)  // no laser measures 100 km; a float holds the rest
          fail_line(path, ln, std::string(w[0]) + ": range " + std::to_string(i + 1) + ": not a distance: '" + std::string(w[first + i]) + "'");
        s.ranges[i] = static_cast<float>(r);
      }
    };

    if (w[0] == "PARAM") {
      if (w.size() >= 3 && w[1] == "robot_front_laser_max") front_laser_max = num(2, "robot_front_laser_max");
    } else if (w[0] == "FLASER") {
      need(2, "reading count");
      const size_t n = count_at(1, "reading count");
      need(2 + n + 9, std::to_string(n) + " readings, pose, odometry, timestamps");
      LaserScan2D s;
      ranges(s, 2, n);
      for (float r : s.ranges) largest = std::max(largest, r);
      s.pose = {num(2 + n, "x"), num(3 + n, "y"), num(4 + n, "theta")};
      s.time_s = num(8 + n, "ipc_timestamp");
      s.start_angle_rad = -kPi / 2;
      s.angle_step_rad = carmen_step(n);
      flaser.push_back(scans.size());
      scans.push_back(std::move(s));
    } else if (w[0] == "ROBOTLASER1") {
      // laser_type start_angle fov angular_res max_range accuracy remission_mode n r1..rn
      // m rem1..remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
      // forward_safety_dist side_safety_dist turn_axis timestamp hostname logger_timestamp
      need(9, "header");
      const size_t n = count_at(8, "num_readings");
      need(10 + n, std::to_string(n) + " readings and the remission count");
      const size_t m = count_at(9 + n, "num_remissions");
      const size_t p = 10 + n + m;
      need(p + 14, "remissions, poses, velocities, timestamps");
      LaserScan2D s;
      s.start_angle_rad = num(2, "start_angle");
      s.angle_step_rad = num(4, "angular_resolution");
      s.max_range_m = num(5, "maximum_range");
      ranges(s, 9, n);
      s.pose = {num(p, "laser_pose_x"), num(p + 1, "laser_pose_y"), num(p + 2, "laser_pose_theta")};
      s.time_s = num(p + 11, "timestamp");
      scans.push_back(std::move(s));
    }
  }
  const double max_range = front_laser_max.value_or(static_cast<double>(largest));
  for (size_t i : flaser) scans[i].max_range_m = max_range;
  return scans;
}

// --- Scans to grid ---------------------------------------------------------

OccupancyGrid grid_from_scans(const std::vector<LaserScan2D>& scans, double resolution_m,
                              const ScanGridSettings& st) {
  if (!(resolution_m > 0)) throw std::invalid_argument("grid_from_scans: resolution_m must be > 0");
  // Each beam: where it ends and whether that end is a hit.
  struct Beam {
    Eigen::Vector2d end;
    bool hit;
  };
  auto beam = [&](const LaserScan2D& s, size_t i) -> std::optional<Beam> {
    const double r = s.ranges[i];
    if (!(r > 0)) return std::nullopt;
    const double a = s.pose.z() + s.start_angle_rad + static_cast<double>(i) * s.angle_step_rad;
    const bool hit = r < s.max_range_m && r < st.max_hit_range_m;
    const double len = hit ? r : std::min(r, st.no_return_free_m);
    return Beam{s.pose.head<2>() + len * Eigen::Vector2d(std::cos(a), std::sin(a)), hit};
  };

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& s : scans) {
    lo = lo.cwiseMin(s.pose.head<2>());
    hi = hi.cwiseMax(s.pose.head<2>());
    for (size_t i = 0; i < s.ranges.size(); ++i)
      if (const auto b = beam(s, i)) {
        lo = lo.cwiseMin(b->end);
        hi = hi.cwiseMax(b->end);
      }
  }
  OccupancyGrid grid;
  grid.resolution_m = resolution_m;
  if (scans.empty()) return grid;
  const Eigen::Vector2d span = (hi - lo) / resolution_m;
  if (!(span.x() * span.y() < 1e8))  // 0.9 GB of log-odds, stamps and cells
    throw std::invalid_argument("grid_from_scans: the scans span " + std::to_string(hi.x() - lo.x()) + " x " +
                                std::to_string(hi.y() - lo.y()) + " m: too many cells at " +
                                std::to_string(resolution_m) + " m");
  grid.origin_m = lo - Eigen::Vector2d::Constant(resolution_m);
  grid.width = static_cast<int>(std::ceil((hi.x() - grid.origin_m.x()) / resolution_m)) + 1;
  grid.height = static_cast<int>(std::ceil((hi.y() - grid.origin_m.y()) / resolution_m)) + 1;
  const size_t count = static_cast<size_t>(grid.width) * static_cast<size_t>(grid.height);
  std::vector<float> logodds(count, 0.0f);
  std::vector<uint32_t> touched(count, 0);  // scan number + 1 of the last update: one update per cell per scan

  auto index = [&](const Eigen::Vector2i& c) { return static_cast<size_t>(c.y()) * static_cast<size_t>(grid.width) + static_cast<size_t>(c.x()); };
  auto update = [&](size_t k, double delta) {
    logodds[k] = static_cast<float>(std::clamp(logodds[k] + delta, -st.clamp_logodds, st.clamp_logodds));
  };
  for (size_t si = 0; si < scans.size(); ++si) {
    const auto& s = scans[si];
    const auto stamp = static_cast<uint32_t>(si + 1);
    // Hits first, so that this scan's own rays never clear a cell it sees as a wall.
    for (size_t i = 0; i < s.ranges.size(); ++i)
      if (const auto b = beam(s, i); b && b->hit) {
        const size_t k = index(grid.cell_of(b->end));
        if (touched[k] != stamp) update(k, st.hit_logodds);
        touched[k] = stamp;
      }
    const Eigen::Vector2i from = grid.cell_of(s.pose.head<2>());
    for (size_t i = 0; i < s.ranges.size(); ++i) {
      const auto b = beam(s, i);
      if (!b) continue;
      // Bresenham from the laser's cell to the beam's end: every cell it
      // crosses is a miss; the end cell too when the beam found nothing.
      const Eigen::Vector2i to = grid.cell_of(b->end);
      const int dx = std::abs(to.x() - from.x()), dy = -std::abs(to.y() - from.y());
      const int sx = from.x() < to.x() ? 1 : -1, sy = from.y() < to.y() ? 1 : -1;
      int err = dx + dy;
      Eigen::Vector2i c = from;
      for (;;) {
        const bool last = c == to;
        if (last && b->hit) break;
        const size_t k = index(c);
        if (touched[k] != stamp) update(k, st.miss_logodds);
        touched[k] = stamp;
        if (last) break;
        const int e2 = 2 * err;
        if (e2 >= dy) { err += dy; c.x() += sx; }
        if (e2 <= dx) { err += dx; c.y() += sy; }
      }
    }
  }
  grid.cells.assign(count, CellState::Unknown);
  for (size_t k = 0; k < count; ++k) {
    if (logodds[k] > st.occupied_logodds) grid.cells[k] = CellState::Occupied;
    else if (logodds[k] < st.free_logodds) grid.cells[k] = CellState::Free;
  }
  return grid;
}

}  // namespace rise::semantic
