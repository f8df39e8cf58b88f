// The Environment Builder in Debian's chromium (playwright-core): on a copy
// of sim/worlds/building.yaml the page moves door_ab into the opening of
// wall_b_corridor by a mouse drag and typing, shows a loader error inline,
// deletes the hazardous object, adds a region, saves, and meets a file
// changed on disk (409). The saved file is then run: rise-sim's laser,
// straight ahead from the start, now passes where the door stood (it met the
// door before the edit), and a second server started on the file draws the
// door in its new opening, without the object, with the region.

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "browser_support.hpp"
#include "process/child_process.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;
using rise::process::ChildProcess;

namespace {

// The range (m) of the return of scan_0000.pcd (ASCII, sensor frame) nearest
// to straight ahead; -1 when there is none within 1°.
double range_ahead(const fs::path& pcd) {
  std::ifstream in(pcd);
  std::string line;
  bool data = false;
  double best_angle = 1.0 * M_PI / 180, range = -1;
  while (std::getline(in, line)) {
    if (!data) {
      data = line.rfind("DATA ascii", 0) == 0;
      continue;
    }
    std::istringstream p(line);
    double x = 0, y = 0;
    if (!(p >> x >> y)) continue;
    const double angle = std::fabs(std::atan2(y, x));
    if (angle < best_angle) {
      best_angle = angle;
      range = std::hypot(x, y);
    }
  }
  return range;
}

// rise-sim with the skid robot (its 2D laser ahead) in `world`, one scan at
// the start: the range straight ahead, and rise-sim's output.
std::pair<double, std::string> sim_range_ahead(const fs::path& dir, const std::string& world, const std::string& tag) {
  const fs::path scans = dir / ("scans_" + tag);
  const auto [code, out] =
      run_program(dir, {"rise-sim", "--robot", kSource + "/sim/robots/skid4.yaml", "--world", world, "--lcm", "memq://",
                        "--fast", "--duration", "0.2", "--log-level", "warn", "--scan-format", "ascii", "--scan-dir",
                        scans.string()});
  if (code != 0) return {-2, out};
  return {range_ahead(scans / "scan_0000.pcd"), out};
}

// Whether the JSON array `v` holds `want`, to 1e-9.
bool same_numbers(const Json::Value& v, const std::vector<double>& want) {
  if (!v.isArray() || v.size() != want.size()) return false;
  for (Json::ArrayIndex i = 0; i < v.size(); ++i)
    if (!v[i].isNumeric() || std::fabs(v[i].asDouble() - want[i]) > 1e-9) return false;
  return true;
}

Json::Value get_json(const BuilderServer& s, const std::string& path) {
  httplib::Client http("127.0.0.1", s.port);
  auto r = http.Get(path, {{"X-Rise-Token", s.token}});
  return r && r->status == 200 ? parse_json(r->body) : Json::Value();
}

}  // namespace

