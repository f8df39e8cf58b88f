// The Task Builder's endpoints in this process over real HTTP, on copies of
// the shipped tasks in a scratch folder laid out as the source tree (their
// ../../robots paths resolve): the listing with the kinds from the loader's
// table, a task read with its world, a proposed task checked by the loader
// and against its world (errors with the line of the YAML and the key),
// saved atomically and loadable, 409 when the file changed on disk, 422
// when it would not load, and names with '/' refused.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "instructor/design_files.hpp"
#include "instructor/task_builder.hpp"
#include "instructor/web_server.hpp"
#include "sim/training/task_description.hpp"
#include "builder_api_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;

namespace {

const std::string kSrc = RISE_SOURCE_DIR;

// dir/sim/training/examples holds copies of the task files; the folders they
// name (robots, worlds, panels, scenarios) are links to the source tree's.
struct TaskFixture : BuilderApiFixture {
  fs::path designs;

  TaskFixture() : BuilderApiFixture("task-api", "tok-task") {
    designs = copy_shipped("sim/training/examples", fs::path("sim") / "training" / "examples", "");
    fs::create_directories(dir / "instructor");
    for (const char* d : {"sim/robots", "sim/worlds", "panels", "instructor/scenarios"})
      fs::create_directory_symlink(kSrc + "/" + d, dir / d);
    settings.designs_dir = designs.string();
  }
};

std::string body(const Json::Value& task, const std::string& version) {
  Json::Value b;
  b["task"] = task;
  b["version"] = version;
  return text(b);
}

// Line `n` (1-based) of `text`.
std::string line_of(const std::string& yaml, int n) {
  std::istringstream in(yaml);
  std::string l;
  for (int i = 0; i < n; ++i) std::getline(in, l);
  return l;
}

}  // namespace

TEST_CASE("the Task Builder lists tasks with the executor's kinds and opens one with its world", "[instructor][task_builder]") {
  TaskFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  CHECK(http.Get("/api/builder/tasks")->status == 401);
  http.set_default_headers(f.auth());
  const auto listing = parse_json(http.Get("/api/builder/tasks")->body);
  REQUIRE(listing["tasks"].size() == 3);  // not the training
  CHECK(listing["tasks"][0]["file"].asString() == "approach_object.yaml");
  // The kinds are the loader's table, in its order, with their keys.
  const auto& kinds = rise::sim::training::task_event_kinds();
  REQUIRE(listing["kinds"].size() == kinds.size());
  for (Json::ArrayIndex i = 0; i < kinds.size(); ++i) {
    CHECK(listing["kinds"][i]["kind"].asString() == kinds[i].name);
    CHECK(listing["kinds"][i]["params"].size() == kinds[i].params.size());
  }
  CHECK(listing["kinds"][1]["params"][0]["key"].asString() == "after_s");
  const auto opened = parse_json(http.Get("/api/builder/task/approach_object.yaml")->body);
  CHECK(opened["version"].asString() == rise::instructor::content_version(slurp(f.designs / "approach_object.yaml")));
  CHECK(opened["check"]["ok"].asBool());
  CHECK(opened["task"]["robot"].asString() == "../../robots/tracked_eod.yaml");
  CHECK(opened["task"]["events"][0]["kind"].asString() == "reach_region");
  CHECK(opened["task"]["start"]["yaw_deg"].asDouble() == Approx(36.87));
  CHECK(opened["world_json"]["objects"][0]["name"].asString() == "hazardous_object");
  CHECK(http.Get("/api/builder/task/nothing.yaml")->status == 404);
}

