// The Console Builder end to end ("[console_builder]"): an emulated console
// (rise-panel emulate on socketcand over loopback) whose firmware has a horn
// on button.7, which the definition being edited (a copy of
// rise_console.yaml) does not bind, pressed for 0.3 s every 1.2 s; the
// server reads the console itself (--console-source); the page learns that
// signal, the user names it, picks kind and safe value, saves; the saved file
// loads in `rise-panel check`, and a rise-hild started with it publishes
// PanelState over LCM in which the new control follows the press.

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "browser_support.hpp"
#include "process/child_process.hpp"
#include "web_peer.hpp"

using namespace rise::instructor_test;
using rise::process::ChildProcess;

namespace {

// rise_console.yaml with a horn on button.7: what the console's firmware has.
std::string firmware_definition(const std::string& shipped) {
  std::string text = shipped;
  const auto at = text.find("\nfeedback:");
  text.insert(at, "  - {name: horn, kind: button, signal: button.7, safe: false}\n");
  return text;
}

bool horn(const rise_msgs::PanelState& p, bool pressed) {
  return std::any_of(p.buttons.begin(), p.buttons.end(),
                     [&](const rise_msgs::PanelButton& b) { return b.name == "horn" && b.pressed == pressed; });
}

}  // namespace

TEST_CASE("the console builder learns an unbound button, saves it, and rise-hild publishes it",
          "[instructor][console_builder]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  char tmpl[] = "/tmp/rise-console-builder-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const fs::path consoles = dir / "consoles", designs = dir / "designs";
  fs::create_directories(consoles);
  fs::create_directories(designs);
  const std::string shipped = read_file(kSource + "/panels/definitions/rise_console.yaml");
  std::ofstream(consoles / "rise_console.yaml") << shipped;
  std::ofstream(dir / "firmware.yaml") << firmware_definition(shipped);
  std::ofstream(dir / "press.txt") << "0.0 mode drive\n0.0 horn released\n0.6 horn pressed\n0.9 horn released\n1.2 horn released\n";
  const std::string bus = "127.0.0.1:" + std::to_string(free_port()) + "/can0";
  ChildProcess emulator({kBin + "/rise-panel", "emulate", "--panel", (dir / "firmware.yaml").string(), "--can",
                         "socketcand+listen://" + bus, "--script", (dir / "press.txt").string(), "--loop"},
                        (dir / "emulator.log").string());
  BuilderServer server(dir, designs, {"--consoles", consoles.string(), "--console-source", "socketcand://" + bus});
  INFO(read_file((dir / "server.log").string()));
  REQUIRE(server.up);

  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/console_builder_check.cjs", server.base(),
                     server.token, screens_dir(), kWeb, consoles.string()},
                    (dir / "console_check.log").string());
  const int node_code = node.wait_for(120000);
  if (node_code < 0) node.stop();
  const auto r = read_result((dir / "console_check.log").string());
  INFO(read_file((dir / "console_check.log").string()));
  INFO(read_file((dir / "emulator.log").string()));
  REQUIRE(node_code == 0);
  REQUIRE_FALSE(r.isMember("error"));
  CHECK(r["page_errors"].size() == 0);
  CHECK(r["status"].asInt() == 200);
  CHECK(r["opened"]["cls"].asString() == "ok");
  CHECK(r["controls"].size() == 11);
  CHECK(r["nav"].size() == 6);
  // Every signal of the rise-can-v1 source, bound or not.
  CHECK(r["signals"].size() == 6 + 32 + 6);
  CHECK(r["learn_shown"].asString().find("move it now") == 0);
  // Learning proposed the horn's button, which the definition does not bind.
  CHECK(r["form"]["signal"].asString() == "button.7");
  CHECK(r["form"]["kind"].asString() == "button");
  CHECK(r["form"]["source"].asString() == "console");
  CHECK(r["proposal"].asString().find("button.7 of console moved") == 0);
  CHECK(r["proposal"].asString().find("already bound") == std::string::npos);
  CHECK(r["proposal"].asString().find("pressed = 1") != std::string::npos);  // it rests released
  // Without a signal the loader's error shows with its line and key, beside the control.
  REQUIRE(r["missing_signal_errors"].size() == 1);
  CHECK(r["missing_signal_errors"][0]["key"].asString() == "controls.horn.signal");
  CHECK(r["missing_signal_errors"][0]["line"].asInt() > 20);
  CHECK(r["error_row"].asString().find("controls.horn.signal") != std::string::npos);
  CHECK(r["save_disabled_on_error"].asBool());
  CHECK(r["valid"]["cls"].asString() == "ok");
  // The preview's horn followed the press (PanelMapper on the edited definition).
  CHECK(text(r["preview_horn"]) == text(parse_json(R"(["false","true"])")));
  CHECK(is_png(screens_dir() + "/console_builder.png"));
  // Saved with its comment; the rest of the file kept.
  const std::string saved = read_file((consoles / "rise_console.yaml").string());
  CHECK(saved == r["saved_text"].asString());
  CHECK(saved.find("  # learned: button.7 of console\n  - {name: horn, kind: button, signal: button.7, safe: false}\n") !=
        std::string::npos);
  CHECK(saved.find("feedback:\n  leds:") != std::string::npos);

  // The saved file loads in the CLI.
  const auto checked = run_program(dir, {"rise-panel", "check", (consoles / "rise_console.yaml").string()});
  INFO(checked.second);
  CHECK(checked.first == 0);
  CHECK(checked.second.find("ok: panel rise-console, 1 sources, 12 controls") != std::string::npos);
  // A malformed one does not, with file:line and key.
  std::string broken_text = firmware_definition(shipped);
  broken_text.replace(broken_text.find("button.7, safe: false"), 21, "button.7, safe: maybe");
  std::ofstream(dir / "broken.yaml") << broken_text;
  const auto broken = run_program(dir, {"rise-panel", "check", (dir / "broken.yaml").string()});
  CHECK(broken.first == 1);
  CHECK(broken.second.find("broken.yaml:") != std::string::npos);
  CHECK(broken.second.find("controls.horn.safe") != std::string::npos);

  // rise-hild with it: the horn in PanelState follows the emulator's presses.
  server.process.stop();
  const std::string id = "cb" + std::to_string(::getpid());
  TraineePeer peer(id);
  REQUIRE(peer.good());
  ChildProcess hild({kBin + "/rise-hild", "--panel", (consoles / "rise_console.yaml").string(), "--can",
                     "socketcand://" + bus, "--id", id, "--lcm", kLcm},
                    (dir / "hild.log").string());
  const bool followed = peer.wait_until(
      [&] {
        const auto& p = peer.daemon_panels;
        return std::any_of(p.begin(), p.end(), [](const auto& m) { return horn(m, true); }) &&
               std::any_of(p.begin(), p.end(), [](const auto& m) { return horn(m, false); });
      },
      15000);
  INFO(read_file((dir / "hild.log").string()));
  CHECK(followed);
  hild.stop();
  emulator.stop();
  fs::remove_all(dir);
}
