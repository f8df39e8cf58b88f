// The Console Builder against the real kernel HID stack: a Gravis pad made
// through uhid, whose button_7 the definition does not bind, pressed for
// 0.3 s every 1.2 s. The server (in this process, over HTTP) opens the
// definition's hid source as rise-hild would (hidapi / hidraw), lists every
// signal of the pad's report descriptor, learns button_7, binds and saves
// it; a bridge started with the saved file, as rise-hild runs it, maps the
// new control and it follows the press. Runs only inside the VM of
// run_in_vcan_vm.sh (modules hid, uhid, hid-generic), as root.

#include <catch2/catch.hpp>
#include <httplib.h>
#include <json/json.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <thread>

#include "hil/bridge.hpp"
#include "hil/io/uhid_device.hpp"
#include "hil/source_factory.hpp"
#include "instructor/web_server.hpp"
#include "panels/panel_definition.hpp"
#include "tests/hid_test_devices.hpp"

namespace fs = std::filesystem;
namespace io = rise::hil::io;

namespace {

Json::Value parse(const std::string& text) {
  Json::Value v;
  std::string error;
  const std::unique_ptr<Json::CharReader> reader(Json::CharReaderBuilder().newCharReader());
  reader->parse(text.data(), text.data() + text.size(), &v, &error);
  return v;
}

std::string text(const Json::Value& v) { return Json::writeString(Json::StreamWriterBuilder(), v); }

// Polls `done` until it holds (the VM runs under TCG: generous deadlines).
bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

// The pad on /dev/uhid, reporting every 20 ms: centred stick, button_7
// (bit 6 of the buttons' first byte) held 0.3 s of every 1.2 s.
class PressingPad {
 public:
  PressingPad() : device_(settings()) {
    REQUIRE(device_.create() == io::IoStatus::Ok);
    thread_ = std::thread([this] {
      for (int tick = 0; !stop_; ++tick) {
        const uint8_t buttons = tick % 60 >= 30 && tick % 60 < 45 ? 0x40 : 0x00;
        const std::vector<uint8_t> report{0x80, 0x80, buttons, 0x00};
        device_.send_input(report);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    });
  }
  ~PressingPad() {
    stop_ = true;
    thread_.join();
  }

 private:
  static io::UhidSettings settings() {
    io::UhidSettings s;
    s.name = "Gravis GamePad Pro (uhid)";
    s.uniq = "rise-console-builder";
    s.vendor_id = 0x0428;
    s.product_id = 0x4001;
    s.descriptor.assign(std::begin(rise::test::gravis_descriptor), std::end(rise::test::gravis_descriptor));
    return s;
  }
  io::UhidDevice device_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

const char* kPanel =
    "# A Gravis pad as a console.\n"
    "panel: gravis\n"
    "sources:\n"
    "  - {name: pad, protocol: hid, device: 'hid://0428:4001', timeout_ms: 1000}\n"
    "controls:\n"
    "  - {name: stick_x, kind: axis, signal: x, safe: 0}\n"
    "  - {name: red, kind: button, signal: button_1, safe: false}\n";

}  // namespace

TEST_CASE("the console builder learns a uhid pad's unbound button and the saved definition maps it", "[vcan]") {
  PressingPad pad;
  char tmpl[] = "/tmp/console-builder-vm-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  fs::create_directories(dir / "www");
  std::ofstream(dir / "www" / "index.html") << "<!doctype html>";
  fs::create_directories(dir / "consoles");
  std::ofstream(dir / "consoles" / "gravis.yaml") << kPanel;
  // The virtual panel's console (a rise-can-v1 one; not used here).
  std::ofstream(dir / "panel.yaml") << "panel: v\nsources:\n  - {name: console, protocol: rise-can-v1}\n"
                                       "controls:\n  - {name: b, kind: button, signal: button.0, safe: false}\n";

  rise::instructor::WebServerSettings settings;
  settings.port = 0;
  settings.token = "vm";
  settings.web_dir = (dir / "www").string();
  settings.panel_file = (dir / "panel.yaml").string();
  settings.designs_dir = "";
  settings.lcm_url = "memq://";
  settings.consoles_dir = (dir / "consoles").string();
  settings.console_sources = {"-"};  // the definition's device:, as rise-hild --source -
  auto server = std::make_unique<rise::instructor::WebServer>(settings);
  server->start();
  httplib::Client http("127.0.0.1", server->port());
  http.set_default_headers({{"X-Rise-Token", "vm"}});
  http.set_read_timeout(20, 0);

  // The pad shows up in hidraw a moment after UHID_CREATE2.
  std::string live_body;
  REQUIRE(wait_for([&] {
    const auto live = http.Post("/api/builder/console/gravis.yaml/live", "{}", "application/json");
    live_body = live ? live->body : "";
    return live && live->status == 200;
  }));
  const Json::Value listed = parse(live_body);
  INFO(text(listed));
  std::map<std::string, Json::Value> signals;
  for (const auto& s : listed["signals"]) signals[s["signal"].asString()] = s;
  CHECK(signals.size() == 12);  // x, y, button_1..10
  REQUIRE(signals.count("button_7"));
  CHECK_FALSE(signals["button_7"]["bound"].asBool());
  CHECK(signals["button_1"]["bound"].asBool());

  const auto state = [&] { return parse(http.Get("/api/builder/console_live")->body); };
  REQUIRE(wait_for([&] {
    const auto s = state();
    return s["sources"][0]["connected"].asBool() && s["sources"][0]["frames_ok"].asInt() > 10;
  }));
  REQUIRE(http.Post("/api/builder/console_learn", R"({"seconds": 3})", "application/json")->status == 200);
  REQUIRE(wait_for([&] { return state()["learning"].asBool(); }));
  REQUIRE(wait_for([&] {
    const auto s = state();
    return !s["learning"].asBool() && s.isMember("proposal");
  }));
  const Json::Value p = state()["proposal"];
  INFO(text(p));
  CHECK(p["signal"].asString() == "button_7");
  CHECK(p["kind"].asString() == "button");
  CHECK(p["pressed_value"].asInt() == 1);

  // Bound as the page would, and saved.
  const Json::Value opened = parse(http.Get("/api/builder/console/gravis.yaml")->body);
  Json::Value controls = opened["controls"];
  Json::Value wipers;
  wipers["comment"] = "learned: button_7 of pad";
  for (const auto& [k, v] : {std::pair{"name", "wipers"}, {"kind", "button"}, {"signal", "button_7"}, {"safe", "false"}}) {
    Json::Value pair(Json::arrayValue);
    pair.append(k);
    pair.append(v);
    wipers["fields"].append(pair);
  }
  controls.append(wipers);
  Json::Value body;
  body["controls"] = controls;
  body["version"] = opened["version"];
  const auto saved = http.Post("/api/builder/console/gravis.yaml", text(body), "application/json");
  REQUIRE(saved);
  INFO(saved->body);
  REQUIRE(saved->status == 200);
  server->stop();
  server.reset();

  // As rise-hild --panel gravis.yaml --source - runs it.
  const auto def = rise::panels::load_panel_definition((dir / "consoles" / "gravis.yaml").string());
  const auto wipers_index = def.find_control("wipers");
  REQUIRE(wipers_index);
  auto sources = rise::hil::open_panel_sources(def, {"-"}, "");
  rise::hil::Bridge bridge(def, std::move(sources.transports), [](const rise::hil::PanelSnapshot&) {});
  bridge.start();
  bool pressed = false, released = false;
  CHECK(wait_for([&] {
    const auto snap = bridge.snapshot();
    if (!snap.controls[*wipers_index].forced_safe) {
      pressed = pressed || snap.controls[*wipers_index].pressed;
      released = released || !snap.controls[*wipers_index].pressed;
    }
    return pressed && released;
  }));
  bridge.stop();
  fs::remove_all(dir);
}
