// The Environment Builder's endpoints, in this process over real HTTP: the
// worlds folder listed, a world read as the page edits it, an edit checked
// by the loader of rise-sim (its error with line and key), saved atomically
// keeping the file's comments, refused with 409 when the file changed on
// disk since it was read, 422 when it would not load, and no name outside
// the folder.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "instructor/web_server.hpp"
#include "instructor/world_builder.hpp"
#include "sim/world_description.hpp"
#include "builder_api_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;

namespace {
struct WorldFixture : BuilderApiFixture {
  WorldFixture() : BuilderApiFixture("world-builder-api", "tok-world") {
    settings.worlds_dir = copy_shipped("sim/worlds", "worlds", ".yaml");
    std::ofstream(dir / "worlds" / "broken.yaml") << "world: x\nwalls: 3\n";
  }
  fs::path building() const { return dir / "worlds" / "building.yaml"; }
};

std::string body(const Json::Value& world, const std::string& version) {
  Json::Value b;
  b["world"] = world;
  b["version"] = version;
  return text(b);
}
}  // namespace

TEST_CASE("the world builder lists, reads, checks and saves worlds through the loader of rise-sim",
          "[instructor][world_builder]") {
  WorldFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());

  auto list = http.Get("/api/builder/worlds", f.auth());
  REQUIRE(list);
  REQUIRE(list->status == 200);
  const Json::Value l = parse_json(list->body);
  REQUIRE(l["worlds"].size() == 3);
  CHECK(l["worlds"][0]["file"].asString() == "broken.yaml");
  CHECK(l["worlds"][0]["error"].asString().find("broken.yaml:2: walls: expected a list") != std::string::npos);
  CHECK(l["worlds"][1]["name"].asString() == "building");
  CHECK(http.Get("/api/builder/worlds")->status == 401);  // the token guards it too

  auto read = http.Get("/api/builder/world/building.yaml", f.auth());
  REQUIRE(read->status == 200);
  const Json::Value r = parse_json(read->body);
  const std::string version = r["version"].asString();
  Json::Value world = r["world"];
  REQUIRE(world["doors"].size() == 1);
  CHECK(text(world["doors"][0]["hinge"]) == text(parse_json("[3.0,-0.55]")));
  CHECK(world["doors"][0]["yaw_deg"].asDouble() == 90.0);  // the file's degrees, not 89.99999999999999
  CHECK(world["ceiling"]["follows_walls"].asBool());
  CHECK(r["view"]["boxes"].size() > 10);

  SECTION("unchanged, the check's YAML loads as the same world and keeps the comments") {
    auto c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    REQUIRE(c->status == 200);
    const Json::Value v = parse_json(c->body);
    CHECK(v["ok"].asBool());
    CHECK(v["yaml"].asString().find("  # Room A / room B, with the door's opening at y -0.55..0.55.\n") != std::string::npos);
    CHECK(v["view"]["boxes"].size() == r["view"]["boxes"].size());
  }

  SECTION("a bad value: the loader's error with line and key, and nothing saved (422)") {
    world["doors"][0]["width"] = -1.0;
    auto c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    const Json::Value v = parse_json(c->body);
    CHECK_FALSE(v["ok"].asBool());
    REQUIRE(v["errors"].size() == 1);
    CHECK(v["errors"][0]["key"].asString() == "doors[0].width");
    CHECK(v["errors"][0]["file"].asString() == "building.yaml");
    CHECK(v["errors"][0]["message"].asString() == "must be > 0");
    // The line is the door's line of the YAML it would save.
    const int line = v["errors"][0]["line"].asInt();
    std::istringstream y(v["yaml"].asString());
    std::string text;
    for (int i = 0; i < line; ++i) std::getline(y, text);
    CHECK(text.find("{name: door_ab,") != std::string::npos);
    const std::string before = slurp(f.building());
    auto s = http.Post("/api/builder/world/building.yaml", f.auth(), body(world, version), "application/json");
    CHECK(s->status == 422);
    CHECK(slurp(f.building()) == before);
  }

  SECTION("an opening outside its wall, and a duplicate name: the loader's words") {
    world["walls"][6]["openings"][0]["at_m"] = 5.5;
    auto c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    Json::Value v = parse_json(c->body);
    REQUIRE(v["errors"].size() == 1);
    CHECK(v["errors"][0]["key"].asString() == "walls[6].openings[0]");
    CHECK(v["errors"][0]["message"].asString().find("outside the wall") != std::string::npos);
    world["walls"][6]["openings"][0]["at_m"] = 3.0;
    world["regions"][0]["name"] = "door_ab";
    v = parse_json(http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json")->body);
    REQUIRE(v["errors"].size() == 1);
    CHECK(v["errors"][0]["key"].asString() == "regions[0].name");
    CHECK(v["errors"][0]["message"].asString() == "duplicate name 'door_ab'");
  }

  SECTION("a wrong shape is 400 with the key") {
    world["doors"][0]["hinge"] = "here";
    auto c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    CHECK(c->status == 400);
    CHECK(parse_json(c->body)["error"].asString() == "doors[0].hinge: expected 2 numbers");
  }

  SECTION("an opening that is no object, a follows_walls that is no bool: 400, not jsoncpp's throw (fuzz_world_builder)") {
    world["walls"][0]["openings"] = parse_json("[0, 0]");
    auto c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    CHECK(c->status == 400);
    CHECK(parse_json(c->body)["error"].asString() == "walls[0].openings[0]: expected an object");
    world["walls"][0]["openings"] = Json::Value(Json::arrayValue);
    world["ceiling"] = parse_json(R"({"height_m": 2.6, "follows_walls": "yes"})");
    c = http.Post("/api/builder/world/building.yaml/check", f.auth(), body(world, version), "application/json");
    CHECK(c->status == 400);
    CHECK(parse_json(c->body)["error"].asString() == "ceiling.follows_walls: expected true or false");
  }

  SECTION("a move saved: rise-sim's loader reads the door where it was put; 409 on a file changed since") {
    world["doors"][0]["hinge"] = parse_json("[6, 3]");
    world["doors"][0]["yaw_deg"] = 0;
    world["doors"][0]["width"] = 0.9;
    Json::Value region;
    region["name"] = "drop_zone";
    region["min"] = parse_json("[-3, -2, 0]");
    region["max"] = parse_json("[-2, -1, 1]");
    world["regions"].append(region);
    world["objects"] = Json::Value(Json::arrayValue);  // the hazardous object deleted
    auto s = http.Post("/api/builder/world/building.yaml", f.auth(), body(world, version), "application/json");
    REQUIRE(s->status == 200);
    const Json::Value v = parse_json(s->body);
    CHECK(v["version"].asString() != version);
    const auto saved = rise::sim::load_world_description(f.building().string());
    REQUIRE(saved.doors.size() == 1);
    CHECK(saved.doors[0].hinge_m == std::array<double, 2>{6, 3});
    CHECK(saved.doors[0].yaw_rad == 0.0);
    CHECK(saved.objects.empty());
    REQUIRE(saved.regions.size() == 2);
    CHECK(saved.regions[1].name == "drop_zone");
    CHECK(slurp(f.building()).rfind("# A small building", 0) == 0);
    // Saved again with the old version: someone else's change would be lost.
    auto again = http.Post("/api/builder/world/building.yaml", f.auth(), body(world, version), "application/json");
    CHECK(again->status == 409);
    CHECK(parse_json(again->body)["error"].asString().find("building.yaml changed on disk since this page loaded it") !=
          std::string::npos);
    CHECK(parse_json(again->body)["current_version"].asString() == v["version"].asString());
  }

  SECTION("a file changed on disk by another editor: 409, the file left as they wrote it") {
    std::ofstream(f.building(), std::ios::app) << "# someone else\n";
    const std::string theirs = slurp(f.building());
    auto s = http.Post("/api/builder/world/building.yaml", f.auth(), body(world, version), "application/json");
    CHECK(s->status == 409);
    CHECK(slurp(f.building()) == theirs);
  }

  SECTION("names outside the folder, or not .yaml, are refused") {
    for (const char* bad : {"/api/builder/world/..%2Fbuilding.yaml", "/api/builder/world/a%2Fb.yaml",
                            "/api/builder/world/.hidden.yaml", "/api/builder/world/building.yml"}) {
      INFO(bad);
      auto g = http.Get(bad, f.auth());
      REQUIRE(g);
      CHECK(g->status != 200);
      auto p = http.Post(bad, f.auth(), body(world, version), "application/json");
      REQUIRE(p);
      CHECK(p->status != 200);
    }
    CHECK_FALSE(fs::exists(f.dir / "building.yaml"));
    CHECK_FALSE(fs::exists(f.dir / "worlds" / "a"));
    auto g = http.Get("/api/builder/world/.hidden.yaml", f.auth());
    CHECK(g->status == 400);
    CHECK(parse_json(g->body)["error"].asString().find("a .yaml name of the worlds folder") != std::string::npos);
  }
}

TEST_CASE("without a worlds folder the world builder answers 503", "[instructor][world_builder]") {
  WorldFixture f;
  f.settings.worlds_dir = "";
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  CHECK(http.Get("/api/builder/worlds", f.auth())->status == 503);
  CHECK(http.Get("/api/builder/world/building.yaml", f.auth())->status == 503);
}
