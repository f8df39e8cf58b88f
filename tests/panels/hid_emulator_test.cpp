// The HID emulator without a kernel: the reports it would send, read back
// with the protocol's decoder; the output reports it is given, decoded.

#include <catch2/catch.hpp>

#include <span>
#include <string>
#include <vector>

#include "firmware_protocol/hid_report.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "tests/hid_test_devices.hpp"

namespace fp = rise::firmware_protocol;
using rise::panels::HidEmulator;
using rise::panels::PanelDefinition;

namespace {

fp::HidDescriptor parse(std::span<const uint8_t> bytes) {
  fp::HidParseResult parsed = fp::parse_hid_descriptor(bytes);
  REQUIRE(parsed);
  return parsed.descriptor;
}

// A panel of one hid source "pad": its controls' and feedback's YAML lines
// (the controls start at line 5).
PanelDefinition pad_panel(const std::string& controls, const std::string& feedback = "") {
  return rise::panels::parse_panel_definition(
      "panel: p\nsources:\n  - {name: pad, protocol: hid}\ncontrols:\n" + controls +
          (feedback.empty() ? "" : "feedback:\n" + feedback),
      "p.yaml");
}

PanelDefinition led_pad_definition() {
  return rise::panels::parse_panel_definition(
      "panel: led-pad\n"
      "sources:\n"
      "  - {name: pad, protocol: hid}\n"
      "controls:\n"
      "  - {name: drive_x, kind: axis, signal: x, safe: 0}\n"
      "  - {name: drive_y, kind: axis, signal: y, safe: 0}\n"
      "  - {name: deadman, kind: button, signal: button_1, safe: false}\n"
      "  - {name: horn, kind: button, signal: button_8, safe: false}\n",
      "led_pad.yaml");
}

// Collects what tick() sends.
struct Sent {
  std::vector<std::vector<uint8_t>> reports;
  HidEmulator::ReportSink sink() {
    return [this](std::span<const uint8_t> r) {
      reports.emplace_back(r.begin(), r.end());
      return true;
    };
  }
};

void play(HidEmulator& emulator, const PanelDefinition& definition, const std::string& script) {
  for (const auto& e : rise::panels::parse_timeline(script, "script.txt", definition).events) emulator.apply(e);
}

}  // namespace

TEST_CASE("hid emulator sends the timeline's values as reports the decoder reads back", "[panels]") {
  const PanelDefinition definition = led_pad_definition();
  const fp::HidDescriptor descriptor = parse(rise::test::led_pad_descriptor);
  HidEmulator emulator(definition, 0, descriptor);
  const fp::HidReportDecoder decoder(descriptor);
  const auto value = [&](const std::vector<fp::HidSignalValue>& v, const char* name) {
    return v[decoder.find(name)];
  };
  Sent sent;
  SECTION("at rest: sticks centred, buttons up") {
    REQUIRE(emulator.tick(0, sent.sink()) == 1);
    const auto v = decoder.decode(sent.reports.at(0));
    CHECK(sent.reports[0] == std::vector<uint8_t>{0x01, 0x80, 0x80, 0x00});
    CHECK(value(v, "x").value == Approx(0.0).margin(0.005));
    CHECK(value(v, "button_1").value == 0.0);
  }
  SECTION("moved") {
    const double x = GENERATE(-1.0, -0.5, 0.0, 0.25, 1.0);
    play(emulator, definition,
         "0 drive_x " + std::to_string(x) + "\n0 drive_y -1\n0 deadman pressed\n0 horn pressed\n");
    REQUIRE(emulator.tick(0, sent.sink()) == 1);
    const auto v = decoder.decode(sent.reports.at(0));
    CHECK(value(v, "x").value == Approx(x).margin(1.0 / 255));
    CHECK(value(v, "y").value == Approx(-1.0).margin(1e-9));
    CHECK(value(v, "button_1").value == 1.0);
    CHECK(value(v, "button_8").value == 1.0);
    CHECK(value(v, "button_2").value == 0.0);
    CHECK(std::vector<uint8_t>(emulator.report(1).begin(), emulator.report(1).end()) == sent.reports[0]);
  }
}

TEST_CASE("hid emulator sends a report when a value changes and every report at its period", "[panels]") {
  const PanelDefinition definition = led_pad_definition();
  HidEmulator emulator(definition, 0, parse(rise::test::led_pad_descriptor), {8000});
  Sent sent;
  CHECK(emulator.tick(0, sent.sink()) == 1);  // the first period starts now
  CHECK(emulator.tick(1000, sent.sink()) == 0);
  play(emulator, definition, "0 horn pressed\n");
  CHECK(emulator.tick(2000, sent.sink()) == 1);  // on change, not waiting for the period
  CHECK(emulator.tick(3000, sent.sink()) == 0);
  play(emulator, definition, "0 horn pressed\n");  // the same value: no change
  CHECK(emulator.tick(4000, sent.sink()) == 0);
  CHECK(emulator.tick(8000, sent.sink()) == 1);  // periodic
  CHECK(emulator.tick(9000, sent.sink()) == 0);
  CHECK(emulator.tick(16000, sent.sink()) == 1);
  CHECK(emulator.reports_sent() == 4);
  CHECK(sent.reports.back() == std::vector<uint8_t>{0x01, 0x80, 0x80, 0x80});
  SECTION("a report the device could not send is sent again") {
    play(emulator, definition, "0 horn released\n");
    CHECK(emulator.tick(17000, [](std::span<const uint8_t>) { return false; }) == 0);
    CHECK(emulator.tick(18000, sent.sink()) == 1);
    CHECK(sent.reports.back() == std::vector<uint8_t>{0x01, 0x80, 0x80, 0x00});
  }
  SECTION("period 0: only on change") {
    HidEmulator on_change(definition, 0, parse(rise::test::led_pad_descriptor), {0});
    CHECK(on_change.tick(0, sent.sink()) == 1);  // the initial state is a change
    CHECK(on_change.tick(100000, sent.sink()) == 0);
  }
}

