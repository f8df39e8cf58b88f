#include "instructor/world_builder_routes.hpp"

#include <memory>

#include "instructor/design_routes.hpp"
#include "instructor/web_json.hpp"
#include "instructor/world_builder.hpp"

namespace rise::instructor {

namespace {

// The list: each world file with its name, or the loader's error.
Json::Value world_files_json(const DesignFolder& folder) {
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
  return v;
}

// The Environment Builder's kind of file: the worlds of --worlds DIR.
DesignKind world_kind() {
  DesignKind kind;
  kind.plural = "worlds";
  kind.singular = "world";
  kind.flag = "--worlds DIR";
  kind.list = world_files_json;
  kind.read = [](const std::string& text, const std::string& path) {
    const auto w = sim::parse_world_description(text, path);
    Json::Value v;
    v["world"] = world_model_json(w);
    v["view"] = world_json(w);
    return v;
  };
  kind.check = [](const Json::Value& body, const std::string& path, const std::string& disk,
                  std::string* error) -> std::optional<DesignCheck> {
    const auto world = world_model_from_json(body["world"], error);
    if (!world) return std::nullopt;
    WorldCheck c = check_world(*world, path, disk);
    // The loaded world as /api/world draws it (null with errors).
    Json::Value extra;
    extra["view"] = c.loaded ? world_json(*c.loaded) : Json::Value();
    return DesignCheck{std::move(c.yaml), std::move(c.errors), extra};
  };
  return kind;
}

}  // namespace

void add_world_builder_routes(httplib::Server& http, const std::string& worlds_dir) {
  add_design_routes(http, std::make_shared<DesignFolder>(worlds_dir), world_kind());
}

}  // namespace rise::instructor
