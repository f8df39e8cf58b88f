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
#include "instructor/design_routes.hpp"
#include "instructor/sandbox.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "process/child_process.hpp"

namespace rise::instructor {

namespace {

using Req = httplib::Request;
using Res = httplib::Response;

DesignKind robot_kind();

struct RobotBuilder {
  RobotBuilderSettings settings;
  std::shared_ptr<DesignFolder> folder;
  DesignKind kind = robot_kind();
  Sandbox sandbox;
  std::string drive_dir;  ///< the test drive's logs
  std::mutex mutex;
  std::string drive_robot;  ///< the file the test drive runs (guarded by mutex)

  explicit RobotBuilder(const RobotBuilderSettings& s)
      : settings(s),
        folder(std::make_shared<DesignFolder>(s.robots_dir)),
        sandbox(process::executable_dir(), s.lcm_url),
        drive_dir((std::filesystem::temp_directory_path() / ("rise-robot-drive-" + std::to_string(::getpid()))).string()) {}
};

// The Robot Builder's kind of file: the robots of --robots DIR, edited in
// place (the page sends the changed values, applied to the file on disk).
DesignKind robot_kind() {
  DesignKind kind;
  kind.plural = "robots";
  kind.singular = "robot";
  kind.flag = "--robots DIR";
  kind.list = [](const DesignFolder& folder) { return robot_files_json(folder.dir(), folder.list(".yaml")); };
  // A file that does not load opens too: its values and the loader's errors show.
  kind.read = [](const std::string& text, const std::string& path) {
    return robot_check_json(check_robot(text, {}, path));
  };
  kind.check = [](const Json::Value& body, const std::string& path, const std::string& disk,
                  std::string* error) -> std::optional<DesignCheck> {
    const auto edits = robot_edits_from_json(body["edits"], error);
    if (!edits) return std::nullopt;
    RobotCheck c = check_robot(disk, *edits, path);
    Json::Value extra = robot_check_json(c);
    return DesignCheck{std::move(c.yaml), std::move(c.errors), extra};
  };
  return kind;
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
  const std::string name = design_name(*b.folder, b.kind, req, res);
  if (name.empty()) return;
  const std::string path = b.folder->path(name);
  const RobotCheck check = [&] {
    try {
      return check_robot(b.folder->read(name).text, {}, path);
    } catch (const std::exception& e) {
      RobotCheck c;
      c.errors.push_back({name, 0, "", e.what()});
      return c;
    }
  }();
  if (!check.errors.empty()) {
    Json::Value v = robot_check_json(check);
    v["error"] = name + ": rise-sim would refuse it";
    return reply_json(res, v, 422);
  }
  SandboxRequest r;
  r.station = b.settings.station;
  r.world_file = b.settings.world_file;
  r.robot_file = path;
  r.out_dir = b.drive_dir;
  try {
    b.sandbox.start(r);
  } catch (const std::exception& e) {
    return reply_json_error(res, 500, e.what());
  }
  {
    std::lock_guard lock(b.mutex);
    b.drive_robot = name;
  }
  reply_json(res, drive_json(b));
}

}  // namespace

void add_robot_builder_routes(httplib::Server& http, const RobotBuilderSettings& settings) {
  auto b = std::make_shared<RobotBuilder>(settings);
  http.Post(R"(/api/builder/robot/([^/]+)/drive)", [b](const Req& req, Res& res) { handle_drive(*b, req, res); });
  add_design_routes(http, b->folder, b->kind);
  http.Get("/api/builder/drive", [b](const Req&, Res& res) { reply_json(res, drive_json(*b)); });
  http.Post("/api/builder/drive/stop", [b](const Req&, Res& res) {
    b->sandbox.stop();
    reply_json(res, drive_json(*b));
  });
}

}  // namespace rise::instructor
