#include "instructor/task_builder_routes.hpp"

#include <httplib.h>
#include <json/json.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <memory>

#include "instructor/design_files.hpp"
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

struct TaskBuilder {
  DesignFolder folder;
  Sandbox sandbox;
  std::string out_dir;  ///< the sandbox's logs and reports: one folder per try (try-1, try-2, ...)
  std::string station;  ///< the sandbox's trainee id
  std::atomic<int> tries{0};
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
std::string task_name(const DesignFolder& folder, const Req& req, Res& res) {
  if (folder.dir().empty()) {
    reply_error(res, 503, "no designs folder (rise-instructor serve --designs DIR)");
    return "";
  }
  const std::string name = req.matches[1];
  if (!valid_design_name(name, ".yaml")) {
    reply_error(res, 400, "file '" + name + "': a .yaml name of the designs folder (letters, digits, _ . -)");
    return "";
  }
  return name;
}

// The body's task; nullopt after replying 400.
std::optional<tr::TaskDescription> body_task(const Req& req, Res& res, Json::Value* body) {
  std::string error;
  auto parsed = parse_json_object(req.body, &error);
  if (!parsed) return reply_error(res, 400, error), std::nullopt;
  *body = *parsed;
  auto task = task_from_json((*body)["task"], &error);
  if (!task) reply_error(res, 400, "task: " + error);
  return task;
}

// The world the task names, drawn by the page (or why it cannot be).
void add_world(const tr::TaskDescription& task, Json::Value* v) {
  try {
    (*v)["world_json"] = world_json(sim::load_world_description(task.world_file));
  } catch (const std::exception& e) {
    (*v)["world_error"] = e.what();
  }
}

void handle_read(const TaskBuilder& b, const Req& req, Res& res) {
  const std::string name = task_name(b.folder, req, res);
  if (name.empty()) return;
  DesignText file;
  try {
    file = b.folder.read(name);
  } catch (const std::exception& e) {
    return reply_error(res, 404, e.what());
  }
  Json::Value v;
  v["file"] = name;
  v["version"] = file.version;
  v["text"] = file.text;
  try {
    const auto task = tr::parse_task_description(file.text, b.folder.path(name));
    v["task"] = task_json(task);
    v["check"] = check_json(check_task(task, b.folder.path(name)));
    add_world(task, &v);
  } catch (const std::exception& e) {
    v["load_error"] = e.what();  // the page shows the text and the error
  }
  reply(res, v);
}

void handle_check(const TaskBuilder& b, const Req& req, Res& res) {
  const std::string name = task_name(b.folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto task = body_task(req, res, &body);
  if (!task) return;
  reply(res, check_json(check_task(*task, b.folder.path(name))));
}

void handle_save(TaskBuilder& b, const Req& req, Res& res) {
  const std::string name = task_name(b.folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto task = body_task(req, res, &body);
  if (!task) return;
  if (!body["version"].isString()) return reply_error(res, 400, "version: expected the version the page loaded");
  const TaskCheck check = check_task(*task, b.folder.path(name));
  // A file the trainer would refuse is not written over one it loads.
  if (!check.errors.empty()) {
    Json::Value v = check_json(check);
    v["error"] = name + ": not saved: the task has errors";
    return reply(res, v, 422);
  }
  SaveOutcome saved;
  try {
    saved = b.folder.save(name, check.yaml, body["version"].asString());
  } catch (const std::exception& e) {
    return reply_error(res, 500, e.what());
  }
  Json::Value v;
  v["file"] = name;
  if (saved.status == SaveStatus::Conflict) {
    v["error"] = name + " changed on disk since this page loaded it (version " + body["version"].asString() +
                 ", now " + (saved.version.empty() ? "deleted" : saved.version) +
                 "): not saved. Reload it, or overwrite the other change.";
    v["current_version"] = saved.version;
    return reply(res, v, 409);
  }
  v["saved"] = true;
  v["version"] = saved.version;
  v["yaml"] = check.yaml;
  reply(res, v);
}

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
  const std::string name = task_name(b.folder, req, res);
  if (name.empty()) return;
  SandboxRequest request;
  try {
    // The file as saved: what rise-trainer loads is what the user saved.
    const std::string out = (fs::path(b.out_dir) / ("try-" + std::to_string(++b.tries))).string();
    request = sandbox_request_for_task(b.folder.path(name), b.station, out);
    tr::check_against_world(tr::load_task_description(request.task_file),
                            sim::load_world_description(request.world_file));
  } catch (const std::exception& e) {
    return reply_error(res, 422, e.what());
  }
  Json::Value v;
  try {
    v = status_json(b.sandbox.start(request));
  } catch (const std::exception& e) {
    return reply_error(res, 500, e.what());
  }
  v["file"] = name;
  v["panel"] = "panel.html?id=" + b.station;
  reply(res, v);
}

void handle_report_html(TaskBuilder& b, Res& res) {
  const SandboxStatus s = b.sandbox.status();
  if (!s.task_done || !fs::exists(s.report_html)) return reply_error(res, 404, "no report yet");
  res.set_content(panels::read_text_file(s.report_html), "text/html");
}

}  // namespace

void add_task_builder_routes(httplib::Server& http, const std::string& designs_dir, const std::string& bin_dir,
                             const std::string& lcm_url) {
  auto b = std::shared_ptr<TaskBuilder>(new TaskBuilder{
      DesignFolder(designs_dir), Sandbox(bin_dir, lcm_url),
      (fs::temp_directory_path() / ("rise-task-builder-" + std::to_string(::getpid()))).string(),
      "sandbox-" + std::to_string(::getpid())});
  http.Get("/api/builder/tasks", [b](const Req&, Res& res) {
    if (b->folder.dir().empty()) return reply_error(res, 503, "no designs folder (rise-instructor serve --designs DIR)");
    reply(res, task_files_json(b->folder.dir(), b->folder.list(".yaml")));
  });
  http.Get(R"(/api/builder/task/([^/]+))", [b](const Req& req, Res& res) { handle_read(*b, req, res); });
  http.Post(R"(/api/builder/task/([^/]+)/check)", [b](const Req& req, Res& res) { handle_check(*b, req, res); });
  http.Post(R"(/api/builder/task/([^/]+)/try)", [b](const Req& req, Res& res) { handle_try(*b, req, res); });
  http.Post(R"(/api/builder/task/([^/]+))", [b](const Req& req, Res& res) { handle_save(*b, req, res); });
  http.Get("/api/builder/try", [b](const Req&, Res& res) { reply(res, status_json(b->sandbox.status())); });
  http.Get("/api/builder/try/report.html", [b](const Req&, Res& res) { handle_report_html(*b, res); });
  http.Post("/api/builder/try/stop", [b](const Req&, Res& res) {
    b->sandbox.stop();
    reply(res, status_json(b->sandbox.status()));
  });
}

}  // namespace rise::instructor
