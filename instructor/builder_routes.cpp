#include "instructor/builder_routes.hpp"

#include <httplib.h>
#include <json/json.h>

#include <memory>

#include "instructor/design_files.hpp"
#include "instructor/training_builder.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "sim/training/training_graph.hpp"

namespace rise::instructor {

namespace {

using Req = httplib::Request;
using Res = httplib::Response;

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
std::string training_name(const DesignFolder& folder, const Req& req, Res& res) {
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

// The body's graph; nullopt after replying 400.
std::optional<sim::training::TrainingGraph> body_graph(const Req& req, Res& res, Json::Value* body) {
  std::string error;
  auto parsed = parse_json_object(req.body, &error);
  if (!parsed) return reply_error(res, 400, error), std::nullopt;
  *body = *parsed;
  auto graph = training_graph_from_json((*body)["graph"], &error);
  if (!graph) reply_error(res, 400, "graph: " + error);
  return graph;
}

void handle_read(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = training_name(folder, req, res);
  if (name.empty()) return;
  DesignText file;
  try {
    file = folder.read(name);
  } catch (const std::exception& e) {
    return reply_error(res, 404, e.what());
  }
  Json::Value v;
  v["file"] = name;
  v["version"] = file.version;
  v["text"] = file.text;
  try {
    // Unvalidated: a graph with errors opens, and the check lists them
    // beside its entries as rise-trainer check would (tasks loaded).
    const auto g = sim::training::parse_training_graph(file.text, folder.path(name), false, false);
    v["graph"] = training_graph_json(g);
    v["check"] = check_json(check_training(g, folder.path(name)));
  } catch (const std::exception& e) {
    v["load_error"] = e.what();  // not a training graph's form: the page shows the text and the error
  }
  reply(res, v);
}

void handle_check(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = training_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto graph = body_graph(req, res, &body);
  if (!graph) return;
  reply(res, check_json(check_training(*graph, folder.path(name))));
}

void handle_save(DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = training_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto graph = body_graph(req, res, &body);
  if (!graph) return;
  if (!body["version"].isString()) return reply_error(res, 400, "version: expected the version the page loaded");
  const TrainingCheck check = check_training(*graph, folder.path(name));
  // A file the trainer would refuse is not written over one it loads.
  if (!check.errors.empty()) {
    Json::Value v = check_json(check);
    v["error"] = name + ": not saved: the training has errors";
    return reply(res, v, 422);
  }
  SaveOutcome saved;
  try {
    saved = folder.save(name, check.yaml, body["version"].asString());
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

}  // namespace

void add_builder_routes(httplib::Server& http, const std::string& designs_dir) {
  auto folder = std::make_shared<DesignFolder>(designs_dir);
  http.Get("/api/builder/trainings", [folder](const Req&, Res& res) {
    if (folder->dir().empty()) return reply_error(res, 503, "no designs folder (rise-instructor serve --designs DIR)");
    reply(res, training_files_json(folder->dir(), folder->list(".yaml")));
  });
  http.Get(R"(/api/builder/training/([^/]+))", [folder](const Req& req, Res& res) { handle_read(*folder, req, res); });
  http.Post(R"(/api/builder/training/([^/]+)/check)",
            [folder](const Req& req, Res& res) { handle_check(*folder, req, res); });
  http.Post(R"(/api/builder/training/([^/]+))", [folder](const Req& req, Res& res) { handle_save(*folder, req, res); });
}

}  // namespace rise::instructor
