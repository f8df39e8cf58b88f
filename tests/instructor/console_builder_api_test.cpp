// The Console Builder's endpoints, in this process over real HTTP: the
// definitions of --consoles listed and read with their controls, a proposed
// control checked by rise-hild's loader (the error with its line, the key
// and the control it belongs to), saved atomically with its comment, 409
// when the file changed on disk since it was read, 422 when it would not
// load, a name with '/' refused, and a live view refused for a count of
// source URLs that is not the definition's. And learning, against a console
// emulated in this process on socketcand and on Modbus/TCP: an axis the
// definition does not bind, moved, is proposed with its invert and deadband.

#include <catch2/catch.hpp>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

#include "instructor/console_builder.hpp"
#include "instructor/design_files.hpp"
#include "instructor/web_server.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/io/modbus_server.hpp"
#include "msgs/clock.hpp"
#include "panels/console_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "builder_api_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;

namespace {

struct ConsoleFixture : BuilderApiFixture {
  ConsoleFixture() : BuilderApiFixture("console-builder", "tok-console") {
    settings.designs_dir = "";
    settings.consoles_dir = copy_shipped("panels/definitions", "consoles", "");
  }
};

// A control as the page sends it.
Json::Value control(const std::string& comment, std::vector<std::pair<std::string, std::string>> fields) {
  Json::Value c;
  c["comment"] = comment;
  c["fields"] = Json::Value(Json::arrayValue);
  for (const auto& [k, v] : fields) {
    Json::Value pair(Json::arrayValue);
    pair.append(k);
    pair.append(v);
    c["fields"].append(pair);
  }
  return c;
}

std::string body(const Json::Value& controls, const std::string& version = "") {
  Json::Value b;
  b["controls"] = controls;
  if (!version.empty()) b["version"] = version;
  return text(b);
}

}  // namespace

