// The Robot Builder's endpoints, in this process over real HTTP, on copies
// of the shipped robots (with their URDFs) in a scratch folder: listed, read
// with their values by path and the 3D view's parts; edits checked by the
// loader rise-sim uses (errors inline with line and key); saved in place
// (comments kept, atomically); refused with 409 when the file changed on
// disk since it was read, 422 when rise-sim would refuse it, 400 for a name
// with '/' or a malformed body; the URDF beside it never written.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "instructor/web_server.hpp"
#include "sim/robot_description.hpp"
#include "builder_api_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;

namespace {

struct RobotFixture : BuilderApiFixture {
  RobotFixture() : BuilderApiFixture("robot-api", "tok-robot") {
    fs::copy(std::string(RISE_SOURCE_DIR) + "/sim/robots", dir / "robots", fs::copy_options::recursive);  // with the URDFs' folders
    settings.robots_dir = (dir / "robots").string();
  }
};

// {version, edits: [{path, value}]}.
std::string edits_body(const std::vector<std::pair<std::string, std::string>>& edits, const std::string& version) {
  Json::Value b, list(Json::arrayValue);
  for (const auto& [path, value] : edits) {
    Json::Value e;
    e["path"] = path;
    e["value"] = value;
    list.append(e);
  }
  b["edits"] = list;
  if (!version.empty()) b["version"] = version;
  return text(b);
}

const Json::Value* find_error(const Json::Value& errors, const std::string& key) {
  for (const auto& e : errors)
    if (e["key"].asString() == key) return &e;
  return nullptr;
}

}  // namespace

