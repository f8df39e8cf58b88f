// A USB gamepad as a panel source: controls bound to the names of its report
// descriptor's signals. Oracle: Android's CTS input tests for the Gravis
// GamePad Pro (shared data): the button and axis events Android derives from
// each raw report.

#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "firmware_protocol/hid_text.hpp"
#include "hil/io/hid_device.hpp"
#include "hil/feedback.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/panel_state_message.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/timeline.hpp"
#include "panels/panel_definition.hpp"
#include "tests/hid_test_devices.hpp"

using rise::hil::PanelMapper;
using rise::hil::PanelSnapshot;
using rise::test::gravis_descriptor;

namespace {

std::string data_file(const std::string& relative) {
  const char* root = std::getenv("RISE_TEST_DATA");
  if (!root) return {};
  const auto p = std::filesystem::path(root) / relative;
  return std::filesystem::exists(p) ? p.string() : std::string{};
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// One CTS test: its raw reports and, per report, the text of its event.
struct CtsTest {
  std::string name;
  std::vector<std::vector<uint8_t>> reports;
  std::vector<std::string> events;
};

// The CTS files use 0x literals (not strict JSON) and a fixed layout: one
// object per test with "name", "reports" (arrays of bytes) and "events".
std::vector<CtsTest> read_cts(const std::string& path) {
  const std::string text = read_text(path);
  std::vector<CtsTest> tests;
  const std::regex name_re("\"name\": \"([^\"]*)\"");
  const std::regex report_re("\\[(0x[0-9a-fA-F]{2}(?:, 0x[0-9a-fA-F]{2})*)\\]");
  const std::regex event_re("\\{\"action\"[^\\n]*");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), name_re); it != std::sregex_iterator(); ++it) {
    CtsTest t;
    t.name = (*it)[1];
    const auto begin = text.begin() + (it->position() + it->length());
    const auto next = text.find("\"name\"", static_cast<std::size_t>(it->position() + it->length()));
    const auto end = next == std::string::npos ? text.end() : text.begin() + static_cast<std::ptrdiff_t>(next);
    const std::string body(begin, end);
    const auto events_at = body.find("\"events\"");
    const std::string reports = body.substr(0, events_at), events = body.substr(events_at);
    for (auto r = std::sregex_iterator(reports.begin(), reports.end(), report_re); r != std::sregex_iterator(); ++r) {
      std::vector<uint8_t> bytes;
      std::stringstream items((*r)[1].str());
      std::string item;
      while (std::getline(items, item, ','))
        bytes.push_back(static_cast<uint8_t>(std::stoul(item, nullptr, 16)));
      t.reports.push_back(bytes);
    }
    for (auto e = std::sregex_iterator(events.begin(), events.end(), event_re); e != std::sregex_iterator(); ++e)
      t.events.push_back(e->str());
    tests.push_back(std::move(t));
  }
  return tests;
}

// Gravis GamePad Pro: a D-pad on x/y and ten buttons (Android's key layout
// Vendor_0428_Product_4001.kl names them).
std::string gamepad_definition(int timeout_ms) {
  std::string text =
      "panel: gravis\n"
      "sources:\n"
      "  - {name: pad, protocol: hid, device: 'hid://0428:4001', timeout_ms: " + std::to_string(timeout_ms) + "}\n"
      "controls:\n"
      "  - {name: hat_x, kind: axis, signal: x, safe: 0}\n"
      "  - {name: hat_y, kind: axis, signal: y, safe: 0}\n";
  const char* keys[] = {"BUTTON_X", "BUTTON_A", "BUTTON_B", "BUTTON_Y", "BUTTON_L1",
                        "BUTTON_R1", "BUTTON_L2", "BUTTON_R2", "BUTTON_SELECT", "BUTTON_START"};
  for (int b = 1; b <= 10; ++b)
    text += "  - {name: " + std::string(keys[b - 1]) + ", kind: button, signal: button_" + std::to_string(b) +
            ", safe: false}\n";
  return text;
}

std::size_t control(const PanelMapper& m, const std::string& name) { return *m.definition().find_control(name); }

}  // namespace