TEST_CASE("hid emulator directives silence, corrupt and invalidate reports", "[panels]") {
  const PanelDefinition definition = led_pad_definition();
  HidEmulator emulator(definition, 0, parse(rise::test::led_pad_descriptor));
  Sent sent;
  SECTION("@silent stops every report until @resume") {
    play(emulator, definition, "0 @silent\n");
    CHECK(emulator.tick(0, sent.sink()) == 0);
    CHECK(emulator.tick(8000, sent.sink()) == 0);
    play(emulator, definition, "0 @resume\n");
    CHECK(emulator.tick(16000, sent.sink()) == 1);
  }
  SECTION("@corrupt N sends N reports one byte short") {
    play(emulator, definition, "0 @corrupt 2\n");
    for (int64_t t = 0; t < 4 * 8000; t += 8000) emulator.tick(t, sent.sink());
    REQUIRE(sent.reports.size() == 4);
    CHECK(sent.reports[0].size() == 3);
    CHECK(sent.reports[1].size() == 3);
    CHECK(sent.reports[2].size() == 4);
    const fp::HidReportDecoder decoder(parse(rise::test::led_pad_descriptor));
    std::vector<fp::HidSignalValue> values(decoder.signals().size());
    CHECK(decoder.decode(sent.reports[0], values) == fp::HidDecodeStatus::TooShort);
  }
  SECTION("@end ends it") {
    play(emulator, definition, "0 @end\n");
    CHECK(emulator.ended());
    CHECK(emulator.tick(0, sent.sink()) == 0);
  }
}

TEST_CASE("hid emulator sets switches by position and @invalid sends the null state", "[panels]") {
  // A hat switch 0..7 in 4 bits with a null state, and 4 buttons.
  const std::vector<uint8_t> descriptor = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x09, 0x39, 0x15, 0x00, 0x25,
                                           0x07, 0x75, 0x04, 0x95, 0x01, 0x81, 0x42, 0x05, 0x09, 0x19, 0x01,
                                           0x29, 0x04, 0x25, 0x01, 0x75, 0x01, 0x95, 0x04, 0x81, 0x02, 0xC0};
  const PanelDefinition definition = pad_panel(
      "  - {name: view, kind: switch, signal: hat_switch, positions: [n, ne, e, se, s, sw, w, nw], safe: n}\n"
      "  - {name: a, kind: button, signal: button_2, safe: false}\n");
  HidEmulator emulator(definition, 0, parse(descriptor));
  const fp::HidReportDecoder decoder(parse(descriptor));
  Sent sent;
  play(emulator, definition, "0 view e\n0 a 1\n");
  emulator.tick(0, sent.sink());
  CHECK(sent.reports.at(0) == std::vector<uint8_t>{0x22});  // hat 2 (east), button 2
  CHECK(decoder.decode(sent.reports[0])[decoder.find("hat_switch")].value == Approx(90.0).margin(1e-9));
  SECTION("good") {
    play(emulator, definition, "0 view 7\n");
    emulator.tick(1000, sent.sink());
    CHECK(sent.reports.back() == std::vector<uint8_t>{0x27});
  }
  SECTION("@invalid: just outside the logical range") {
    play(emulator, definition, "0 @invalid view\n");
    emulator.tick(1000, sent.sink());
    CHECK(sent.reports.back() == std::vector<uint8_t>{0x28});
    CHECK(decoder.decode(sent.reports.back())[decoder.find("hat_switch")].is_null);
  }
}

