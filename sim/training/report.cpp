#include "sim/training/report.hpp"

#include <fcntl.h>
#include <json/json.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace rise::sim::training {
namespace {

std::string compact(const Json::Value& v) {
  Json::StreamWriterBuilder b;
  b["indentation"] = "";
  b["emitUTF8"] = true;
  return Json::writeString(b, v);
}

std::string pretty(const Json::Value& v) {
  Json::StreamWriterBuilder b;
  b["indentation"] = "  ";
  b["emitUTF8"] = true;
  return Json::writeString(b, v) + "\n";
}

Json::Value parse(const std::string& text, const std::string& what) {
  Json::CharReaderBuilder b;
  std::unique_ptr<Json::CharReader> reader(b.newCharReader());
  Json::Value v;
  std::string errors;
  if (!reader->parse(text.data(), text.data() + text.size(), &v, &errors))
    throw std::runtime_error(what + ": not JSON: " + errors);
  return v;
}

Json::Value track_json(const std::vector<TrajectoryPoint>& track) {
  Json::Value a(Json::arrayValue);
  for (const auto& p : track) {
    Json::Value q(Json::arrayValue);
    q.append(p.time_s);
    q.append(p.x_m);
    q.append(p.y_m);
    q.append(p.yaw_rad);
    a.append(q);
  }
  return a;
}

std::vector<TrajectoryPoint> track_from(const Json::Value& a) {
  std::vector<TrajectoryPoint> out;
  for (const auto& q : a)
    if (q.isArray() && q.size() == 4) out.push_back({q[0].asDouble(), q[1].asDouble(), q[2].asDouble(), q[3].asDouble()});
  return out;
}

Json::Value result_value(const TaskResult& r) {
  Json::Value v;
  v["task"] = r.task;
  v["title"] = r.title;
  v["task_file"] = r.task_file;
  v["world_file"] = r.world_file;
  v["node"] = r.node;
  v["attempt"] = r.attempt;
  v["score"] = r.score;
  v["time_s"] = r.time_s;
  v["time_limit_s"] = r.time_limit_s;
  v["success"] = r.success;
  v["finished"] = r.finished;
  v["end_reason"] = r.end_reason;
  v["damage"] = r.damage;
  v["collisions"] = r.collisions;
  Json::Value counts(Json::objectValue);
  for (const auto& [k, n] : r.counts) counts[k] = n;
  v["counts"] = counts;
  Json::Value events(Json::arrayValue);
  for (const auto& e : r.events) {
    Json::Value x;
    x["time_s"] = e.time_s;
    x["name"] = e.name;
    x["kind"] = e.kind;
    x["points"] = e.points;
    x["score"] = e.score;
    x["detail"] = e.detail;
    events.append(x);
  }
  v["events"] = events;
  v["trajectory"] = track_json(r.trajectory);
  Json::Value objects(Json::objectValue);
  for (const auto& [name, t] : r.object_tracks) objects[name] = track_json(t);
  v["object_tracks"] = objects;
  return v;
}

TaskResult result_from(const Json::Value& v, const std::string& what) {
  for (const char* key : {"task", "score", "time_s", "success", "finished", "end_reason", "counts"})
    if (!v.isMember(key)) throw std::runtime_error(what + ": key '" + key + "' missing");
  TaskResult r;
  r.task = v["task"].asString();
  r.title = v["title"].asString();
  r.task_file = v["task_file"].asString();
  r.world_file = v["world_file"].asString();
  r.node = v["node"].asString();
  r.attempt = v.get("attempt", 1).asInt();
  r.score = v["score"].asInt();
  r.time_s = v["time_s"].asDouble();
  r.time_limit_s = v["time_limit_s"].asDouble();
  r.success = v["success"].asBool();
  r.finished = v["finished"].asBool();
  r.end_reason = v["end_reason"].asString();
  r.damage = v["damage"].asDouble();
  r.collisions = v["collisions"].asInt();
  for (const auto& k : v["counts"].getMemberNames()) r.counts[k] = v["counts"][k].asInt();
  for (const auto& x : v["events"])
    r.events.push_back({x["time_s"].asDouble(), x["name"].asString(), x["kind"].asString(), x["points"].asInt(),
                        x["score"].asInt(), x["detail"].asString()});
  r.trajectory = track_from(v["trajectory"]);
  for (const auto& k : v["object_tracks"].getMemberNames()) r.object_tracks[k] = track_from(v["object_tracks"][k]);
  return r;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// World (x east, y north) → SVG pixels (y down), fitted into the plot.
struct MapFrame {
  double min_x = 0, min_y = 0, max_x = 1, max_y = 1, scale = 1, margin = 20;
  double px(double x) const { return margin + (x - min_x) * scale; }
  double py(double y) const { return margin + (max_y - y) * scale; }
  double width() const { return 2 * margin + (max_x - min_x) * scale; }
  double height() const { return 2 * margin + (max_y - min_y) * scale; }
  void add(double x, double y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
};

// A box's footprint as an SVG polygon.
std::string footprint(const MapFrame& f, double cx, double cy, double sx, double sy, double yaw, const std::string& attrs) {
  std::string pts;
  const double c = std::cos(yaw), s = std::sin(yaw);
  for (const auto& [u, v] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
    const double x = cx + c * u * sx / 2 - s * v * sy / 2;
    const double y = cy + s * u * sx / 2 + c * v * sy / 2;
    pts += num(f.px(x)) + "," + num(f.py(y)) + " ";
  }
  return "<polygon points=\"" + pts + "\" " + attrs + "/>\n";
}

std::string polyline(const MapFrame& f, const std::vector<TrajectoryPoint>& t, const std::string& attrs) {
  std::string pts;
  for (const auto& p : t) pts += num(f.px(p.x_m)) + "," + num(f.py(p.y_m)) + " ";
  return "<polyline points=\"" + pts + "\" fill=\"none\" " + attrs + "/>\n";
}

std::string map_svg(const TaskResult& r, const WorldDescription& w) {
  MapFrame f;
  f.min_x = f.min_y = std::numeric_limits<double>::infinity();
  f.max_x = f.max_y = -std::numeric_limits<double>::infinity();
  for (const auto& wall : w.walls) {
    f.add(wall.from_m[0], wall.from_m[1]);
    f.add(wall.to_m[0], wall.to_m[1]);
  }
  for (const auto& g : w.regions) {
    f.add(g.min_m[0], g.min_m[1]);
    f.add(g.max_m[0], g.max_m[1]);
  }
  for (const auto& b : w.boxes) f.add(b.center_m[0], b.center_m[1]);
  for (const auto& o : w.objects) f.add(o.center_m[0], o.center_m[1]);
  for (const auto& p : r.trajectory) f.add(p.x_m, p.y_m);
  if (!std::isfinite(f.min_x)) f.min_x = f.min_y = -1, f.max_x = f.max_y = 1;
  f.min_x -= 0.5, f.min_y -= 0.5, f.max_x += 0.5, f.max_y += 0.5;
  f.scale = 860.0 / std::max(1e-6, std::max(f.max_x - f.min_x, (f.max_y - f.min_y) * 1.4));
  std::ostringstream s;
  s << "<svg id=\"map\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(f.width()) << "\" height=\""
    << num(f.height()) << "\" style=\"background:#fafafa;border:1px solid #ccc\">\n";
  for (const auto& g : w.regions)
    s << "<rect x=\"" << num(f.px(g.min_m[0])) << "\" y=\"" << num(f.py(g.max_m[1])) << "\" width=\""
      << num((g.max_m[0] - g.min_m[0]) * f.scale) << "\" height=\"" << num((g.max_m[1] - g.min_m[1]) * f.scale)
      << "\" fill=\"#2ca02c\" fill-opacity=\"0.2\" stroke=\"#2ca02c\"><title>region " << escape(g.name)
      << "</title></rect>\n<text x=\"" << num(f.px(g.min_m[0]) + 3) << "\" y=\"" << num(f.py(g.min_m[1]) - 4)
      << "\" font-size=\"11\" fill=\"#1b6e1b\">" << escape(g.name) << "</text>\n";
  for (const auto& st : w.stairs) {
    const double len = st.steps * st.tread_m + st.landing_m;
    const double cx = st.start_m[0] + std::cos(st.yaw_rad) * len / 2, cy = st.start_m[1] + std::sin(st.yaw_rad) * len / 2;
    s << footprint(f, cx, cy, len, st.width_m, st.yaw_rad, "fill=\"#d9c9a3\" stroke=\"#8a7440\"");
  }
  for (const auto& b : w.boxes) s << footprint(f, b.center_m[0], b.center_m[1], b.size_m[0], b.size_m[1], b.yaw_rad, "fill=\"#999\"");
  for (const auto& p : w.props)
    s << footprint(f, p.box.center_m[0], p.box.center_m[1], p.box.size_m[0], p.box.size_m[1], p.box.yaw_rad, "fill=\"#aaa\"");
  for (const auto& wall : w.walls)
    for (const auto& b : wall_boxes(wall))
      if (b.center_m[2] - b.size_m[2] / 2 < 0.3)  // lintels over openings would hide them from above
      s << footprint(f, b.center_m[0], b.center_m[1], b.size_m[0], b.size_m[1], b.yaw_rad, "fill=\"#444\"");
  for (const auto& d : w.doors)
    s << "<line x1=\"" << num(f.px(d.hinge_m[0])) << "\" y1=\"" << num(f.py(d.hinge_m[1])) << "\" x2=\""
      << num(f.px(d.hinge_m[0] + std::cos(d.yaw_rad) * d.width_m)) << "\" y2=\""
      << num(f.py(d.hinge_m[1] + std::sin(d.yaw_rad) * d.width_m))
      << "\" stroke=\"#8b4513\" stroke-width=\"4\"><title>door " << escape(d.name) << "</title></line>\n";
  for (const auto& o : w.objects) {
    s << footprint(f, o.center_m[0], o.center_m[1], o.size_m[0], o.size_m[1], 0.0,
                   "fill=\"none\" stroke=\"#ff7f0e\" stroke-dasharray=\"3,2\"");
    const auto it = r.object_tracks.find(o.name);
    if (it != r.object_tracks.end() && !it->second.empty()) {
      s << polyline(f, it->second, "stroke=\"#ff7f0e\" stroke-width=\"2\" stroke-dasharray=\"6,3\"");
      const auto& e = it->second.back();
      s << footprint(f, e.x_m, e.y_m, o.size_m[0], o.size_m[1], 0.0, "fill=\"#ff7f0e\"");
    }
  }
  if (!r.trajectory.empty()) {
    s << polyline(f, r.trajectory, std::string("id=\"trajectory\" stroke=\"") + kTrajectoryColour +
                                       "\" stroke-width=\"4\" stroke-linejoin=\"round\"");
    const auto& a = r.trajectory.front();
    const auto& b = r.trajectory.back();
    s << "<circle cx=\"" << num(f.px(a.x_m)) << "\" cy=\"" << num(f.py(a.y_m))
      << "\" r=\"6\" fill=\"#1f77b4\"><title>start</title></circle>\n";
    s << "<circle cx=\"" << num(f.px(b.x_m)) << "\" cy=\"" << num(f.py(b.y_m))
      << "\" r=\"6\" fill=\"#000\"><title>end</title></circle>\n";
    for (const auto& e : r.events) {
      auto p = std::lower_bound(r.trajectory.begin(), r.trajectory.end(), e.time_s,
                                [](const TrajectoryPoint& q, double t) { return q.time_s < t; });
      if (p == r.trajectory.end()) --p;
      s << "<circle cx=\"" << num(f.px(p->x_m)) << "\" cy=\"" << num(f.py(p->y_m)) << "\" r=\"4\" fill=\""
        << (e.points >= 0 ? "#2ca02c" : "#9467bd") << "\"><title>" << num(e.time_s) << " s " << escape(e.name) << " "
        << e.points << "</title></circle>\n";
    }
  }
  s << "</svg>\n";
  return s.str();
}

std::string timeline_svg(const TaskResult& r) {
  const double span = std::max(1.0, std::max(r.time_s, r.time_limit_s > 0 ? std::min(r.time_limit_s, r.time_s * 1.1 + 1) : 0.0));
  const double w = 860, x0 = 20;
  std::ostringstream s;
  s << "<svg id=\"timeline\" xmlns=\"http://www.w3.org/2000/svg\" width=\"900\" height=\"70\">\n"
    << "<line x1=\"" << x0 << "\" y1=\"40\" x2=\"" << x0 + w << "\" y2=\"40\" stroke=\"#333\"/>\n";
  for (int t = 0; t <= static_cast<int>(span); t += std::max(1, static_cast<int>(span / 10)))
    s << "<text x=\"" << num(x0 + w * t / span) << "\" y=\"62\" font-size=\"10\" text-anchor=\"middle\">" << t
      << " s</text>\n";
  for (const auto& e : r.events)
    s << "<circle cx=\"" << num(x0 + w * e.time_s / span) << "\" cy=\"40\" r=\"6\" fill=\""
      << (e.points >= 0 ? "#2ca02c" : "#9467bd") << "\"><title>" << num(e.time_s) << " s " << escape(e.name) << " ("
      << e.points << ")</title></circle>\n";
  s << "<line x1=\"" << num(x0 + w * r.time_s / span) << "\" y1=\"25\" x2=\"" << num(x0 + w * r.time_s / span)
    << "\" y2=\"55\" stroke=\"#000\" stroke-width=\"2\"><title>end: " << escape(r.end_reason) << "</title></line>\n";
  s << "</svg>\n";
  return s.str();
}

const char* kStyle =
    "<style>body{font-family:sans-serif;margin:20px;color:#222}table{border-collapse:collapse}"
    "td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}.ok{color:#1b6e1b}.bad{color:#b00}</style>\n";

void check(bool ok, const std::string& path, const char* what) {
  if (!ok) throw std::runtime_error(path + ": " + what + ": " + std::strerror(errno));
}

JournalEntry entry_from(const Json::Value& v, const std::string& where) {
  if (!v.isObject() || !v.isMember("type")) throw std::runtime_error(where + ": key 'type' missing");
  JournalEntry e;
  e.type = v["type"].asString();
  e.training = v["training"].asString();
  e.trainee_id = v["trainee_id"].asString();
  e.node = v["node"].asString();
  e.attempt = v["attempt"].asInt();
  e.detail = v["detail"].asString();
  if (v.isMember("result")) e.result = result_from(v["result"], where + ": result");
  return e;
}

}  // namespace

std::string task_result_json(const TaskResult& result) { return pretty(result_value(result)); }

TaskResult task_result_from_json(const std::string& json) {
  return result_from(parse(json, "task result"), "task result");
}

std::string task_report_html(const TaskResult& r, const WorldDescription& world) {
  std::ostringstream s;
  s << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Task " << escape(r.task) << "</title>" << kStyle
    << "</head><body>\n<h1>Task " << escape(r.task) << (r.title.empty() ? "" : ": " + escape(r.title)) << "</h1>\n";
  s << "<p>Score <b>" << r.score << "</b>, " << (r.success ? "<span class=ok>success</span>" : "<span class=bad>not achieved</span>")
    << ", " << num(r.time_s) << " s of " << num(r.time_limit_s) << " s, ended by " << escape(r.end_reason)
    << (r.node.empty() ? "" : ", node " + escape(r.node) + " attempt " + std::to_string(r.attempt)) << ". Collisions "
    << r.collisions << ", damage " << num(r.damage) << ". World " << escape(world.name) << ".</p>\n";
  s << "<h2>Trajectory</h2>\n" << map_svg(r, world);
  s << "<h2>Events</h2>\n" << timeline_svg(r);
  s << "<table><tr><th>time</th><th>event</th><th>kind</th><th>points</th><th>score</th><th>detail</th></tr>\n";
  for (const auto& e : r.events)
    s << "<tr><td>" << num(e.time_s) << " s</td><td>" << escape(e.name) << "</td><td>" << escape(e.kind) << "</td><td>"
      << e.points << "</td><td>" << e.score << "</td><td>" << escape(e.detail) << "</td></tr>\n";
  s << "</table>\n</body></html>\n";
  return s.str();
}

std::string training_report_json(const TrainingReport& t) {
  Json::Value v;
  v["training"] = t.training;
  v["title"] = t.title;
  v["file"] = t.file;
  v["trainee_id"] = t.trainee_id;
  v["finished"] = t.finished;
  v["end_reason"] = t.end_reason;
  v["total_score"] = t.total_score;
  Json::Value visits(Json::arrayValue);
  for (std::size_t i = 0; i < t.visits.size(); ++i) {
    const auto& x = t.visits[i];
    Json::Value q;
    q["node"] = x.node;
    q["attempt"] = x.attempt;
    q["task"] = x.result.task;
    q["score"] = x.result.score;
    q["time_s"] = x.result.time_s;
    q["success"] = x.result.success;
    q["end_reason"] = x.result.end_reason;
    q["transition"] = x.transition;
    if (i < t.task_report_files.size()) q["report"] = t.task_report_files[i];
    visits.append(q);
  }
  v["visits"] = visits;
  return pretty(v);
}

std::string training_report_html(const TrainingReport& t) {
  std::ostringstream s;
  s << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Training " << escape(t.training) << "</title>"
    << kStyle << "</head><body>\n<h1>Training " << escape(t.training) << (t.title.empty() ? "" : ": " + escape(t.title))
    << "</h1>\n<p>Trainee <b>" << escape(t.trainee_id) << "</b>, total score <b>" << t.total_score << "</b>, "
    << (t.finished ? "finished: " + escape(t.end_reason) : std::string("in progress")) << ".</p>\n";
  s << "<table><tr><th>#</th><th>node</th><th>attempt</th><th>task</th><th>score</th><th>time</th><th>result</th>"
       "<th>ended by</th><th>next</th></tr>\n";
  for (std::size_t i = 0; i < t.visits.size(); ++i) {
    const auto& x = t.visits[i];
    const std::string task = i < t.task_report_files.size()
                                 ? "<a href=\"" + escape(t.task_report_files[i]) + "\">" + escape(x.result.task) + "</a>"
                                 : escape(x.result.task);
    s << "<tr><td>" << i + 1 << "</td><td>" << escape(x.node) << "</td><td>" << x.attempt << "</td><td>" << task
      << "</td><td>" << x.result.score << "</td><td>" << num(x.result.time_s) << " s</td><td>"
      << (x.result.success ? "<span class=ok>success</span>" : "<span class=bad>not achieved</span>") << "</td><td>"
      << escape(x.result.end_reason) << "</td><td>" << escape(x.transition) << "</td></tr>\n";
  }
  s << "</table>\n</body></html>\n";
  return s.str();
}

void write_file_atomically(const std::string& path, const std::string& content) {
  const std::filesystem::path p(path);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  check(fd >= 0, tmp, "cannot create");
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      errno = err;
      check(false, tmp, "cannot write");
    }
    done += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  check(synced, tmp, "cannot fsync");
  check(::rename(tmp.c_str(), path.c_str()) == 0, path, "cannot rename the temporary onto it");
  const auto dir = p.has_parent_path() ? p.parent_path().string() : std::string(".");
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

void append_journal(const std::string& path, const JournalEntry& e) {
  Json::Value v;
  v["type"] = e.type;
  v["training"] = e.training;
  v["trainee_id"] = e.trainee_id;
  v["node"] = e.node;
  v["attempt"] = e.attempt;
  if (!e.detail.empty()) v["detail"] = e.detail;
  if (e.result) v["result"] = result_value(*e.result);
  const std::string line = compact(v) + "\n";
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  check(fd >= 0, path, "cannot open the journal");
  const ssize_t n = ::write(fd, line.data(), line.size());
  const int err = errno;
  const bool synced = n == static_cast<ssize_t>(line.size()) && ::fsync(fd) == 0;
  ::close(fd);
  errno = err;
  check(synced, path, "cannot append to the journal");
}

std::vector<JournalEntry> read_journal(const std::string& path) {
  std::vector<JournalEntry> out;
  std::ifstream in(path, std::ios::binary);
  if (!in) return out;
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  std::size_t from = 0;
  int line = 0;
  while (from < text.size()) {
    ++line;
    const auto nl = text.find('\n', from);
    if (nl == std::string::npos) break;  // torn: the writer died mid-line
    const std::string where = path + ":" + std::to_string(line);
    const std::string one = text.substr(from, nl - from);
    from = nl + 1;
    if (one.empty()) continue;
    try {
      out.push_back(entry_from(parse(one, where), where));
    } catch (const std::runtime_error&) {
      if (from >= text.size()) break;  // a torn last line
      throw;
    }
  }
  return out;
}

}  // namespace rise::sim::training
