#include "instructor/task_builder_routes.hpp"

#include <httplib.h>
#include <json/json.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <memory>

#include "instructor/design_files.hpp"
#include "instructor/design_routes.hpp"
#include "instructor/sandbox.hpp"
#include "instructor/task_builder.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "panels/yaml_reader.hpp"
#include "sim/training/task_description.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {

namespace {

namespace fs = std::filesystem;
namespace tr = sim::training;
using Req = httplib::Request;
using Res = httplib::Response;

// The world the task names, drawn by the page (or why it cannot be).
void add_world(const tr::TaskDescription& task, Json::Value* v) {
  try {
    (*v)["world_json"] = world_json(sim::load_world_description(task.world_file));
  } catch (const std::exception& e) {
    (*v)["world_error"] = e.what();
  }
}

// The Task Builder's kind of file: the tasks of --designs DIR (beside the
// trainings that name them).
DesignKind task_kind() {
  DesignKind kind;
  kind.plural = "tasks";
  kind.singular = "task";
  kind.flag = "--designs DIR";
  kind.list = [](const DesignFolder& folder) { return task_files_json(folder.dir(), folder.list(".yaml")); };
  kind.read = [](const std::string& text, const std::string& path) {
    const auto task = tr::parse_task_description(text, path);
    Json::Value v;
    v["task"] = task_json(task);
    v["check"] = check_json(check_task(task, path));
    add_world(task, &v);
    return v;
  };
  kind.check = [](const Json::Value& body, const std::string& path, const std::string&,
                  std::string* error) -> std::optional<DesignCheck> {
    auto task = task_from_json(body["task"], error);
    if (!task) return *error = "task: " + *error, std::nullopt;
    TaskCheck check = check_task(*task, path);
    return DesignCheck{std::move(check.yaml), std::move(check.errors), Json::Value()};
  };
  return kind;
}

struct TaskBuilder {
  std::shared_ptr<DesignFolder> folder;
  DesignKind kind = task_kind();
  Sandbox sandbox;
  std::string out_dir;  ///< the sandbox's logs and reports: one folder per try (try-1, try-2, ...)
  std::string station;  ///< the sandbox's trainee id
  std::atomic<int> tries{0};
};

Json::Value status_json(const SandboxStatus& s) {
  Json::Value v;
  v["active"] = s.active;
  v["station"] = s.station;
  v["sim_running"] = s.sim_running;
  v["task_running"] = s.task_running;
  v["task_done"] = s.task_done;
  v["task_exit_code"] = s.task_exit_code;
  if (s.task_done && fs::exists(s.report_json)) {
    std::string error;
    if (auto report = parse_json_object(panels::read_text_file(s.report_json), &error)) v["report"] = *report;
    v["report_html"] = "/api/builder/try/report.html";
  }
  return v;
}

void handle_try(TaskBuilder& b, const Req& req, Res& res) {
  const std::string name = design_name(*b.folder, b.kind, req, res);
  if (name.empty()) return;
  SandboxRequest request;
  try {
    // The file as saved: what rise-trainer loads is what the user saved.
    const std::string out = (fs::path(b.out_dir) / ("try-" + std::to_string(++b.tries))).string();
    request = sandbox_request_for_task(b.folder->path(name), b.station, out);
    tr::check_against_world(tr::load_task_description(request.task_file),
                            sim::load_world_description(request.world_file));
  } catch (const std::exception& e) {
    return reply_json_error(res, 422, e.what());
  }
  Json::Value v;
  try {
    v = status_json(b.sandbox.start(request));
  } catch (const std::exception& e) {
    return reply_json_error(res, 500, e.what());
  }
  v["file"] = name;
  v["panel"] = "panel.html?id=" + b.station;
  reply_json(res, v);
}

void handle_report_html(TaskBuilder& b, Res& res) {
  const SandboxStatus s = b.sandbox.status();
  if (!s.task_done || !fs::exists(s.report_html)) return reply_json_error(res, 404, "no report yet");
  res.set_content(panels::read_text_file(s.report_html), "text/html");
}

}  // namespace

void add_task_builder_routes(httplib::Server& http, const std::string& designs_dir, const std::string& bin_dir,
                             const std::string& lcm_url) {
  auto b = std::shared_ptr<TaskBuilder>(new TaskBuilder{
      std::make_shared<DesignFolder>(designs_dir), task_kind(), Sandbox(bin_dir, lcm_url),
      (fs::temp_directory_path() / ("rise-task-builder-" + std::to_string(::getpid()))).string(),
      "sandbox-" + std::to_string(::getpid())});
  http.Post(R"(/api/builder/task/([^/]+)/try)", [b](const Req& req, Res& res) { handle_try(*b, req, res); });
  add_design_routes(http, b->folder, b->kind);
  http.Get("/api/builder/try", [b](const Req&, Res& res) { reply_json(res, status_json(b->sandbox.status())); });
  http.Get("/api/builder/try/report.html", [b](const Req&, Res& res) { handle_report_html(*b, res); });
  http.Post("/api/builder/try/stop", [b](const Req&, Res& res) {
    b->sandbox.stop();
    reply_json(res, status_json(b->sandbox.status()));
  });
}

}  // namespace rise::instructor