TEST_CASE("robot builder: list, read, check with line and key, save in place, 409, 422, names", "[instructor][robot_builder]") {
  RobotFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  const std::string url = "/api/builder/robot/tracked_eod.yaml";
  const fs::path file = f.dir / "robots" / "tracked_eod.yaml", urdf = f.dir / "robots" / "tracked_eod.urdf";
  const std::string shipped = slurp(file), shipped_urdf = slurp(urdf);
  CHECK(http.Get("/api/builder/robots")->status == 401);
  CHECK(http.Post(url, "{}", "application/json")->status == 401);
  http.set_default_headers(f.auth());

  const auto listing = parse_json(http.Get("/api/builder/robots")->body);
  REQUIRE(listing["robots"].size() == 3);
  CHECK(listing["robots"][1]["file"] == "tracked_eod.yaml");
  CHECK(listing["robots"][1]["kind"] == "tracked");

  const auto opened = parse_json(http.Get(url)->body);
  REQUIRE(opened["ok"].asBool());
  const std::string version = opened["version"].asString();
  CHECK(opened["text"] == shipped);
  // Values by path with their lines: control.linear.max_mps is on line 23.
  bool found = false;
  for (const auto& s : opened["scalars"])
    if (s["path"] == "control.linear.max_mps") found = s["value"] == "0.8" && s["line"] == 23;
  CHECK(found);
  // The 3D view's parts: the URDF's links and joints, the tracks, the laser, the cameras.
  const Json::Value& robot = opened["robot"];
  CHECK(robot["kind"] == "tracked");
  CHECK(robot["links"].size() >= 5);
  CHECK(robot["joints"].size() >= 4);
  CHECK(robot["tracks"]["gauge"].asDouble() == Approx(0.52));
  CHECK(robot["laser"]["fov"].asDouble() == Approx(M_PI));
  CHECK(robot["cameras"].size() == 2);

  SECTION("a bad value: inline error with line and key, 422 on save, the file untouched") {
    auto r = http.Post(url + "/check", edits_body({{"control.arm.elbow_pitch.break_torque_nm", "-5"}}, ""), "application/json");
    REQUIRE(r->status == 200);
    const auto check = parse_json(r->body);
    CHECK_FALSE(check["ok"].asBool());
    const Json::Value* e = find_error(check["errors"], "control.arm.elbow_pitch.break_torque_nm");
    REQUIRE(e);
    CHECK((*e)["line"] == 32);
    CHECK((*e)["file"] == "tracked_eod.yaml");
    r = http.Post(url, edits_body({{"control.arm.elbow_pitch.break_torque_nm", "-5"}}, version), "application/json");
    CHECK(r->status == 422);
    CHECK(find_error(parse_json(r->body)["errors"], "control.arm.elbow_pitch.break_torque_nm"));
    // A name not on the panel is the panel's business, but an unknown key is the loader's.
    const auto typo = parse_json(http.Post(url + "/check", edits_body({{"control.linear.max_mpss", "1"}}, ""),
                                           "application/json")->body);
    CHECK_FALSE(typo["ok"].asBool());
    CHECK(typo["errors"][0]["line"] == 23);
    // An edit that cannot apply names its path.
    const auto bad_path = parse_json(http.Post(url + "/check", edits_body({{"control.arm", "1"}}, ""), "application/json")->body);
    CHECK(find_error(bad_path["errors"], "control.arm"));
    CHECK(slurp(file) == shipped);
  }

  SECTION("a save edits the values in place: comments kept, rise-sim's loader reads the edit, the URDF untouched") {
    auto r = http.Post(url, edits_body({{"control.linear.max_mps", "0.3"}, {"control.linear.invert", "true"},
                                        {"control.arm.shoulder_yaw.axis", "drive_x"},
                                        {"control.arm.elbow_pitch.break_torque_nm", "120"},
                                        {"sounds.horn.sample", "air horn"}}, version),
                       "application/json");
    REQUIRE(r->status == 200);
    const auto saved = parse_json(r->body);
    CHECK(saved["version"] != version);
    const std::string now = slurp(file);
    CHECK(now.find("linear:  {axis: drive_y, max_mps: 0.3, invert: true}") != std::string::npos);
    CHECK(now.find("# A tracked EOD robot") == 0);
    CHECK(now.find("# stick right → turn right") != std::string::npos);
    CHECK(slurp(urdf) == shipped_urdf);
    const auto d = rise::sim::load_robot_description(file.string());
    CHECK(d.control.linear.max == 0.3);
    CHECK(d.control.linear.invert);
    CHECK(d.control.arm->joints[0].axis.axis == "drive_x");
    CHECK(d.control.arm->joints[2].break_torque_nm == 120);
    CHECK(d.sounds.back().sample == "air horn");

    // The page's version is stale now: 409, nothing written.
    r = http.Post(url, edits_body({{"control.linear.max_mps", "0.5"}}, version), "application/json");
    CHECK(r->status == 409);
    const auto conflict = parse_json(r->body);
    CHECK(conflict["current_version"] == saved["version"]);
    CHECK(slurp(file) == now);
    // Changed on disk by someone else: 409 too; saving over the version on disk works.
    std::ofstream(file, std::ios::app) << "# an editor's note\n";
    r = http.Post(url, edits_body({{"control.linear.max_mps", "0.5"}}, saved["version"].asString()), "application/json");
    CHECK(r->status == 409);
    const std::string disk = parse_json(r->body)["current_version"].asString();
    r = http.Post(url, edits_body({{"control.linear.max_mps", "0.5"}}, disk), "application/json");
    CHECK(r->status == 200);
    CHECK(slurp(file).find("# an editor's note") != std::string::npos);
    CHECK(rise::sim::load_robot_description(file.string()).control.linear.max == 0.5);
  }

  SECTION("names and bodies the builder refuses") {
    // A name with '/' (decoded or not) reaches no file: 400, or no route (404).
    CHECK(http.Get("/api/builder/robot/..%2Frobots%2Fskid4.yaml")->status >= 400);
    CHECK(http.Post("/api/builder/robot/a%2Fb.yaml", edits_body({}, version), "application/json")->status >= 400);
    CHECK(http.Post("/api/builder/robot/..%2Ftracked_eod.yaml", edits_body({}, version), "application/json")->status >= 400);
    CHECK(http.Get("/api/builder/robot/skid4.urdf")->status == 400);
    CHECK(http.Post("/api/builder/robot/skid4.urdf", edits_body({}, version), "application/json")->status == 400);
    CHECK(http.Get("/api/builder/robot/missing.yaml")->status == 404);
    CHECK(http.Post(url, "not json", "application/json")->status == 400);
    CHECK(http.Post(url, R"({"edits": {"path": 1}, "version": "x"})", "application/json")->status == 400);
    CHECK(http.Post(url, R"({"edits": [{"path": "a"}]})", "application/json")->status == 400);
    CHECK(http.Post(url, R"({"edits": [{"path": "control.linear.max_mps", "value": 0.3}], "version": "x"})",
                    "application/json")->status == 400);  // a number's JSON text is not what was typed
    CHECK(http.Post(url, edits_body({}, ""), "application/json")->status == 400);  // no version
    CHECK(slurp(file) == shipped);
  }
  server.stop();
}

TEST_CASE("robot builder: a robot that does not load opens with its errors; --robots \"\" is off", "[instructor][robot_builder]") {
  RobotFixture f;
  std::ofstream(f.dir / "robots" / "broken.yaml") << "robot: broken\nurdf: skid4.urdf\nwheels:\n  joints: [a, b, c, d]\ncontrol: {}\n";
  {
    rise::instructor::WebServer server(f.settings);
    server.start();
    httplib::Client http("127.0.0.1", server.port());
    http.set_default_headers(f.auth());
    const auto broken = parse_json(http.Get("/api/builder/robot/broken.yaml")->body);
    CHECK_FALSE(broken["ok"].asBool());
    REQUIRE(broken["errors"].size() == 1);
    CHECK(broken["errors"][0]["line"] == 2);
    CHECK(broken["errors"][0]["key"] == "urdf");
    CHECK(broken["scalars"].size() == 6);
    const auto listing = parse_json(http.Get("/api/builder/robots")->body);
    CHECK(listing["robots"][0]["error"].asString().find("broken.yaml:2: urdf:") != std::string::npos);
    server.stop();
  }
  f.settings.robots_dir = "";
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  http.set_default_headers(f.auth());
  CHECK(http.Get("/api/builder/robots")->status == 503);
  CHECK(http.Get("/api/builder/robot/skid4.yaml")->status == 503);
  server.stop();
}