TEST_CASE("the console builder lists, reads, checks and saves a definition's controls", "[instructor][console_builder]") {
  ConsoleFixture f;
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  const std::string url = "/api/builder/console/rise_console.yaml";
  CHECK(http.Get(url)->status == 401);
  CHECK(http.Post(url, "{}", "application/json")->status == 401);
  http.set_default_headers(f.auth());

  const auto listing = parse_json(http.Get("/api/builder/consoles", f.auth())->body);
  REQUIRE(listing["files"].isArray());
  CHECK(text(listing["files"]).find("rise_console.yaml") != std::string::npos);
  CHECK(text(listing["files"]).find(".eds") == std::string::npos);  // only .yaml names

  const auto opened = parse_json(http.Get(url, f.auth())->body);
  REQUIRE(opened["controls"].size() == 11);
  CHECK(opened["check"]["ok"].asBool());
  CHECK(opened["controls"][0]["comment"].asString() == "Drive stick: y forward, x right (the robot file maps them to v and ω).");
  CHECK(opened["sources"][0]["protocol"].asString() == "rise-can-v1");
  const std::string version = opened["version"].asString();
  Json::Value controls = opened["controls"];

  SECTION("an error names its line, key and control, and is not saved (422)") {
    // A button without its safe value.
    controls.append(control("horn", {{"name", "horn"}, {"kind", "button"}, {"signal", "button.7"}}));
    const auto check = parse_json(http.Post(url + "/check", body(controls), "application/json")->body);
    REQUIRE_FALSE(check["ok"].asBool());
    REQUIRE(check["errors"].size() == 1);
    const auto& e = check["errors"][0];
    CHECK(e["key"].asString() == "controls.horn.safe");
    CHECK(e["file"].asString() == "rise_console.yaml");
    CHECK(e["control"].asInt() == 11);
    CHECK(e["line"].asInt() == check["lines"][11].asInt());
    CHECK(e["message"].asString().find("missing") != std::string::npos);
    // The line is the one the YAML holds the control on.
    std::istringstream yaml(check["yaml"].asString());
    std::string line;
    for (int i = 0; i < e["line"].asInt(); ++i) std::getline(yaml, line);
    CHECK(line.find("name: horn") != std::string::npos);
    auto r = http.Post(url, body(controls, version), "application/json");
    CHECK(r->status == 422);
    CHECK(slurp(f.dir / "consoles" / "rise_console.yaml") == slurp(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml"));
    // A signal bound twice is the loader's error too, on the second control's line.
    controls[11] = control("", {{"name", "horn"}, {"kind", "button"}, {"signal", "button.2"}, {"safe", "false"}});
    const auto twice = parse_json(http.Post(url + "/check", body(controls), "application/json")->body);
    REQUIRE(twice["errors"].size() == 1);
    CHECK(twice["errors"][0]["control"].asInt() >= 7);
  }
  SECTION("a new control saves with its comment and loads in the loader rise-hild uses") {
    controls.append(control("learned: button.7 of console", {{"name", "horn"}, {"kind", "button"}, {"signal", "button.7"}, {"safe", "false"}}));
    auto r = http.Post(url, body(controls, version), "application/json");
    REQUIRE(r->status == 200);
    const auto saved = parse_json(r->body);
    const std::string on_disk = slurp(f.dir / "consoles" / "rise_console.yaml");
    CHECK(saved["version"].asString() == rise::instructor::content_version(on_disk));
    CHECK(on_disk.find("  # learned: button.7 of console\n  - {name: horn, kind: button, signal: button.7, safe: false}\n") !=
          std::string::npos);
    CHECK(on_disk.find("feedback:\n  leds:") != std::string::npos);  // the rest of the file is kept
    const auto def = rise::panels::load_panel_definition((f.dir / "consoles" / "rise_console.yaml").string());
    REQUIRE(def.find_control("horn"));
    SECTION("a second save at the old version is refused (409) and writes nothing") {
      controls[11] = control("", {{"name", "horn2"}, {"kind", "button"}, {"signal", "button.7"}, {"safe", "false"}});
      r = http.Post(url, body(controls, version), "application/json");
      CHECK(r->status == 409);
      CHECK(parse_json(r->body)["current_version"].asString() == saved["version"].asString());
      CHECK(slurp(f.dir / "consoles" / "rise_console.yaml") == on_disk);
    }
  }
  SECTION("a file changed on disk since it was read is not overwritten (409)") {
    std::ofstream(f.dir / "consoles" / "rise_console.yaml", std::ios::app) << "# edited elsewhere\n";
    const auto r = http.Post(url, body(controls, version), "application/json");
    CHECK(r->status == 409);
    CHECK(slurp(f.dir / "consoles" / "rise_console.yaml").find("# edited elsewhere") != std::string::npos);
  }
  SECTION("names outside the folder and malformed bodies are refused") {
    // A '/' in the name matches no route (404); the handler's own check refuses the rest (400).
    CHECK(http.Get("/api/builder/console/..%2Fconsoles%2Frise_console.yaml", f.auth())->status == 404);
    CHECK(http.Post("/api/builder/console/..%2Fx.yaml", body(controls, ""), "application/json")->status == 404);
    CHECK_FALSE(fs::exists(f.dir / "x.yaml"));
    CHECK_FALSE(rise::instructor::valid_design_name("../x.yaml", ".yaml"));
    CHECK_FALSE(rise::instructor::valid_design_name("a/b.yaml", ".yaml"));
    CHECK(http.Get("/api/builder/console/rise_console_j1939.dbc", f.auth())->status == 400);
    CHECK(http.Post("/api/builder/console/a%20b.yaml", body(controls, version), "application/json")->status == 400);
    CHECK(http.Post("/api/builder/console/..yaml/live", "{}", "application/json")->status == 400);
    CHECK(http.Get("/api/builder/console/missing.yaml", f.auth())->status == 404);
    CHECK(http.Post(url, "not json", "application/json")->status == 400);
    Json::Value bad = controls;
    bad[0]["fields"][0] = "name";
    const auto r = http.Post(url + "/check", body(bad), "application/json");
    CHECK(r->status == 400);
    CHECK(parse_json(r->body)["error"].asString().find("controls[0].fields[0]") != std::string::npos);
  }
  SECTION("the live view needs one source URL per source") {
    const auto r = http.Post(url + "/live", "{}", "application/json");
    CHECK(r->status == 422);
    CHECK(parse_json(r->body)["error"].asString().find("--console-source") != std::string::npos);
    CHECK(http.Get("/api/builder/console_live", f.auth())->status == 404);
  }
  server.stop();
}

TEST_CASE("the live view lists every signal of a rise-can-v1 and a dbc source, bound or not", "[instructor][console_builder]") {
  const std::string dir = std::string(RISE_SOURCE_DIR) + "/panels/definitions/";
  for (const char* file : {"rise_console.yaml", "rise_console_j1939.yaml"}) {
    INFO(file);
    const std::string path = dir + file;
    const auto def = rise::panels::load_panel_definition(path);
    const auto signals = rise::instructor::raw_signals(def, rise::panels::read_panel_controls(slurp(path), path));
    std::size_t bound = 0;
    for (const auto& s : signals) bound += s.bound;
    CHECK(bound == def.controls.size());  // each bound signal once
    CHECK(signals.size() > def.controls.size());  // and the ones not bound yet
    for (const auto& s : signals) CHECK(s.wire.rfind("CAN 0x", 0) == 0);
  }
}

namespace {

// A rise console's firmware (rise_console.yaml on socketcand, or
// rise_console_modbus.yaml as a Modbus/TCP slave) with a winch lever on
// axis.5 (the definition does not bind it), played in this process over
// loopback; the test moves the lever as a person would.
struct WinchConsole {
  rise::panels::PanelDefinition firmware;
  std::unique_ptr<rise::hil::io::CanBus> bus;
  std::unique_ptr<rise::hil::io::ModbusServer> slave;
  std::size_t winch = 0;
  std::mutex mutex;  // guards emulator
  std::unique_ptr<rise::panels::ConsoleEmulator> emulator;
  std::atomic<bool> stop{false};
  std::thread thread;

  WinchConsole(const std::string& file, const std::string& listen_url) {
    std::string text = slurp(std::string(RISE_SOURCE_DIR) + "/panels/definitions/" + file);
    text.insert(text.find("\nfeedback:"), "  - {name: winch, kind: axis, signal: axis.5, safe: 0.0}\n");
    firmware = rise::panels::parse_panel_definition(text, "firmware.yaml");
    winch = *firmware.find_control("winch");
    emulator = std::make_unique<rise::panels::ConsoleEmulator>(firmware, 0);
    if (firmware.sources[0].is_modbus()) {
      slave = std::make_unique<rise::hil::io::ModbusServer>(listen_url, rise::panels::ConsoleEmulator::modbus_table_sizes());
    } else {
      bus = rise::hil::io::open_can_bus(listen_url);
      bus->reopen();
    }
    thread = std::thread([this] {
      while (!stop) {
        {
          std::lock_guard lock(mutex);
          if (slave) emulator->tick_modbus(*slave, rise::msgs::monotonic_us());
          else emulator->tick(*bus, rise::msgs::monotonic_us());
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
  }
  ~WinchConsole() {
    stop = true;
    thread.join();
  }
  void set(float value) {
    rise::panels::TimelineEvent e;
    e.control = winch;
    e.axis = value;
    std::lock_guard lock(mutex);
    emulator->apply(e);
  }
};

}  // namespace

TEST_CASE("learning an axis proposes its signal, invert and deadband from its rest, min and max",
          "[instructor][console_builder]") {
  ConsoleFixture f;
  const std::string port = std::to_string(free_port());
  // The same console on CAN (socketcand) and on Modbus/TCP: the same signals.
  const bool modbus = GENERATE(false, true);
  const std::string file = modbus ? "rise_console_modbus.yaml" : "rise_console.yaml";
  INFO(file);
  WinchConsole console(file, modbus ? "modbus+tcp-listen://127.0.0.1:" + port + "?unit=1"
                                    : "socketcand+listen://127.0.0.1:" + port + "/can0");
  f.settings.console_sources = {modbus ? "modbus+tcp://127.0.0.1:" + port + "?unit=1"
                                       : "socketcand://127.0.0.1:" + port + "/can0"};
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  http.set_default_headers(f.auth());
  const auto live = http.Post("/api/builder/console/" + file + "/live", "{}", "application/json");
  REQUIRE(live->status == 200);
  const auto signals = parse_json(live->body)["signals"];
  CHECK(signals.size() == 6 + 32 + 6);
  CHECK(signals[5]["signal"].asString() == "axis.5");
  // Where each travels: the frame of its node (0) or the register of its unit.
  CHECK(signals[5]["wire"].asString() == (modbus ? "input register 5" : "CAN 0x120"));
  CHECK(signals[13]["wire"].asString() == (modbus ? "discrete input 7" : "CAN 0x130"));
  CHECK_FALSE(signals[5]["bound"].asBool());
  CHECK(signals[4]["bound"].asBool());
  // Live: the source up, the lever read before anyone learns.
  console.set(0.02f);  // a lever resting a little off centre
  auto state = [&] { return parse_json(http.Get("/api/builder/console_live")->body); };
  const auto wait_for = [&](const std::function<bool(const Json::Value&)>& done) {
    for (int i = 0; i < 100; ++i) {
      if (done(state())) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  };
  REQUIRE(wait_for([](const Json::Value& s) {
    return s["sources"].size() == 1 && s["sources"][0]["connected"].asBool() && !s["sources"][0]["stale"].asBool() &&
           std::fabs(s["values"][5].asDouble() - 0.02) < 0.001;
  }));
  CHECK(http.Post("/api/builder/console_learn", R"({"seconds": 100})", "application/json")->status == 400);
  REQUIRE(http.Post("/api/builder/console_learn", R"({"seconds": 1.5})", "application/json")->status == 200);
  // The window has read the lever at rest (its first snapshot is the rest) ...
  REQUIRE(wait_for([](const Json::Value& s) { return s["learning"].asBool() && s["learn_samples"].asInt() >= 1; }));
  // ... then pulled to its negative end and let go once the window has read
  // it there (the live value and the learn statistics come from one
  // snapshot): it is wired the other way round.
  console.set(-0.9f);
  REQUIRE(wait_for([](const Json::Value& s) {
    return s["learning"].asBool() && std::fabs(s["values"][5].asDouble() + 0.9) < 0.001;
  }));
  console.set(0.02f);
  REQUIRE(wait_for([](const Json::Value& s) { return !s["learning"].asBool() && s.isMember("proposal"); }));
  const auto p = state()["proposal"];
  INFO(text(p));
  CHECK(p["signal"].asString() == "axis.5");
  CHECK(p["kind"].asString() == "axis");
  CHECK_FALSE(p["bound"].asBool());
  CHECK(p["rest"].asDouble() == Approx(0.02).margin(0.001));
  CHECK(p["min"].asDouble() == Approx(-0.9).margin(0.001));
  CHECK(p["invert"].asBool());
  CHECK(p["deadband"].asDouble() == Approx(0.05).margin(0.001));  // 0.02 off centre + 0.03
  CHECK_FALSE(p.isMember("range"));  // rise-can-v1 axes are -1..1 already
  // A learn window in which nothing moves proposes nothing.
  REQUIRE(http.Post("/api/builder/console_learn", R"({"seconds": 0.5})", "application/json")->status == 200);
  REQUIRE(wait_for([](const Json::Value& s) { return s["learning"].asBool(); }));
  REQUIRE(wait_for([](const Json::Value& s) { return !s["learning"].asBool(); }));
  CHECK(state()["proposal"].isMember("none"));
  server.stop();
}

TEST_CASE("a hid source lists every signal of its device's descriptor and learns a button the definition does not bind",
          "[instructor][console_builder]") {
  ConsoleFixture f;
  // The HID golden's pad (a Gravis GamePad Pro: x, y, button_1..10) as a
  // hid-recorder file whose button_7, not bound by pad.yaml, is pressed for
  // 0.3 s every 1.2 s; reports every 20 ms as the pad sends them.
  const std::string golden = slurp(std::string(RISE_SOURCE_DIR) + "/tests/data/replay/hid/pad.hid");
  std::ofstream rec(f.dir / "pad.hid");
  std::istringstream in(golden);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("R:", 0) == 0 || line.rfind("N:", 0) == 0 || line.rfind("I:", 0) == 0) rec << line << "\n";
  for (int i = 0; i < 60; ++i) {
    char event[64];
    std::snprintf(event, sizeof event, "E: %06d.%06d 4 80 80 %s 00\n", i * 20000 / 1000000, i * 20000 % 1000000, i >= 30 && i < 45 ? "40" : "00");
    rec << event;
  }
  rec.close();
  fs::copy_file(std::string(RISE_SOURCE_DIR) + "/tests/data/replay/hid/pad.yaml", f.dir / "consoles" / "pad.yaml");
  f.settings.console_sources = {"replay://" + (f.dir / "pad.hid").string() + "?loop=1000"};
  rise::instructor::WebServer server(f.settings);
  server.start();
  httplib::Client http("127.0.0.1", server.port());
  http.set_default_headers(f.auth());
  const auto live = http.Post("/api/builder/console/pad.yaml/live", "{}", "application/json");
  INFO(live->body);
  REQUIRE(live->status == 200);
  std::map<std::string, Json::Value> signals;
  const Json::Value listed = parse_json(live->body);
  for (const auto& s : listed["signals"]) signals[s["signal"].asString()] = s;
  CHECK(signals.size() == 12);  // x, y, button_1..10 (not the padding)
  REQUIRE(signals.count("button_7"));
  CHECK(signals["button_7"]["kind"].asString() == "button");
  CHECK_FALSE(signals["button_7"]["bound"].asBool());
  CHECK(signals["button_2"]["bound"].asBool());
  CHECK(signals["button_7"]["wire"].asString() == "usage 0x0009:0x0007");  // Button page, button 7
  CHECK(signals["x"]["wire"].asString() == "usage 0x0001:0x0030");
  CHECK(signals["x"]["kind"].asString() == "axis");
  auto state = [&] { return parse_json(http.Get("/api/builder/console_live")->body); };
  const auto wait_for = [&](const std::function<bool(const Json::Value&)>& done) {
    for (int i = 0; i < 100; ++i) {
      if (done(state())) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  };
  REQUIRE(wait_for([](const Json::Value& s) { return s["sources"][0]["connected"].asBool() && !s["sources"][0]["stale"].asBool(); }));
  REQUIRE(http.Post("/api/builder/console_learn", R"({"seconds": 2})", "application/json")->status == 200);
  REQUIRE(wait_for([](const Json::Value& s) { return s["learning"].asBool(); }));
  REQUIRE(wait_for([](const Json::Value& s) { return !s["learning"].asBool() && s.isMember("proposal"); }));
  const auto p = state()["proposal"];
  INFO(text(p));
  CHECK(p["signal"].asString() == "button_7");
  CHECK(p["source"].asString() == "pad");
  CHECK(p["kind"].asString() == "button");
  CHECK(p["pressed_value"].asInt() == 1);
  // Bound and saved: it loads.
  const auto opened = parse_json(http.Get("/api/builder/console/pad.yaml")->body);
  Json::Value controls = opened["controls"];
  controls.append(control("learned: button_7 of pad", {{"name", "wipers"}, {"kind", "button"}, {"signal", "button_7"}, {"safe", "false"}}));
  const auto r = http.Post("/api/builder/console/pad.yaml", body(controls, opened["version"].asString()), "application/json");
  CHECK(r->status == 200);
  const auto def = rise::panels::load_panel_definition((f.dir / "consoles" / "pad.yaml").string());
  REQUIRE(def.find_control("wipers"));
  CHECK(def.controls[*def.find_control("wipers")].hid_signal == "button_7");
  server.stop();
}