TEST_CASE("hid emulator decodes the output reports the host writes", "[panels]") {
  const PanelDefinition definition = led_pad_definition();
  HidEmulator emulator(definition, 0, parse(rise::test::led_pad_descriptor));
  CHECK(emulator.feedback_text() ==
        "outputs usage_0008_0001=0 usage_0008_0002=0 usage_0008_0003=0 usage_0008_0004=0");
  SECTION("good: report 2, LEDs 1 and 3") {
    CHECK(emulator.on_output(std::vector<uint8_t>{0x02, 0x05}));
    CHECK(emulator.feedback_text() ==
          "outputs usage_0008_0001=1 usage_0008_0002=0 usage_0008_0003=1 usage_0008_0004=0");
    CHECK_FALSE(emulator.on_output(std::vector<uint8_t>{0x02, 0xF5}));  // padding bits are no LED
    CHECK(emulator.outputs_received() == 2);
  }
  SECTION("bad: unknown report id, too short") {
    CHECK_FALSE(emulator.on_output(std::vector<uint8_t>{0x05, 0x01}));
    CHECK_FALSE(emulator.on_output(std::vector<uint8_t>{0x02}));
    CHECK(emulator.bad_outputs() == 2);
  }
  SECTION("a device without output reports has none to show") {
    const PanelDefinition gravis = pad_panel("  - {name: a, kind: button, signal: button_10, safe: false}\n");
    HidEmulator plain(gravis, 0, parse(rise::test::gravis_descriptor));
    CHECK(plain.feedback_text() == "outputs none");
    CHECK_FALSE(plain.on_output(std::vector<uint8_t>{0x00, 0x01}));
    CHECK(plain.bad_outputs() == 1);
  }
}

TEST_CASE("hid emulator takes hidraw's leading 0 of a report without ids", "[panels]") {
  // 5 LED bits, 3 padding bits, no report id (the HID 1.11 appendix E.6 keyboard's LEDs).
  const std::vector<uint8_t> descriptor = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x05, 0x09, 0x19, 0x01, 0x29,
                                           0x02, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x02, 0x81, 0x02,
                                           0x95, 0x06, 0x81, 0x01, 0x05, 0x08, 0x19, 0x01, 0x29, 0x05, 0x95,
                                           0x05, 0x91, 0x02, 0x95, 0x03, 0x91, 0x01, 0xC0};
  const PanelDefinition definition = pad_panel("  - {name: a, kind: button, signal: button_1, safe: false}\n");
  HidEmulator emulator(definition, 0, parse(descriptor));
  const std::vector<uint8_t> report = GENERATE(std::vector<uint8_t>{0x00, 0x12}, std::vector<uint8_t>{0x12});
  CHECK(emulator.on_output(report));
  CHECK(emulator.feedback_text() ==
        "outputs usage_0008_0001=0 usage_0008_0002=1 usage_0008_0003=0 usage_0008_0004=0 usage_0008_0005=1");
}

TEST_CASE("hid emulator refuses a control bound to a name the descriptor lacks", "[panels]") {
  const PanelDefinition definition = pad_panel(
      "  - {name: a, kind: button, signal: button_1, safe: false}\n"
      "  - {name: throttle, kind: axis, signal: slider, safe: 0}\n");
  CHECK_THROWS_WITH(HidEmulator(definition, 0, parse(rise::test::gravis_descriptor)),
                    Catch::StartsWith("p.yaml:6: controls.throttle.signal: the descriptor has no input signal "
                                      "'slider' (it has: x, y, button_1, button_2"));
  const PanelDefinition can = rise::panels::parse_panel_definition(
      "panel: c\nsources:\n  - {name: console, protocol: rise-can-v1}\ncontrols:\n"
      "  - {name: a, kind: button, signal: button.0, safe: false}\n",
      "c.yaml");
  CHECK_THROWS_WITH(HidEmulator(can, 0, parse(rise::test::gravis_descriptor)),
                    "c.yaml: source 'console' is protocol rise-can-v1, not hid");
}

TEST_CASE("hid emulator shows the definition's LEDs by name", "[panels]") {
  const PanelDefinition definition =
      pad_panel("  - {name: a, kind: button, signal: button_1, safe: false}\n",
                "  leds: [{name: power, signal: usage_0008_0001}, {name: fault, signal: usage_0008_0002},\n"
                "         {name: horn, signal: usage_0008_0009}]\n");
  HidEmulator emulator(definition, 0, parse(rise::test::led_pad_descriptor));
  CHECK(emulator.feedback_text() == "leds power=off fault=off horn=-; outputs usage_0008_0003=0 usage_0008_0004=0");
  CHECK(emulator.on_output(std::vector<uint8_t>{0x02, 0x09}));
  CHECK(emulator.feedback_text() == "leds power=on fault=off horn=-; outputs usage_0008_0003=0 usage_0008_0004=1");
}

TEST_CASE("a restarted hid emulator undoes every directive and sends its inputs at rest", "[panels]") {
  const PanelDefinition definition = led_pad_definition();
  HidEmulator emulator(definition, 0, parse(rise::test::led_pad_descriptor));
  Sent at_rest, sent;
  emulator.tick(0, at_rest.sink());
  REQUIRE(at_rest.reports.size() == 1);
  play(emulator, definition, "0 drive_y 0.8\n0 deadman pressed\n0 @invalid drive_x\n0 @corrupt 100\n0 @silent\n");
  CHECK(emulator.tick(8000, sent.sink()) == 0);
  emulator.restart();
  CHECK_FALSE(emulator.silent());
  CHECK(emulator.tick(16000, sent.sink()) == 1);
  REQUIRE(sent.reports.size() == 1);
  CHECK(sent.reports[0] == at_rest.reports[0]);  // whole, and every signal where it rests
  play(emulator, definition, "0 @end\n");
  emulator.restart();
  CHECK_FALSE(emulator.ended());
}