TEST_CASE("the Environment Builder moves a door, deletes an object and adds a region by mouse and typing, and "
          "rise-sim runs the saved world as edited",
          "[instructor][world_builder]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  char tmpl[] = "/tmp/rise-world-builder-test-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const fs::path worlds = dir / "worlds";
  fs::create_directories(worlds);
  fs::copy_file(kSource + "/sim/worlds/building.yaml", worlds / "building.yaml");
  const std::string file = (worlds / "building.yaml").string();

  // Before the edit the laser, straight ahead from the start, meets door_ab 3 m ahead.
  const auto before = sim_range_ahead(dir, file, "before");
  INFO(before.second);
  CHECK(before.first == Approx(3.0 - 0.35 - 0.02).margin(0.08));

  BuilderServer server(dir, worlds, {"--worlds", worlds.string()});
  INFO(read_file((dir / "server.log").string()));
  REQUIRE(server.up);
  const std::string screens = screens_dir();
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/world_builder_check.cjs", server.base(),
                     server.token, screens, kWeb, worlds.string()},
                    (dir / "world_builder_check.log").string());
  const int node_code = node.wait_for(180000);
  if (node_code < 0) node.stop();
  const auto r = read_result((dir / "world_builder_check.log").string());
  INFO(read_file((dir / "world_builder_check.log").string()));
  REQUIRE(node_code == 0);
  REQUIRE_FALSE(r.isMember("error"));
  CHECK(r["page_errors"].size() == 0);
  CHECK(r["status"].asInt() == 200);
  CHECK(r["opened"].asString() == "ok");
  CHECK(r["entities"].size() == 13);  // 9 walls, a door, the stairs, an object, a region
  CHECK(text(r["nav"]) == text(parse_json(R"(["console_builder.html","robot_builder.html","world_builder.html","task_builder.html","training.html","/"])")));
  // Both views drew something: the map and the 3D view are not one flat colour.
  CHECK(r["stats_before"]["map"]["variance"].asDouble() > 100);
  CHECK(r["stats_before"]["view3d"]["variance"].asDouble() > 50);
  CHECK(same_numbers(r["door_before"]["center"], {3, 0, 1}));

  // The door: selected by a click, dragged (its hinge snapped onto the opening's edge), turned and narrowed by typing.
  CHECK(r["selected"].asString() == "doors[0] door_ab");
  CHECK(same_numbers(r["hinge_after_drag"], {6, 3}));
  CHECK(same_numbers(r["door_after"]["center"], {6.45, 3, 1}));
  CHECK(r["door_after"]["yaw"].asDouble() == 0.0);
  // A width the loader refuses: its words, on the door's line, with the key.
  REQUIRE(r["bad_width_errors"].size() == 1);
  const auto& bad = r["bad_width_errors"][0];
  CHECK(bad["key"].asString() == "doors[0].width");
  CHECK(bad["text"].asString() ==
        "building.yaml:" + std::to_string(bad["line"].asInt()) + ": doors[0].width: must be > 0");
  CHECK(bad["line"].asInt() > 10);
  CHECK(r["bad_width_save_disabled"].asBool());
  CHECK(text(r["bad_width_marked"]) == text(parse_json(R"(["door_ab"])")));
  // The object deleted, the region added and named.
  CHECK(r["selected_object"].asString() == "objects[0] hazardous_object");
  CHECK(same_numbers(r["new_region"]["min"], {-3, -2, 0}));
  CHECK(same_numbers(r["new_region"]["max"], {-2, -1, 1.5}));
  const std::string after = text(r["entities_after"]);
  CHECK(after.find("hazardous_object") == std::string::npos);
  CHECK(after.find("drop_zone") != std::string::npos);
  CHECK(r["stats_after"]["view3d"]["variance"].asDouble() > 50);

  // The saved file: the edits, in the loader's keys, the comments kept.
  const std::string saved = r["disk_after_save"].asString();
  CHECK(saved.find("  - {name: door_ab, hinge: [6, 3], width: 0.9, height: 2, thickness: 0.04, yaw_deg: 0, "
                   "open_deg_max: 100, break_torque_nm: 900, mass_kg: 20}\n") != std::string::npos);
  CHECK(saved.find("  - {name: drop_zone, min: [-3, -2, 0], max: [-2, -1, 1.5]}\n") != std::string::npos);
  CHECK(saved.find("hazardous_object") == std::string::npos);
  CHECK(saved.rfind("# A small building (see sim/README.md for the format).", 0) == 0);
  CHECK(saved.find("  # Room A / room B, with the door's opening at y -0.55..0.55.\n") != std::string::npos);

  // Someone else's change on disk: refused, said so, the file left as they wrote it.
  CHECK(r["conflict_text"].asString().find("building.yaml changed on disk since this page loaded it") !=
        std::string::npos);
  CHECK(r["save_state_after_conflict"].asString() == "not saved: changed on disk");
  const std::string disk = read_file(file);
  CHECK(disk == r["disk_after_conflict"].asString());
  CHECK(disk == saved + "# changed by someone else\n");
  CHECK(r["region_after_reload"]["max"][2].asDouble() == 1.5);  // the page's unsaved 2.5 gone, the disk's shown

  // rise-sim runs the saved world: straight ahead the laser now passes the
  // open doorway into room B and meets its east wall (x 9 - 7.5 cm).
  const auto edited = sim_range_ahead(dir, file, "after");
  INFO(edited.second);
  CHECK(edited.first == Approx(9.0 - 0.075 - 0.35).margin(0.08));

  // A second server on the saved world draws the door in wall_b_corridor's opening, no object, the region.
  fs::create_directories(dir / "second");
  BuilderServer second(dir / "second", worlds, {"--worlds", worlds.string(), "--world", file});
  REQUIRE(second.up);
  const Json::Value w = get_json(second, "/api/world");
  Json::Value door;
  for (const auto& b : w["boxes"])
    if (b["kind"].asString() == "door") door = b;
  REQUIRE(door.isObject());
  CHECK(door["name"].asString() == "door_ab");
  CHECK(door["center"][0].asDouble() == Approx(6.45));
  CHECK(door["center"][1].asDouble() == Approx(3.0));
  CHECK(door["size"][0].asDouble() == Approx(0.9));
  CHECK(w["objects"].size() == 0);
  REQUIRE(w["regions"].size() == 2);
  CHECK(w["regions"][1]["name"].asString() == "drop_zone");

  CHECK(is_png(screens + "/world_builder.png"));
  CHECK(is_png(screens + "/world_builder_conflict.png"));
  second.process.stop();
  server.process.stop();
  fs::remove_all(dir);
}