TEST_CASE("hid source reproduces Android CTS button events of the Gravis GamePad Pro", "[hil]") {
  const std::string reg = data_file("hid/android-cts/gravis_gamepadprousb_register.json");
  const std::string keys = data_file("hid/android-cts/gravis_gamepadprousb_keyeventtests.json");
  if (reg.empty() || keys.empty()) {
    WARN("Gravis CTS files not found: skipped");
    return;
  }
  PanelMapper mapper(rise::panels::parse_panel_definition(gamepad_definition(0), "gravis.yaml"));
  mapper.on_connection(0, true, 1000);
  std::string error;
  REQUIRE(mapper.attach_hid(0, rise::firmware_protocol::read_hid_descriptor_file(reg).bytes, &error));
  const auto tests = read_cts(keys);
  REQUIRE(tests.size() == 10);
  int64_t now = 2000;
  std::map<std::string, bool> pressed;
  for (const auto& t : tests) {
    INFO(t.name);
    REQUIRE(t.reports.size() == t.events.size());
    for (std::size_t i = 0; i < t.reports.size(); ++i) {
      now += 1000;
      mapper.on_hid_report(0, t.reports[i], now);
      const PanelSnapshot snap = mapper.evaluate(now);
      REQUIRE_FALSE(snap.failsafe);
      // Each report of a CTS key test presses or releases exactly the key of its event.
      std::vector<std::string> changes;
      for (std::size_t c = 2; c < snap.controls.size(); ++c) {
        const std::string& name = mapper.definition().controls[c].name;
        if (snap.controls[c].pressed != pressed[name])
          changes.push_back((snap.controls[c].pressed ? "DOWN " : "UP ") + name);
        pressed[name] = snap.controls[c].pressed;
      }
      const std::smatch m = [&] {
        std::smatch out;
        std::regex_search(t.events[i], out, std::regex("\"action\": \"(\\w+)\", \"keycode\": \"(\\w+)\""));
        return out;
      }();
      REQUIRE(m.size() == 3);
      CHECK(changes == std::vector<std::string>{m[1].str() + " " + m[2].str()});
    }
  }
}

TEST_CASE("hid source reproduces Android CTS axis values of the Gravis GamePad Pro", "[hil]") {
  const std::string motion = data_file("hid/android-cts/gravis_gamepadprousb_motioneventtests.json");
  if (motion.empty()) {
    WARN("Gravis CTS files not found: skipped");
    return;
  }
  PanelMapper mapper(rise::panels::parse_panel_definition(gamepad_definition(0), "gravis.yaml"));
  mapper.on_connection(0, true, 1000);
  REQUIRE(mapper.attach_hid(0, gravis_descriptor));
  int64_t now = 2000;
  int checked = 0;
  for (const auto& t : read_cts(motion)) {
    INFO(t.name);
    for (std::size_t i = 0; i < t.reports.size(); ++i) {
      now += 1000;
      mapper.on_hid_report(0, t.reports[i], now);
      const PanelSnapshot snap = mapper.evaluate(now);
      REQUIRE_FALSE(snap.failsafe);
      if (t.events.empty()) {  // the neutrality check: centred within Android's flat range
        CHECK(snap.controls[control(mapper, "hat_x")].axis == Approx(0.0).margin(0.01));
        CHECK(snap.controls[control(mapper, "hat_y")].axis == Approx(0.0).margin(0.01));
        continue;
      }
      REQUIRE(i < t.events.size());
      std::smatch m;
      REQUIRE(std::regex_search(t.events[i], m, std::regex("\"AXIS_HAT_([XY])\": (-?[0-9.]+)")));
      const std::string name = m[1] == "X" ? "hat_x" : "hat_y";
      CHECK(snap.controls[control(mapper, name)].axis == Approx(std::stod(m[2])).margin(0.01));
      ++checked;
    }
  }
  CHECK(checked == 8);
}

