#include "instructor/design_routes.hpp"

#include <httplib.h>

#include "instructor/builder_errors.hpp"
#include "instructor/training_builder.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"

namespace rise::instructor {

using Req = httplib::Request;
using Res = httplib::Response;

void reply_json(Res& res, const Json::Value& v, int status) {
  res.status = status;
  res.set_content(json_text(v), "application/json");
}

void reply_json_error(Res& res, int status, const std::string& message) {
  Json::Value v;
  v["error"] = message;
  reply_json(res, v, status);
}

namespace {

// "designs" of "--designs DIR": what the user calls the folder.
std::string folder_word(const DesignKind& kind) {
  const std::string flag = kind.flag.substr(0, kind.flag.find(' '));
  return flag.substr(flag.find_first_not_of('-'));
}

bool folder_on(const DesignFolder& folder, const DesignKind& kind, Res& res) {
  if (folder.dir().empty())
    reply_json_error(res, 503, "no " + folder_word(kind) + " folder (rise-instructor serve " + kind.flag + ")");
  return !folder.dir().empty();
}

// The file on disk now: its text and version ("" and "" when there is none).
DesignText on_disk(const DesignFolder& folder, const std::string& name) {
  try {
    return folder.read(name);
  } catch (const std::exception&) {
    return {};
  }
}

// The body's check against `disk` (the file it would replace); nullopt
// after replying 400.
std::optional<DesignCheck> body_check(const DesignFolder& folder, const DesignKind& kind, const std::string& name,
                                      const DesignText& disk, const Req& req, Res& res, Json::Value* body) {
  std::string error;
  auto parsed = parse_json_object(req.body, &error);
  if (!parsed) return reply_json_error(res, 400, error), std::nullopt;
  *body = *parsed;
  auto check = kind.check(*body, folder.path(name), disk.text, &error);
  if (!check) reply_json_error(res, 400, error);
  return check;
}

void handle_read(const DesignFolder& folder, const DesignKind& kind, const Req& req, Res& res) {
  const std::string name = design_name(folder, kind, req, res);
  if (name.empty()) return;
  DesignText file;
  try {
    file = folder.read(name);
  } catch (const std::exception& e) {
    return reply_json_error(res, 404, e.what());
  }
  Json::Value v;
  try {
    v = kind.read(file.text, folder.path(name));
  } catch (const std::exception& e) {
    v = Json::Value(Json::objectValue);
    v["load_error"] = e.what();  // not a file of this form: the page shows the text and the error
  }
  v["file"] = name;
  v["version"] = file.version;
  v["text"] = file.text;
  reply_json(res, v);
}

void handle_check(const DesignFolder& folder, const DesignKind& kind, const Req& req, Res& res) {
  const std::string name = design_name(folder, kind, req, res);
  if (name.empty()) return;
  Json::Value body;
  const auto check = body_check(folder, kind, name, on_disk(folder, name), req, res, &body);
  if (check) reply_json(res, design_check_json(*check));
}

Json::Value conflict_json(const std::string& name, const std::string& loaded, const SaveOutcome& saved) {
  Json::Value v;
  v["file"] = name;
  v["error"] = name + " changed on disk since this page loaded it (version " + loaded + ", now " +
               (saved.version.empty() ? "deleted" : saved.version) +
               "): not saved. Reload it, or overwrite the other change.";
  v["current_version"] = saved.version;
  return v;
}

void handle_save(DesignFolder& folder, const DesignKind& kind, const Req& req, Res& res) {
  const std::string name = design_name(folder, kind, req, res);
  if (name.empty()) return;
  // Read once: the check is of the text whose version is compared below.
  const DesignText disk = on_disk(folder, name);
  Json::Value body;
  const auto check = body_check(folder, kind, name, disk, req, res, &body);
  if (!check) return;
  if (!body["version"].isString()) return reply_json_error(res, 400, "version: expected the version the page loaded");
  const std::string loaded = body["version"].asString();
  // Changed on disk since the page loaded it: a conflict, whatever the check
  // says (a builder that edits the disk's text checked edits on another text).
  if (disk.version != loaded) {
    SaveOutcome now;
    now.version = disk.version;
    return reply_json(res, conflict_json(name, loaded, now), 409);
  }
  // A file its program would refuse is not written over one it loads.
  if (!check->errors.empty()) {
    Json::Value v = design_check_json(*check);
    v["error"] = name + ": not saved: the " + kind.singular + " has errors";
    return reply_json(res, v, 422);
  }
  SaveOutcome saved;
  try {
    saved = folder.save(name, check->yaml, loaded);
  } catch (const std::exception& e) {
    return reply_json_error(res, 500, e.what());
  }
  if (saved.status == SaveStatus::Conflict) return reply_json(res, conflict_json(name, loaded, saved), 409);
  Json::Value v;
  v["file"] = name;
  v["saved"] = true;
  v["version"] = saved.version;
  v["yaml"] = check->yaml;
  reply_json(res, v);
}

}  // namespace

std::string design_name(const DesignFolder& folder, const DesignKind& kind, const Req& req, Res& res) {
  if (!folder_on(folder, kind, res)) return "";
  const std::string name = req.matches[1];
  if (!valid_design_name(name, ".yaml")) {
    reply_json_error(res, 400,
                     "file '" + name + "': a .yaml name of the " + folder_word(kind) + " folder (letters, digits, _ . -)");
    return "";
  }
  return name;
}

Json::Value design_check_json(const DesignCheck& check) {
  Json::Value v = check_json(check.yaml, check.errors);
  if (check.extra.isObject())
    for (const auto& key : check.extra.getMemberNames())
      v[key] = check.extra[key];
  return v;
}

void add_design_routes(httplib::Server& http, std::shared_ptr<DesignFolder> folder, DesignKind kind) {
  auto k = std::make_shared<const DesignKind>(std::move(kind));
  http.Get("/api/builder/" + k->plural, [folder, k](const Req&, Res& res) {
    if (folder_on(*folder, *k, res)) reply_json(res, k->list(*folder));
  });
  const std::string one = "/api/builder/" + k->singular + "/([^/]+)";
  http.Get(one, [folder, k](const Req& req, Res& res) { handle_read(*folder, *k, req, res); });
  http.Post(one + "/check", [folder, k](const Req& req, Res& res) { handle_check(*folder, *k, req, res); });
  http.Post(one, [folder, k](const Req& req, Res& res) { handle_save(*folder, *k, req, res); });
}

}  // namespace rise::instructor
