#include "instructor/world_builder_routes.hpp"

#include <httplib.h>

#include <memory>

#include "instructor/design_files.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "instructor/world_builder.hpp"

namespace rise::instructor {

namespace {

using Req = httplib::Request;
using Res = httplib::Response;

// ---- routes ------------------------------------------------------------------

void reply(Res& res, const Json::Value& v, int status = 200) {
  res.status = status;
  res.set_content(json_text(v), "application/json");
}

void reply_error(Res& res, int status, const std::string& message) {
  Json::Value v;
  v["error"] = message;
  reply(res, v, status);
}

bool folder_on(const DesignFolder& folder, Res& res) {
  if (folder.dir().empty()) reply_error(res, 503, "no worlds folder (rise-instructor serve --worlds DIR)");
  return !folder.dir().empty();
}

// The request's file name, after checking it names a .yaml of the folder; "" after replying.
std::string world_name(const DesignFolder& folder, const Req& req, Res& res) {
  if (!folder_on(folder, res)) return "";
  const std::string name = req.matches[1];
  if (!valid_design_name(name, ".yaml")) {
    reply_error(res, 400, "file '" + name + "': a .yaml name of the worlds folder (letters, digits, _ . -)");
    return "";
  }
  return name;
}

// The file's text on disk now ("" when there is none yet): whose comments the save keeps.
std::string disk_text(const DesignFolder& folder, const std::string& name) {
  try {
    return folder.read(name).text;
  } catch (const std::exception&) {
    return "";
  }
}

// check_json's {yaml, ok, errors} and the loaded world as /api/world draws it (null with errors).
Json::Value world_check_json(const WorldCheck& c) {
  Json::Value v = check_json({c.yaml, c.errors});
  v["view"] = c.loaded ? world_json(*c.loaded) : Json::Value();
  return v;
}

// The body's world; nullopt after replying 400.
std::optional<sim::WorldDescription> body_world(const Req& req, Res& res, Json::Value* body) {
  std::string error;
  auto parsed = parse_json_object(req.body, &error);
  if (!parsed) return reply_error(res, 400, error), std::nullopt;
  *body = *parsed;
  auto world = world_model_from_json((*body)["world"], &error);
  if (!world) reply_error(res, 400, error);
  return world;
}

void handle_list(const DesignFolder& folder, Res& res) {
  if (!folder_on(folder, res)) return;
  Json::Value v, worlds(Json::arrayValue);
  v["dir"] = folder.dir();
  for (const auto& file : folder.list(".yaml")) {
    Json::Value w;
    w["file"] = file;
    try {
      w["name"] = sim::load_world_description(folder.path(file)).name;
    } catch (const std::exception& e) {
      w["error"] = e.what();
    }
    worlds.append(w);
  }
  v["worlds"] = worlds;
  reply(res, v);
}

void handle_read(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = world_name(folder, req, res);
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
    const auto w = sim::parse_world_description(file.text, folder.path(name));
    v["world"] = world_model_json(w);
    v["view"] = world_json(w);
  } catch (const std::exception& e) {
    v["load_error"] = e.what();  // the page shows the text and the error
  }
  reply(res, v);
}

void handle_check(const DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = world_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto world = body_world(req, res, &body);
  if (!world) return;
  reply(res, world_check_json(check_world(*world, folder.path(name), disk_text(folder, name))));
}

void handle_save(DesignFolder& folder, const Req& req, Res& res) {
  const std::string name = world_name(folder, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto world = body_world(req, res, &body);
  if (!world) return;
  if (!body["version"].isString()) return reply_error(res, 400, "version: expected the version the page loaded");
  const WorldCheck check = check_world(*world, folder.path(name), disk_text(folder, name));
  // A file rise-sim would refuse is not written over one it loads.
  if (!check.errors.empty()) {
    Json::Value v = world_check_json(check);
    v["error"] = name + ": not saved: the world has errors";
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

void add_world_builder_routes(httplib::Server& http, const std::string& worlds_dir) {
  auto folder = std::make_shared<DesignFolder>(worlds_dir);
  http.Get("/api/builder/worlds", [folder](const Req&, Res& res) { handle_list(*folder, res); });
  http.Get(R"(/api/builder/world/([^/]+))", [folder](const Req& req, Res& res) { handle_read(*folder, req, res); });
  http.Post(R"(/api/builder/world/([^/]+)/check)",
            [folder](const Req& req, Res& res) { handle_check(*folder, req, res); });
  http.Post(R"(/api/builder/world/([^/]+))", [folder](const Req& req, Res& res) { handle_save(*folder, req, res); });
}

}  // namespace rise::instructor
