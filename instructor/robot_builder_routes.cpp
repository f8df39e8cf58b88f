#include "instructor/robot_builder_routes.hpp"

// Before httplib.h: its <resolv.h> defines _res, a parameter name in Eigen
// (sim/sensor_description.hpp).
#include "instructor/robot_builder.hpp"

#include <httplib.h>
#include <json/json.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <mutex>

#include "instructor/design_files.hpp"
#include "instructor/sandbox.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "process/child_process.hpp"

namespace rise::instructor {

namespace {

using Req = httplib::Request;
using Res = httplib::Response;

struct RobotBuilder {
  RobotBuilderSettings settings;
  DesignFolder folder;
  Sandbox sandbox;
  std::string drive_dir;  ///< the test drive's logs
  std::mutex mutex;
  std::string drive_robot;  ///< the file the test drive runs (guarded by mutex)

  explicit RobotBuilder(const RobotBuilderSettings& s)
      : settings(s),
        folder(s.robots_dir),
        sandbox(process::executable_dir(), s.lcm_url),
        drive_dir((std::filesystem::temp_directory_path() / ("rise-robot-drive-" + std::to_string(::getpid()))).string()) {}
};

void reply(Res& res, const Json::Value& v, int status = 200) {
  res.status = status;
  res.set_content(json_text(v), "application/json");
}

void reply_error(Res& res, int status, const std::string& message) {
  Json::Value v;
  v["error"] = message;
  reply(res, v, status);
}

// The request's file name, after checking it names a .yaml of the folder;
// "" after replying.
std::string robot_name(const DesignFolder& folder, const Req& req, Res& res) {
  if (folder.dir().empty()) {
    reply_error(res, 503, "no robots folder (rise-instructor serve --robots DIR)");
    return "";
  }
  const std::string name = req.matches[1];
  if (!valid_design_name(name, ".yaml")) {
    reply_error(res, 400, "file '" + name + "': a .yaml name of the robots folder (letters, digits, _ . -)");
    return "";
  }
  return name;
}

// The body and its edits; nullopt after replying 400.
std::optional<std::vector<sim::YamlEdit>> body_edits(const Req& req, Res& res, Json::Value* body) {
  std::string error;
  auto parsed = parse_json_object(req.body, &error);
  if (!parsed) return reply_error(res, 400, error), std::nullopt;
  *body = *parsed;
  auto edits = robot_edits_from_json((*body)["edits"], &error);
  if (!edits) reply_error(res, 400, error);
  return edits;
}

// The file; nullopt after replying 404.
std::optional<DesignText> read_robot(const DesignFolder& folder, const std::string& name, Res& res) {
  try {
    return folder.read(name);
  } catch (const std::exception& e) {
    reply_error(res, 404, e.what());
    return std::nullopt;
  }
}

void handle_read(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = robot_name(folder, req, res);
  if (name.empty()) return;
  const auto file = read_robot(folder, name, res);
  if (!file) return;
  // A file that does not load opens too: its values and the loader's errors show.
  Json::Value v = robot_check_json(check_robot(file->text, {}, folder.path(name)));
  v["file"] = name;
  v["version"] = file->version;
  v["text"] = file->text;
  reply(res, v);
}

void handle_check(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = robot_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto edits = body_edits(req, res, &body);
  if (!edits) return;
  const auto file = read_robot(folder, name, res);
  if (!file) return;
  reply(res, robot_check_json(check_robot(file->text, *edits, folder.path(name))));
}

Json::Value conflict_json(const std::string& name, const std::string& loaded, const std::string& now) {
  Json::Value v;
  v["file"] = name;
  v["error"] = name + " changed on disk since this page loaded it (version " + loaded + ", now " +
               (now.empty() ? "deleted" : now) + "): not saved. Reload it, or overwrite the other change.";
  v["current_version"] = now;
  return v;
}

void handle_save(DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = robot_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto edits = body_edits(req, res, &body);
  if (!edits) return;
  if (!body["version"].isString()) return reply_error(res, 400, "version: expected the version the page loaded");
  const std::string version = body["version"].asString();
  // The edits apply to the text the page loaded: another change since is a conflict.
  DesignText file;
  try {
    file = folder.read(name);
  } catch (const std::exception&) {
    return reply(res, conflict_json(name, version, ""), 409);
  }
  if (file.version != version) return reply(res, conflict_json(name, version, file.version), 409);
  const RobotCheck check = check_robot(file.text, *edits, folder.path(name));
  // A file rise-sim would refuse is not written over one it loads.
  if (!check.errors.empty()) {
    Json::Value v = robot_check_json(check);
    v["error"] = name + ": not saved: the robot has errors";
    return reply(res, v, 422);
  }
  SaveOutcome saved;
  try {
    saved = folder.save(name, check.yaml, version);
  } catch (const std::exception& e) {
    return reply_error(res, 500, e.what());
  }
  if (saved.status == SaveStatus::Conflict) return reply(res, conflict_json(name, version, saved.version), 409);
  Json::Value v;
  v["file"] = name;
  v["saved"] = true;
  v["version"] = saved.version;
  v["yaml"] = check.yaml;
  reply(res, v);
}

Json::Value drive_json(RobotBuilder& b) {
  const SandboxStatus s = b.sandbox.status();
  Json::Value v;
  v["active"] = s.active;
  v["sim_running"] = s.sim_running;
  v["station"] = b.settings.station;
  v["panel"] = "panel.html?id=" + b.settings.station;
  v["world"] = b.settings.world_file;
  std::lock_guard lock(b.mutex);
  v["robot"] = b.drive_robot;
  return v;
}

// The saved file (the page saves first) in the sandbox world.
void handle_drive(RobotBuilder& b, const Req& req, Res& res) {
  const std::string name = robot_name(b.folder, req, res);
  if (name.empty()) return;
  const std::string path = b.folder.path(name);
  const RobotCheck check = [&] {
    try {
      return check_robot(b.folder.read(name).text, {}, path);
    } catch (const std::exception& e) {
      RobotCheck c;
      c.errors.push_back({name, 0, "", e.what()});
      return c;
    }
  }();
  if (!check.errors.empty()) {
    Json::Value v = robot_check_json(check);
    v["error"] = name + ": rise-sim would refuse it";
    return reply(res, v, 422);
  }
  SandboxRequest r;
  r.station = b.settings.station;
  r.world_file = b.settings.world_file;
  r.robot_file = path;
  r.out_dir = b.drive_dir;
  try {
    b.sandbox.start(r);
  } catch (const std::exception& e) {
    return reply_error(res, 500, e.what());
  }
  {
    std::lock_guard lock(b.mutex);
    b.drive_robot = name;
  }
  reply(res, drive_json(b));
}

}  // namespace

void add_robot_builder_routes(httplib::Server& http, const RobotBuilderSettings& settings) {
  auto b = std::make_shared<RobotBuilder>(settings);
  http.Get("/api/builder/robots", [b](const Req&, Res& res) {
    if (b->folder.dir().empty()) return reply_error(res, 503, "no robots folder (rise-instructor serve --robots DIR)");
    reply(res, robot_files_json(b->folder.dir(), b->folder.list(".yaml")));
  });
  http.Get(R"(/api/builder/robot/([^/]+))", [b](const Req& req, Res& res) { handle_read(b->folder, req, res); });
  http.Post(R"(/api/builder/robot/([^/]+)/check)", [b](const Req& req, Res& res) { handle_check(b->folder, req, res); });
  http.Post(R"(/api/builder/robot/([^/]+)/drive)", [b](const Req& req, Res& res) { handle_drive(*b, req, res); });
  http.Post(R"(/api/builder/robot/([^/]+))", [b](const Req& req, Res& res) { handle_save(b->folder, req, res); });
  http.Get("/api/builder/drive", [b](const Req&, Res& res) { reply(res, drive_json(*b)); });
  http.Post("/api/builder/drive/stop", [b](const Req&, Res& res) {
    b->sandbox.stop();
    reply(res, drive_json(*b));
  });
}

}  // namespace rise::instructor