TEST_CASE("the Task Builder checks, saves, refuses a stale version and names with '/'", "[instructor][task_builder]") {
  TaskFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  http.set_default_headers(f.auth());
  const std::string url = "/api/builder/task/approach_object.yaml";
  const fs::path file = f.designs / "approach_object.yaml";
  const auto opened = parse_json(http.Get(url)->body);
  Json::Value task = opened["task"];
  const std::string version = opened["version"].asString();

  SECTION("a region the world lacks: the error on the event's line with its key; not saved (422)") {
    task["events"][0]["region"] = "nowhere";
    const auto check = parse_json(http.Post(url + "/check", body(task, version), "application/json")->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "events[0].region");
    CHECK(check["errors"][0]["file"].asString() == "approach_object.yaml");
    const std::string at = line_of(check["yaml"].asString(), check["errors"][0]["line"].asInt());
    CHECK(at.find("{name: near_object, kind: reach_region, region: nowhere") != std::string::npos);
    const std::string before = slurp(file);
    CHECK(http.Post(url, body(task, version), "application/json")->status == 422);
    CHECK(slurp(file) == before);
  }
  SECTION("a kind's threshold the loader refuses: its line and key") {
    task["events"][2]["after_s"] = -3;
    const auto check = parse_json(http.Post(url + "/check", body(task, version), "application/json")->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "events[2].after_s");
    CHECK(line_of(check["yaml"].asString(), check["errors"][0]["line"].asInt()).find("after_s: -3") != std::string::npos);
  }
  SECTION("an unknown event in end_on: the key and the end_on line") {
    task["end_on"].append("no_such_event");
    const auto check = parse_json(http.Post(url + "/check", body(task, version), "application/json")->body);
    REQUIRE(check["errors"].size() == 1);
    CHECK(check["errors"][0]["key"].asString() == "end_on[1]");
    CHECK(line_of(check["yaml"].asString(), check["errors"][0]["line"].asInt()).rfind("end_on:", 0) == 0);
  }
  SECTION("a body of the wrong shape: 400 naming the key") {
    task["events"][1]["points"] = "many";
    const auto r = http.Post(url + "/check", body(task, version), "application/json");
    CHECK(r->status == 400);
    CHECK(parse_json(r->body)["error"].asString() == "task: events[1].points: expected a whole number");
  }
  SECTION("saved at the version read (comments kept, loads as edited), then 409 once someone else wrote it") {
    Json::Value region;
    region["name"] = "drill_zone";
    region["min"] = parse_json("[4.4, 0.1, 0]");
    region["max"] = parse_json("[5.2, 0.9, 1.5]");
    region["comment"] = "added in the builder";
    task["regions"].append(region);
    Json::Value e;
    e["name"] = "in_drill_zone";
    e["kind"] = "reach_region";
    e["region"] = "drill_zone";
    e["points"] = 7;
    task["events"].append(e);
    task["time_limit_s"] = 45;
    auto r = http.Post(url, body(task, version), "application/json");
    REQUIRE(r->status == 200);
    CHECK(parse_json(r->body)["version"].asString() == rise::instructor::content_version(slurp(file)));
    const auto t = rise::sim::training::load_task_description(file.string());
    CHECK(t.time_limit_s == 45);
    CHECK(t.regions.back().name == "drill_zone");
    CHECK(t.region_comments.back() == "added in the builder");
    CHECK(t.events.back().name == "in_drill_zone");
    CHECK(t.events.back().points == 7);
    CHECK(t.comment.rfind("Mission 1 of the example training", 0) == 0);
    CHECK(t.key_comments.at("scenario") == "rise-instructor scenario --task this file");
    // The same version again: the file is no longer at it.
    const std::string saved = slurp(file);
    r = http.Post(url, body(task, version), "application/json");
    CHECK(r->status == 409);
    CHECK(parse_json(r->body)["current_version"].asString() == rise::instructor::content_version(saved));
    CHECK(slurp(file) == saved);
    // A new file must not exist yet ("" version); it then loads.
    r = http.Post("/api/builder/task/drill.yaml", body(task, ""), "application/json");
    CHECK(r->status == 200);
    CHECK(rise::sim::training::load_task_description((f.designs / "drill.yaml").string()).events.size() == 5);
    CHECK(http.Post("/api/builder/task/drill.yaml", body(task, ""), "application/json")->status == 409);
  }
  SECTION("names with a folder, or not .yaml, are refused and nothing is written") {
    for (const char* bad : {"a%2Fb.yaml", "..%2Fx.yaml", "%2Ftmp%2Fx.yaml", "x.yml", ".hidden.yaml"}) {
      INFO(bad);
      const auto r = http.Post(std::string("/api/builder/task/") + bad, body(task, ""), "application/json");
      CHECK(r->status != 200);
      CHECK(http.Get(std::string("/api/builder/task/") + bad)->status != 200);
    }
    CHECK_FALSE(fs::exists(f.dir / "sim" / "training" / "x.yaml"));
    CHECK_FALSE(fs::exists("/tmp/x.yaml"));
    CHECK(http.Post("/api/builder/task/x.yml", body(task, ""), "application/json")->status == 400);
  }
}