TEST_CASE("hid source is failsafe until its device is attached and reports", "[hil]") {
  PanelMapper mapper(rise::panels::parse_panel_definition(gamepad_definition(0), "gravis.yaml"));
  mapper.on_connection(0, true, 1000);
  CHECK(mapper.evaluate(1000).failsafe);
  REQUIRE(mapper.attach_hid(0, gravis_descriptor));
  PanelSnapshot snap = mapper.evaluate(1000);
  CHECK(snap.failsafe);
  CHECK(snap.failsafe_reason == "pad: no report yet");
  CHECK(mapper.on_hid_report(0, std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02}, 2000));
  snap = mapper.evaluate(2000);
  REQUIRE_FALSE(snap.failsafe);
  CHECK(snap.controls[control(mapper, "hat_x")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control(mapper, "BUTTON_START")].pressed);
  SECTION("the same report again changes nothing") {
    CHECK_FALSE(mapper.on_hid_report(0, std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02}, 3000));
  }
  SECTION("a short report is counted and dropped") {
    CHECK_FALSE(mapper.on_hid_report(0, std::vector<uint8_t>{0x7f}, 3000));
    CHECK(mapper.evaluate(3000).sources[0].frames_bad() == 1);
    CHECK(mapper.evaluate(3000).controls[control(mapper, "BUTTON_START")].pressed);
  }
  SECTION("unplugging makes every control safe until the device reports again") {
    mapper.on_connection(0, false, 3000);
    snap = mapper.evaluate(3000);
    CHECK(snap.failsafe);
    CHECK(snap.controls[control(mapper, "BUTTON_START")].forced_safe);
    mapper.on_connection(0, true, 4000);
    REQUIRE(mapper.attach_hid(0, gravis_descriptor));
    CHECK(mapper.evaluate(4000).failsafe);
    mapper.on_hid_report(0, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00}, 5000);
    CHECK_FALSE(mapper.evaluate(5000).failsafe);
    CHECK(mapper.evaluate(5000).sources[0].reconnects == 1);
  }
}

TEST_CASE("hid source goes stale after timeout_ms without a report, never with timeout_ms 0", "[hil]") {
  const int timeout_ms = GENERATE(0, 1000);
  PanelMapper mapper(rise::panels::parse_panel_definition(gamepad_definition(timeout_ms), "gravis.yaml"));
  mapper.on_connection(0, true, 0);
  REQUIRE(mapper.attach_hid(0, gravis_descriptor));
  mapper.on_hid_report(0, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00}, 1'000'000);
  CHECK_FALSE(mapper.evaluate(1'900'000).failsafe);
  const PanelSnapshot later = mapper.evaluate(60'000'000);
  CHECK(later.failsafe == (timeout_ms != 0));
  if (timeout_ms != 0) CHECK(later.failsafe_reason.find("pad: stale") == 0);
}

TEST_CASE("hid source with a name its device lacks fails with the name", "[hil]") {
  std::string text = gamepad_definition(0);
  text += "  - {name: throttle, kind: axis, signal: slider, safe: 0}\n";
  PanelMapper mapper(rise::panels::parse_panel_definition(text, "gravis.yaml"));
  mapper.on_connection(0, true, 0);
  std::string error;
  CHECK_FALSE(mapper.attach_hid(0, gravis_descriptor, &error));
  CHECK(error.rfind("pad: control 'throttle': the device has no signal 'slider' (it has: x, y, button_1", 0) == 0);
  mapper.on_hid_report(0, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00}, 1000);
  const PanelSnapshot snap = mapper.evaluate(1000);
  CHECK(snap.failsafe);
  CHECK(snap.failsafe_reason.find("no signal 'slider'") != std::string::npos);
}

TEST_CASE("panel definition checks hid sources", "[hil]") {
  auto load = [](const std::string& source, const std::string& control) {
    return rise::panels::parse_panel_definition(
        "panel: p\nsources:\n  - " + source + "\ncontrols:\n  - " + control + "\n", "p.yaml");
  };
  SECTION("good: timeout_ms defaults to 1000 for hid") {
    const auto def = load("{name: pad, protocol: hid}", "{name: a, kind: axis, signal: x, safe: 0}");
    CHECK(def.sources[0].timeout_ms == 1000);
    CHECK(def.controls[0].hid_signal == "x");
  }
  SECTION("bad") {
    const auto [source, control, message] = GENERATE(table<std::string, std::string, std::string>({
        {"{name: pad, protocol: hid, device: 'usb://1:2'}", "{name: a, kind: axis, signal: x, safe: 0}",
         "p.yaml:3: sources[0].device: expected hid://"},
        {"{name: pad, protocol: rise-can-v1, device: 'hid://1:2'}", "{name: a, kind: axis, signal: axis.0, safe: 0}",
         "p.yaml:3: sources[0].device: only for protocol hid"},
        {"{name: pad, protocol: rise-can-v1, timeout_ms: 0}", "{name: a, kind: axis, signal: axis.0, safe: 0}",
         "p.yaml:3: sources[0].timeout_ms: must be 5..10000"},
        {"{name: pad, protocol: hid, node: 2}", "{name: a, kind: axis, signal: x, safe: 0}",
         "p.yaml:3: sources[0].node: not used by protocol hid"},
    }));
    INFO(source);
    CHECK_THROWS_WITH(load(source, control), Catch::StartsWith(message));
  }
  SECTION("bad: one signal bound twice") {
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(
                          "panel: p\nsources:\n  - {name: pad, protocol: hid}\ncontrols:\n"
                          "  - {name: a, kind: button, signal: button_1, safe: false}\n"
                          "  - {name: b, kind: button, signal: button_1, safe: false}\n",
                          "p.yaml"),
                      Catch::Contains("signal already bound"));
  }
}

TEST_CASE("hid URLs parse VID:PID and the match options", "[hil]") {
  std::string error;
  const auto url = rise::hil::io::parse_hid_url("hid://0428:4001?serial=A1&name=GamePad&interface=2", &error);
  REQUIRE(url);
  CHECK(url->vendor_id == 0x0428);
  CHECK(url->product_id == 0x4001);
  CHECK(url->serial == "A1");
  CHECK(url->name == "GamePad");
  CHECK(url->interface == 2);
  const std::string bad = GENERATE("hid://0428", "hid://0428:40011", "hid://xyz:1", "hid://1:2?colour=red",
                                   "hid://1:2?interface=x", "socketcan://can0");
  INFO(bad);
  CHECK_FALSE(rise::hil::io::parse_hid_url(bad));
}

TEST_CASE("hid emulator's reports put the mapper's controls at the timeline's values", "[hil]") {
  const auto definition = rise::panels::parse_panel_definition(gamepad_definition(0), "gravis.yaml");
  const auto descriptor = rise::firmware_protocol::parse_hid_descriptor(gravis_descriptor);
  REQUIRE(descriptor);
  rise::panels::HidEmulator emulator(definition, 0, descriptor.descriptor);
  PanelMapper mapper(definition);
  mapper.on_connection(0, true, 0);
  REQUIRE(mapper.attach_hid(0, gravis_descriptor));
  const auto timeline = rise::panels::parse_timeline(
      "0 hat_x -1\n0 hat_y 1\n0 BUTTON_A pressed\n0 BUTTON_START pressed\n1 hat_x 0\n1 BUTTON_A released\n",
      "script.txt", definition);
  int64_t now = 1000;
  std::size_t next = 0;
  const auto feed = [&](std::span<const uint8_t> report) {
    mapper.on_hid_report(0, report, now);
    return true;
  };
  while (next < timeline.events.size() && timeline.events[next].time_s == 0.0) emulator.apply(timeline.events[next++]);
  REQUIRE(emulator.tick(now, feed) == 1);
  PanelSnapshot snap = mapper.evaluate(now);
  REQUIRE_FALSE(snap.failsafe);
  CHECK(snap.controls[control(mapper, "hat_x")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control(mapper, "hat_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control(mapper, "BUTTON_A")].pressed);
  CHECK(snap.controls[control(mapper, "BUTTON_START")].pressed);
  CHECK_FALSE(snap.controls[control(mapper, "BUTTON_B")].pressed);
  while (next < timeline.events.size()) emulator.apply(timeline.events[next++]);
  now += 2000;
  REQUIRE(emulator.tick(now, feed) == 1);
  snap = mapper.evaluate(now);
  CHECK(snap.controls[control(mapper, "hat_x")].axis == Approx(0.0).margin(0.01));
  CHECK_FALSE(snap.controls[control(mapper, "BUTTON_A")].pressed);
  CHECK(snap.controls[control(mapper, "BUTTON_START")].pressed);
}

TEST_CASE("panel definition binds a hid source's LEDs to output signals and refuses bad ones", "[hil]") {
  const std::string head =
      "panel: p\nsources:\n  - {name: pad, protocol: hid}\n  - {name: console, protocol: rise-can-v1}\n"
      "controls:\n  - {name: a, kind: button, source: pad, signal: button_1, safe: false}\nfeedback:\n";
  SECTION("good") {
    const auto def = rise::panels::parse_panel_definition(
        head + "  leds: [{name: power, source: pad, signal: usage_0008_0001},\n"
               "         {name: fault, source: console, bit: 1}]\n",
        "p.yaml");
    REQUIRE(def.leds.size() == 2);
    CHECK(def.leds[0].hid_signal == "usage_0008_0001");
    CHECK(def.leds[0].source == 0);
    CHECK(def.leds[0].line == 8);
    CHECK(def.leds[1].hid_signal.empty());
    CHECK(def.leds[1].bit == 1);
  }
  SECTION("bad") {
    const auto [feedback, message] = GENERATE(table<std::string, std::string>({
        {"  leds: [{name: power, source: pad, bit: 0}]\n",
         "p.yaml:8: feedback.leds.power.bit: a hid source's LED is an output signal of the device: signal: NAME"},
        {"  leds: [{name: power, source: console, signal: usage_0008_0001}]\n",
         "p.yaml:8: feedback.leds.power.signal: only for an LED of a hid source (here: bit: 0..31)"},
        {"  leds: [{name: power, source: pad}]\n", "p.yaml:8: feedback.leds.power.signal: missing"},
        {"  leds: [{name: power, source: pad, signal: ''}]\n", "p.yaml:8: feedback.leds.power.signal: must not be empty"},
        {"  leds: [{name: a1, source: pad, signal: usage_0008_0001}, {name: a2, source: pad, signal: usage_0008_0001}]\n",
         "p.yaml:8: feedback.leds.a2.signal: output signal already bound to another LED"},
        {"  displays: [{name: speed, source: pad, index: 0}]\n", "p.yaml:8: feedback.displays.speed.source: a hid source has no displays"},
        {"  buzzer: {source: pad}\n", "p.yaml:8: feedback.buzzer.source: a hid source has no buzzer"},
    }));
    INFO(feedback);
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(head + feedback, "p.yaml"), Catch::StartsWith(message));
  }
}

TEST_CASE("hid feedback sets the LEDs' bits of the device's output report", "[hil]") {
  using rise::hil::build_hid_feedback;
  namespace fp = rise::firmware_protocol;
  const auto definition = rise::panels::parse_panel_definition(
      "panel: p\nsources:\n  - {name: pad, protocol: hid}\n"
      "controls:\n  - {name: stop, kind: button, signal: button_2, role: estop, safe: false}\n"
      "feedback:\n  leds: [{name: power, signal: usage_0008_0001}, {name: fault, signal: usage_0008_0002},\n"
      "         {name: estop, signal: usage_0008_0003}, {name: lamp, signal: usage_0008_0004}]\n",
      "p.yaml");
  const auto parsed = fp::parse_hid_descriptor(rise::test::led_pad_descriptor);
  REQUIRE(parsed);
  const fp::HidOutputEncoder encoder(parsed.descriptor);
  CHECK(rise::hil::hid_feedback_problems(definition, 0, encoder).empty());
  PanelSnapshot snap;
  snap.controls.resize(1);
  rise::hil::FeedbackRequest request;
  SECTION("the bridge's own LEDs: power on, fault while failsafe, estop while pressed") {
    snap.failsafe = false;
    CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x02, 0x01}});
    snap.failsafe = true;
    snap.controls[0].pressed = true;
    CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x02, 0x07}});
  }
  SECTION("a request wins over the bridge's own LEDs") {
    request.leds = {{"lamp", true}, {"power", false}};
    snap.failsafe = false;
    CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x02, 0x08}});
  }
  SECTION("a device without those outputs gets no report, and a line that says why") {
    const auto gravis = fp::parse_hid_descriptor(gravis_descriptor);
    REQUIRE(gravis);
    const fp::HidOutputEncoder none(gravis.descriptor);
    CHECK(build_hid_feedback(definition, 0, request, snap, none).empty());
    const auto problems = rise::hil::hid_feedback_problems(definition, 0, none);
    REQUIRE(problems.size() == 4);
    CHECK(problems[0] ==
          "p.yaml:7: feedback.leds.power.signal: the device has no output signal 'usage_0008_0001' "
          "(it has no output report)");
  }
  SECTION("without report ids the report starts with hidraw's 0") {
    // 2 buttons in, 5 LEDs out (the HID 1.11 appendix E.6 keyboard's LEDs), no report id.
    const std::vector<uint8_t> keyboard_leds = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x05, 0x09, 0x19, 0x01, 0x29,
                                                0x02, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02, 0x81, 0x02,
                                                0x95, 0x06, 0x81, 0x01, 0x05, 0x08, 0x19, 0x01, 0x29, 0x05, 0x95,
                                                0x05, 0x91, 0x02, 0x95, 0x03, 0x91, 0x01, 0xC0};
    const auto k = fp::parse_hid_descriptor(keyboard_leds);
    REQUIRE(k);
    snap.failsafe = true;
    CHECK(build_hid_feedback(definition, 0, request, snap, fp::HidOutputEncoder(k.descriptor)) ==
          std::vector<std::vector<uint8_t>>{{0x00, 0x03}});
  }
}

TEST_CASE("hid feedback writes the rumble strength into the device's motor output", "[hil]") {
  using rise::hil::build_hid_feedback;
  namespace fp = rise::firmware_protocol;
  const auto definition = rise::panels::parse_panel_definition(
      "panel: p\nsources:\n  - {name: pad, protocol: hid}\n"
      "controls:\n  - {name: x, kind: axis, signal: x, safe: 0}\n"
      "feedback:\n  leds: [{name: power, signal: usage_0008_0001}]\n"
      "  rumble: [{name: motor, signal: vendor_ff00_0002}]\n",
      "p.yaml");
  REQUIRE(definition.rumbles.size() == 1);
  CHECK(definition.rumbles[0].line == 8);
  const auto parsed = fp::parse_hid_descriptor(rise::test::rumble_pad_descriptor);
  REQUIRE(parsed);
  const fp::HidOutputEncoder encoder(parsed.descriptor);
  CHECK(rise::hil::hid_feedback_problems(definition, 0, encoder).empty());
  PanelSnapshot snap;
  snap.controls.resize(1);
  snap.failsafe = false;
  rise::hil::FeedbackRequest request;
  // hidraw's 0 (no report ids), the LED bits, the motor byte.
  CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x00, 0x01, 0x00}});
  request.rumble = 1.0f;
  CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x00, 0x01, 0xFF}});
  request.rumble = 0.5f;
  CHECK(build_hid_feedback(definition, 0, request, snap, encoder) == std::vector<std::vector<uint8_t>>{{0x00, 0x01, 0x80}});

  SECTION("PanelFeedback's rumble is clamped to 0..1") {
    rise_msgs::PanelFeedback m{};
    m.rumble = 3.0f;
    CHECK(rise::hil::from_message(m).rumble == 1.0f);
    m.rumble = -1.0f;
    CHECK(rise::hil::from_message(m).rumble == 0.0f);
  }
  SECTION("a device without the motor output gets a line that says why") {
    const auto gravis = fp::parse_hid_descriptor(gravis_descriptor);
    REQUIRE(gravis);
    const fp::HidOutputEncoder none(gravis.descriptor);
    const auto problems = rise::hil::hid_feedback_problems(definition, 0, none);
    REQUIRE(problems.size() == 2);
    CHECK(problems[1] ==
          "p.yaml:8: feedback.rumble.motor.signal: the device has no output signal 'vendor_ff00_0002' "
          "(it has no output report)");
  }
  SECTION("rumble is refused where it cannot be written") {
    const std::string head =
        "panel: p\nsources:\n  - {name: pad, protocol: hid}\n  - {name: console, protocol: rise-can-v1}\n"
        "controls:\n  - {name: x, kind: axis, source: pad, signal: x, safe: 0}\nfeedback:\n";
    const auto [feedback, message] = GENERATE(table<std::string, std::string>({
        {"  rumble: [{name: m, source: console, signal: vendor_ff00_0002}]\n",
         "p.yaml:8: feedback.rumble.m.source: rumble is an output signal of a hid source's device"},
        {"  rumble: [{name: m, source: pad}]\n", "p.yaml:8: feedback.rumble.m.signal: missing"},
        {"  rumble: [{name: m, source: pad, signal: a}, {name: n, source: pad, signal: a}]\n",
         "p.yaml:8: feedback.rumble.n.signal: output signal already bound to another rumble"},
        {"  rumble: {name: m}\n", "p.yaml:8: feedback.rumble: expected a list"},
    }));
    INFO(feedback);
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(head + feedback, "p.yaml"), Catch::StartsWith(message));
  }
}
