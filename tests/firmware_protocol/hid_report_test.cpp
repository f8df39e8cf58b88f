#include "firmware_protocol/hid_report.hpp"

#include <catch2/catch.hpp>

#include "tests/test_data.hpp"
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <span>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware_protocol/hid_descriptor.hpp"
#include "firmware_protocol/hid_text.hpp"

namespace fp = rise::firmware_protocol;

namespace {

using rise::test::data_file;

// A lenient JSON reader for the Android CTS test files: they use 0x literals
// and are therefore not strict JSON.
struct Json {
  enum class Type { Null, Number, String, Array, Object } type = Type::Null;
  double number = 0;
  std::string string;
  std::vector<Json> array;
  std::vector<std::pair<std::string, Json>> object;

  const Json& operator[](const std::string& key) const {
    for (const auto& [k, v] : object) {
      if (k == key) return v;
    }
    throw std::out_of_range("no key " + key);
  }
  bool has(const std::string& key) const {
    for (const auto& kv : object) {
      if (kv.first == key) return true;
    }
    return false;
  }
};

class JsonReader {
 public:
  explicit JsonReader(std::string text) : text_(std::move(text)) {}

  Json value() {
    skip();
    Json j;
    const char c = peek();
    if (c == '{') {
      ++pos_;
      j.type = Json::Type::Object;
      while (skip(), peek() != '}') {
        Json key = value();
        skip();
        expect(':');
        j.object.emplace_back(key.string, value());
        skip();
        if (peek() == ',') ++pos_;
      }
      ++pos_;
    } else if (c == '[') {
      ++pos_;
      j.type = Json::Type::Array;
      while (skip(), peek() != ']') {
        j.array.push_back(value());
        skip();
        if (peek() == ',') ++pos_;
      }
      ++pos_;
    } else if (c == '"') {
      ++pos_;
      j.type = Json::Type::String;
      while (peek() != '"') {
        if (peek() == '\\') ++pos_;
        j.string += text_.at(pos_++);
      }
      ++pos_;
    } else {
      const std::size_t begin = pos_;
      while (pos_ < text_.size() && std::string(",]}: \t\r\n").find(text_[pos_]) == std::string::npos) ++pos_;
      const std::string token = text_.substr(begin, pos_ - begin);
      j.type = Json::Type::Number;
      j.number = token.find("0x") != std::string::npos ? static_cast<double>(std::stol(token, nullptr, 16))
                                                      : std::stod(token);
    }
    return j;
  }

 private:
  char peek() const {
    if (pos_ >= text_.size()) throw std::runtime_error("unexpected end of JSON");
    return text_[pos_];
  }
  void skip() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  void expect(char c) {
    if (peek() != c) throw std::runtime_error(std::string("expected ") + c);
    ++pos_;
  }
  std::string text_;
  std::size_t pos_ = 0;
};

Json read_json(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return JsonReader(s.str()).value();
}

std::vector<uint8_t> bytes_of(const Json& array) {
  std::vector<uint8_t> out;
  for (const Json& b : array.array) out.push_back(static_cast<uint8_t>(b.number));
  return out;
}

// Which signal Android turns into which KEYCODE_ for the two CTS devices.
// Linux hid-input maps Button page usage N of a Game Pad application to
// BTN_GAMEPAD + N - 1 (0x130 = 304 = BTN_A ...), Consumer AC Back (0x0C:0x224)
// to KEY_BACK (158) and AC Home (0x0C:0x223) to KEY_HOMEPAGE (172); Android's
// key layout files then rename those codes:
// - Vendor_0428_Product_4001.kl (Gravis): 0x130 BUTTON_X, 0x131 BUTTON_A,
//   0x132 BUTTON_B, 0x133 BUTTON_Y, 0x134 L1, 0x135 R1, 0x136 L2, 0x137 R2,
//   0x138 SELECT, 0x139 START; axis 0x00 (X) HAT_X, axis 0x01 (Y) HAT_Y.
// - Vendor_045e_Product_02fd.kl (Xbox One S Bluetooth): 304 A, 305 B, 307 X,
//   308 Y, 310 L1, 311 R1, 315 START, 317 THUMBL, 318 THUMBR, 158 SELECT,
//   172 MODE; 316 (BTN_MODE) is MODE in Android's Generic.kl.
const std::map<std::string, std::string> gravis_keys = {
    {"button_1", "BUTTON_X"},  {"button_2", "BUTTON_A"},      {"button_3", "BUTTON_B"},
    {"button_4", "BUTTON_Y"},  {"button_5", "BUTTON_L1"},     {"button_6", "BUTTON_R1"},
    {"button_7", "BUTTON_L2"}, {"button_8", "BUTTON_R2"},     {"button_9", "BUTTON_SELECT"},
    {"button_10", "BUTTON_START"},
};
const std::map<std::string, std::string> gravis_axes = {{"x", "AXIS_HAT_X"}, {"y", "AXIS_HAT_Y"}};
const std::map<std::string, std::string> xbox_keys = {
    {"button_1", "BUTTON_A"},        {"button_2", "BUTTON_B"},       {"button_4", "BUTTON_X"},
    {"button_5", "BUTTON_Y"},        {"button_7", "BUTTON_L1"},      {"button_8", "BUTTON_R1"},
    {"button_12", "BUTTON_START"},   {"button_13", "BUTTON_MODE"},   {"button_14", "BUTTON_THUMBL"},
    {"button_15", "BUTTON_THUMBR"},  {"usage_000c_0224", "BUTTON_SELECT"},
    {"usage_000c_0223", "BUTTON_MODE"},
};

// Feeds every test's reports through the decoder and compares the button
// transitions with the test's DOWN/UP events.
void check_key_events(const std::string& register_file, const std::string& tests_file,
                      const std::map<std::string, std::string>& keys) {
  const fp::HidReportDecoder decoder(fp::load_hid_descriptor_file(register_file));
  for (const auto& [signal, key] : keys) {
    INFO(signal);
    REQUIRE(decoder.find(signal) < decoder.signals().size());
  }
  std::vector<fp::HidSignalValue> values(decoder.signals().size());
  std::map<std::string, double> pressed;
  const Json tests = read_json(tests_file);
  REQUIRE(tests.array.size() >= 10);
  for (const Json& test : tests.array) {
    INFO(test["name"].string);
    std::vector<std::string> events;
    for (const Json& report : test["reports"].array) {
      const std::vector<uint8_t> bytes = bytes_of(report);
      REQUIRE(decoder.decode(bytes, values) == fp::HidDecodeStatus::Ok);
      for (const auto& [signal, key] : keys) {
        const double v = values[decoder.find(signal)].value;
        if (v != pressed[signal]) events.push_back((v > 0.5 ? "DOWN " : "UP ") + key);
        pressed[signal] = v;
      }
    }
    std::vector<std::string> expected;
    for (const Json& e : test["events"].array) expected.push_back(e["action"].string + " " + e["keycode"].string);
    CHECK(events == expected);
  }
}

}  // namespace

TEST_CASE("decoder reproduces Android CTS button events of the Gravis GamePad Pro", "[firmware_protocol]") {
  const std::string reg = data_file("hid/android-cts/gravis_gamepadprousb_register.json");
  const std::string tests = data_file("hid/android-cts/gravis_gamepadprousb_keyeventtests.json");
  if (reg.empty() || tests.empty()) {
    WARN("Gravis CTS files not found: skipped");
    return;
  }
  check_key_events(reg, tests, gravis_keys);
}

TEST_CASE("decoder reproduces Android CTS button events of the Xbox One S", "[firmware_protocol]") {
  const std::string reg = data_file("hid/android-cts/microsoft_xboxones_register.json");
  const std::string tests = data_file("hid/android-cts/microsoft_xboxones_keyeventtests.json");
  if (reg.empty() || tests.empty()) {
    WARN("Xbox One S CTS files not found: skipped");
    return;
  }
  check_key_events(reg, tests, xbox_keys);
}

TEST_CASE("decoder reproduces Android CTS axis values of the Gravis GamePad Pro", "[firmware_protocol]") {
  const std::string reg = data_file("hid/android-cts/gravis_gamepadprousb_register.json");
  const std::string tests_file = data_file("hid/android-cts/gravis_gamepadprousb_motioneventtests.json");
  if (reg.empty() || tests_file.empty()) {
    WARN("Gravis CTS files not found: skipped");
    return;
  }
  const fp::HidReportDecoder decoder(fp::load_hid_descriptor_file(reg));
  std::vector<fp::HidSignalValue> values(decoder.signals().size());
  const Json tests = read_json(tests_file);
  REQUIRE(tests.array.size() >= 5);
  std::size_t checked = 0;
  for (const Json& test : tests.array) {
    INFO(test["name"].string);
    const auto& reports = test["reports"].array;
    const auto& events = test["events"].array;
    // One MOVE per report here, except the neutral check (no event: every
    // axis within Android's flat range of the centre).
    for (std::size_t i = 0; i < reports.size(); ++i) {
      REQUIRE(decoder.decode(bytes_of(reports[i]), values) == fp::HidDecodeStatus::Ok);
      if (events.empty()) {
        for (const auto& [signal, axis] : gravis_axes) CHECK(values[decoder.find(signal)].value == Approx(0.0).margin(0.01));
        continue;
      }
      REQUIRE(i < events.size());
      for (const auto& [axis, expected] : events[i]["axes"].object) {
        for (const auto& [signal, name] : gravis_axes) {
          if (name != axis) continue;
          CHECK(values[decoder.find(signal)].value == Approx(expected.number).margin(0.01));
          ++checked;
        }
      }
    }
  }
  CHECK(checked == 8);
}

TEST_CASE("decoder sign-extends, normalises and reports the hat null state", "[firmware_protocol]") {
  // Signed 8-bit X (-127..127), unsigned 16-bit Z (0..65535), a throttle
  // (0..255), a hat 0..7 with null state, 3 buttons, 1 padding bit, an array
  // of 2 keyboard slots; report id 5.
  const std::vector<uint8_t> descriptor = {
      0x05, 0x01, 0x09, 0x04, 0xA1, 0x01, 0x85, 0x05,                    //
      0x09, 0x30, 0x15, 0x81, 0x25, 0x7F, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02,  // X
      0x09, 0x32, 0x15, 0x00, 0x27, 0xFF, 0xFF, 0x00, 0x00, 0x75, 0x10, 0x81, 0x02,  // Z
      0x05, 0x02, 0x09, 0xBB, 0x15, 0x00, 0x26, 0xFF, 0x00, 0x75, 0x08, 0x81, 0x02,  // throttle
      0x05, 0x01, 0x09, 0x39, 0x15, 0x00, 0x25, 0x07, 0x75, 0x04, 0x81, 0x42,  // hat
      0x05, 0x09, 0x19, 0x01, 0x29, 0x03, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x03, 0x81, 0x02,
      0x95, 0x01, 0x81, 0x01,                                            // padding
      0x05, 0x07, 0x19, 0x00, 0x29, 0x65, 0x15, 0x00, 0x25, 0x65, 0x75, 0x08, 0x95, 0x02, 0x81, 0x00,
      0xC0};
  const fp::HidParseResult parsed = fp::parse_hid_descriptor(descriptor);
  REQUIRE(parsed);
  const fp::HidReportDecoder decoder(parsed.descriptor);
  const auto value = [&](const std::vector<fp::HidSignalValue>& v, const char* name) {
    const std::size_t i = decoder.find(name);
    REQUIRE(i < v.size());
    return v[i];
  };
  SECTION("a good report") {
    // id 5, X = -127, Z = 0xFFFF, throttle 0x80, hat 2 (90 deg) + buttons 1 and 3, keys 0x04 and 0x00.
    const std::vector<uint8_t> report = {0x05, 0x81, 0xFF, 0xFF, 0x80, 0x52, 0x04, 0x00};
    std::vector<fp::HidSignalValue> v(decoder.signals().size());
    REQUIRE(decoder.decode(report, v) == fp::HidDecodeStatus::Ok);
    CHECK(value(v, "x").raw == -127);
    CHECK(value(v, "x").value == Approx(-1.0).margin(1e-9));
    CHECK(value(v, "z").raw == 65535);
    CHECK(value(v, "z").value == Approx(1.0).margin(1e-9));
    CHECK(value(v, "throttle").value == Approx(128.0 / 255.0).margin(1e-9));
    CHECK(value(v, "hat_switch").value == Approx(90.0).margin(1e-9));
    CHECK_FALSE(value(v, "hat_switch").is_null);
    CHECK(value(v, "button_1").value == 1.0);
    CHECK(value(v, "button_2").value == 0.0);
    CHECK(value(v, "button_3").value == 1.0);
    CHECK(value(v, "array_0007").usage == fp::hid_usage(0x07, 0x04));
    CHECK(value(v, "array_0007_2").usage == 0);
  }
  SECTION("a hat outside its range is null") {
    const std::vector<uint8_t> report = {0x05, 0x00, 0x00, 0x80, 0x00, 0x0F, 0x00, 0x00};
    const std::vector<fp::HidSignalValue> v = decoder.decode(report);
    CHECK(value(v, "hat_switch").is_null);
    CHECK(value(v, "z").value == Approx(0.0).margin(1e-4));
  }
  SECTION("bad reports leave the buffer alone") {
    std::vector<fp::HidSignalValue> v(decoder.signals().size());
    CHECK(decoder.decode(std::vector<uint8_t>{0x05, 0x00}, v) == fp::HidDecodeStatus::TooShort);
    CHECK(decoder.decode(std::vector<uint8_t>{0x06, 0, 0, 0, 0, 0, 0, 0}, v) == fp::HidDecodeStatus::UnknownReportId);
    CHECK(decoder.decode(std::vector<uint8_t>{}, v) == fp::HidDecodeStatus::TooShort);
    std::vector<fp::HidSignalValue> small(1);
    CHECK(decoder.decode(std::vector<uint8_t>{0x05, 0, 0, 0, 0, 0, 0, 0}, small) == fp::HidDecodeStatus::BufferTooSmall);
  }
}

TEST_CASE("output report fields round-trip through encode and decode", "[firmware_protocol]") {
  // The Xbox One S rumble report (id 3): enable bits, 4 motor magnitudes
  // 0..100, duration, start delay, loop count.
  const std::string reg = data_file("hid/android-cts/microsoft_xboxones_register.json");
  fp::HidDescriptor descriptor;
  if (reg.empty()) {
    WARN("Xbox One S register file not found: using an LED descriptor only");
  } else {
    descriptor = fp::load_hid_descriptor_file(reg);
  }
  if (!reg.empty()) {
    const fp::HidOutputEncoder encoder(descriptor);
    REQUIRE(encoder.report_length(3) == 9);
    std::vector<uint8_t> report(encoder.report_length(3), 0);
    const int64_t magnitude = GENERATE(0, 1, 50, 100);
    for (std::size_t i = 0; i < encoder.signals().size(); ++i) {
      REQUIRE(encoder.encode(i, magnitude, report));
    }
    CHECK(report[0] == 3);
    for (std::size_t i = 0; i < encoder.signals().size(); ++i) {
      const fp::HidSignal& s = encoder.signals()[i];
      const int64_t mask = (int64_t{1} << s.bit_size) - 1;
      CHECK(fp::hid_extract(s, std::span<const uint8_t>(report).subspan(1)) == (magnitude & mask));
    }
  }
  // Generic: 5 LED bits and a signed 12-bit force magnitude from bit 5.
  const std::vector<uint8_t> led = {0x05, 0x08, 0x19, 0x01, 0x29, 0x05, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01,
                                    0x95, 0x05, 0x91, 0x02, 0x05, 0x0F, 0x09, 0x70, 0x16, 0x01, 0xF8,
                                    0x26, 0xFF, 0x07, 0x75, 0x0C, 0x95, 0x01, 0x91, 0x02};
  const fp::HidParseResult parsed = fp::parse_hid_descriptor(led);
  REQUIRE(parsed);
  const fp::HidOutputEncoder encoder(parsed.descriptor);
  REQUIRE(encoder.signals().size() == 6);
  REQUIRE(encoder.report_length(0) == 3);
  const std::size_t force = encoder.find("usage_000f_0070");
  REQUIRE(force < 6);
  const double value = GENERATE(-1.0, -0.5, 0.0, 0.25, 1.0);
  const int64_t raw = fp::hid_raw_from_value(encoder.signals()[force], value);
  std::vector<uint8_t> report(3, 0xFF);
  REQUIRE(encoder.encode(force, raw, report));
  REQUIRE(encoder.encode(encoder.find("usage_0008_0002"), 0, report));
  const fp::HidSignal& s = encoder.signals()[force];
  CHECK(fp::hid_extract(s, report) == raw);
  CHECK(fp::hid_normalise(s, parsed.descriptor.fields[s.field_index], raw).value == Approx(value).margin(1e-3));
  CHECK((report[0] & 0x02) == 0);
  CHECK((report[0] & 0x1D) == 0x1D);  // the other LEDs untouched
  std::vector<uint8_t> short_report(2);
  CHECK_FALSE(encoder.encode(force, raw, short_report));
}

namespace {

// Bits of report `id` (wire bytes, id byte included) that its data fields
// carry: only these are determined by the signal values.
std::vector<uint8_t> data_mask(const fp::HidDescriptor& d, fp::HidReportKind kind, uint8_t id) {
  std::vector<uint8_t> mask(d.report_length(id, kind), 0);
  const std::size_t skip = d.uses_report_ids ? 1 : 0;
  if (skip) mask[0] = 0xFF;
  for (const fp::HidField& f : d.fields) {
    if (f.kind != kind || f.report_id != id || f.is_constant()) continue;
    for (uint64_t b = f.bit_offset; b < uint64_t{f.bit_offset} + uint64_t{f.bit_size} * f.count; ++b)
      mask[skip + b / 8] = static_cast<uint8_t>(mask[skip + b / 8] | (1u << (b % 8)));
  }
  return mask;
}

// The raw value a device would send for a decoded value: the inverse of the
// decoder, except array slots, whose value is a usage, not an index.
int64_t raw_for(const fp::HidSignal& s, const fp::HidSignalValue& v) {
  if (s.kind == fp::HidSignalKind::Array) return v.raw;
  if (s.kind == fp::HidSignalKind::Hat && v.is_null) return fp::hid_raw_from_value(s, -1.0);
  return fp::hid_raw_from_value(s, v.value);
}

// Decodes every CTS report of `tests_file`, turns the values back into raw
// ones and encodes the report again: the bytes its fields carry must be the
// CTS bytes. Returns the number of reports checked.
std::size_t check_cts_reencoding(const std::string& register_file, const std::string& tests_file) {
  const fp::HidDescriptor descriptor = fp::load_hid_descriptor_file(register_file);
  const fp::HidReportDecoder decoder(descriptor);
  const fp::HidInputEncoder encoder(descriptor);
  REQUIRE(encoder.signals().size() == decoder.signals().size());
  std::vector<fp::HidSignalValue> values(decoder.signals().size());
  std::vector<int64_t> raw(encoder.signals().size());
  std::vector<uint8_t> out(64);
  std::size_t checked = 0;
  for (const Json& test : read_json(tests_file).array) {
    INFO(test["name"].string);
    for (const Json& report : test["reports"].array) {
      const std::vector<uint8_t> bytes = bytes_of(report);
      REQUIRE(decoder.decode(bytes, values) == fp::HidDecodeStatus::Ok);
      for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = raw_for(encoder.signals()[i], values[i]);
      const uint8_t id = descriptor.uses_report_ids ? bytes[0] : 0;
      const std::size_t length = encoder.encode_report(id, raw, out);
      REQUIRE(length == bytes.size());
      const std::vector<uint8_t> mask = data_mask(descriptor, fp::HidReportKind::Input, id);
      for (std::size_t b = 0; b < length; ++b) {
        INFO("byte " << b);
        CHECK((out[b] & mask[b]) == (bytes[b] & mask[b]));
        CHECK((out[b] & ~mask[b]) == 0);  // padding is sent as 0
      }
      ++checked;
    }
  }
  return checked;
}

}  // namespace

TEST_CASE("input encoder reproduces the Android CTS raw reports from their decoded values", "[firmware_protocol]") {
  const auto [device, register_name, tests_name, reports] = GENERATE(table<std::string, std::string, std::string, std::size_t>({
      {"Gravis", "gravis_gamepadprousb_register.json", "gravis_gamepadprousb_keyeventtests.json", 20},
      {"Gravis", "gravis_gamepadprousb_register.json", "gravis_gamepadprousb_motioneventtests.json", 9},
      {"Xbox One S", "microsoft_xboxones_register.json", "microsoft_xboxones_keyeventtests.json", 24},
  }));
  const std::string reg = data_file("hid/android-cts/" + register_name);
  const std::string tests = data_file("hid/android-cts/" + tests_name);
  if (reg.empty() || tests.empty()) {
    WARN(device << " CTS files not found: skipped");
    return;
  }
  INFO(tests_name);
  CHECK(check_cts_reencoding(reg, tests) == reports);
}

TEST_CASE("input encoder and decoder round-trip every signal of real descriptors", "[firmware_protocol]") {
  const std::string file = GENERATE(as<std::string>{}, "android-cts/gravis_gamepadprousb_register.json",
                                    "android-cts/microsoft_xboxones_register.json", "hid-tools_SaitekGamepad.hid",
                                    "hid-tools_PS4ControllerUSB.hid", "hid-tools_PS3Controller.hid",
                                    "045E_02FF_0005_0001_real.rpt_desc", "xb1s_linux.md");
  const std::string path = data_file("hid/" + file);
  if (path.empty()) {
    WARN(file << " not found: skipped");
    return;
  }
  INFO(file);
  const fp::HidDescriptor descriptor = fp::load_hid_descriptor_file(path);
  const fp::HidInputEncoder encoder(descriptor);
  const fp::HidReportDecoder decoder(descriptor);
  REQUIRE_FALSE(encoder.signals().empty());
  // Patterns: every signal at its minimum, its maximum, the middle, and a
  // pattern that differs between neighbours (catches bits bleeding over).
  const int pattern = GENERATE(0, 1, 2, 3);
  std::vector<int64_t> raw(encoder.signals().size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const fp::HidSignal& s = encoder.signals()[i];
    // Within the logical range and what the field's bits hold: a real
    // descriptor (045E:02FF) declares 1-bit buttons with a maximum of 65535.
    const int64_t top = s.logical_min < 0 ? (int64_t{1} << (s.bit_size - 1)) - 1 : (int64_t{1} << s.bit_size) - 1;
    const int64_t bottom = s.logical_min < 0 ? -(int64_t{1} << (s.bit_size - 1)) : 0;
    const int64_t lo = std::max(s.logical_min, bottom), hi = std::max(std::min(s.logical_max, top), lo);
    const int64_t choice[] = {lo, hi, lo + (hi - lo) / 2, i % 2 == 0 ? lo : hi};
    raw[i] = choice[pattern];
  }
  std::size_t longest = 0;
  for (const uint8_t id : encoder.report_ids()) longest = std::max(longest, encoder.report_length(id));
  std::vector<uint8_t> report(longest);
  std::vector<fp::HidSignalValue> values(decoder.signals().size());
  std::size_t decoded = 0;
  for (const uint8_t id : encoder.report_ids()) {
    INFO("report " << int{id});
    const std::size_t length = encoder.encode_report(id, raw, report);
    REQUIRE(length == descriptor.report_length(id, fp::HidReportKind::Input));
    if (descriptor.uses_report_ids) CHECK(report[0] == id);
    REQUIRE(decoder.decode(std::span<const uint8_t>(report.data(), length), values) == fp::HidDecodeStatus::Ok);
    for (const uint32_t k : encoder.signals_of(id)) {
      INFO(encoder.signals()[k].name);
      CHECK(values[k].raw == raw[k]);
      ++decoded;
    }
  }
  CHECK(decoded == encoder.signals().size());
}

TEST_CASE("input encoder refuses unknown report ids and short buffers", "[firmware_protocol]") {
  // Report id 1: x, y 8 bits; report id 2: 4 buttons + 4 padding bits.
  const std::vector<uint8_t> descriptor = {
      0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x85, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xFF, 0x00,
      0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0x85, 0x02, 0x05, 0x09, 0x19, 0x01, 0x29, 0x04, 0x25, 0x01, 0x75,
      0x01, 0x95, 0x04, 0x81, 0x02, 0x95, 0x01, 0x75, 0x04, 0x81, 0x01, 0xC0};
  const fp::HidParseResult parsed = fp::parse_hid_descriptor(descriptor);
  REQUIRE(parsed);
  const fp::HidInputEncoder encoder(parsed.descriptor);
  REQUIRE(encoder.report_ids() == std::vector<uint8_t>{1, 2});
  std::vector<int64_t> raw(encoder.signals().size(), 1);
  raw[encoder.find("x")] = 0x12;
  raw[encoder.find("y")] = 0xFE;
  std::vector<uint8_t> report(8, 0xAA);
  SECTION("good: each report carries only its own signals, padding 0") {
    REQUIRE(encoder.encode_report(1, raw, report) == 3);
    CHECK(std::vector<uint8_t>(report.begin(), report.begin() + 3) == std::vector<uint8_t>{0x01, 0x12, 0xFE});
    REQUIRE(encoder.encode_report(2, raw, report) == 2);
    CHECK(std::vector<uint8_t>(report.begin(), report.begin() + 2) == std::vector<uint8_t>{0x02, 0x0F});
    CHECK(report[2] == 0xFE);  // beyond the report: untouched
  }
  SECTION("bad: nothing is written") {
    CHECK(encoder.encode_report(3, raw, report) == 0);
    std::vector<uint8_t> short_report(2, 0xAA);
    CHECK(encoder.encode_report(1, raw, short_report) == 0);
    CHECK(short_report == std::vector<uint8_t>{0xAA, 0xAA});
    std::vector<int64_t> few(1);
    CHECK(encoder.encode_report(1, few, report) == 0);
    CHECK(report[0] == 0xAA);
  }
}

TEST_CASE("the README's Gravis worked example decodes as documented", "[firmware_protocol]") {
  // Bytes of android-cts/gravis_gamepadprousb_register.json, inline so the
  // README example is checked without the test data.
  const std::vector<uint8_t> descriptor = {
      0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x05, 0x01, 0x09, 0x01, 0xa1, 0x00, 0x09, 0x30, 0x09, 0x31, 0x15,
      0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0xc0, 0x05, 0x09, 0x19, 0x01, 0x29, 0x0a,
      0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0a, 0x81, 0x02, 0x95, 0x01, 0x75, 0x06, 0x81, 0x01, 0xc0};
  const fp::HidParseResult parsed = fp::parse_hid_descriptor(descriptor);
  REQUIRE(parsed);
  const fp::HidReportDecoder decoder(parsed.descriptor);
  const std::vector<fp::HidSignalValue> v = decoder.decode(std::vector<uint8_t>{0x00, 0xFF, 0x05, 0x02});
  CHECK(v[decoder.find("x")].value == Approx(-1.0).margin(1e-9));
  CHECK(v[decoder.find("y")].value == Approx(1.0).margin(1e-9));
  for (int b = 1; b <= 10; ++b) {
    INFO("button_" << b);
    const bool pressed = b == 1 || b == 3 || b == 10;
    CHECK(v[decoder.find("button_" + std::to_string(b))].value == (pressed ? 1.0 : 0.0));
  }
}

TEST_CASE("hat values round-trip through raw and degrees, with a null state", "[firmware_protocol]") {
  fp::HidSignal hat;
  hat.kind = fp::HidSignalKind::Hat;
  hat.bit_size = 4;
  hat.logical_min = GENERATE(0, 1);
  hat.logical_max = hat.logical_min + 7;
  fp::HidField field;
  field.flags = fp::hid_flags::variable | fp::hid_flags::null_state;
  const double degrees = GENERATE(0.0, 45.0, 90.0, 180.0, 315.0);
  const int64_t raw = fp::hid_raw_from_value(hat, degrees);
  CHECK(fp::hid_normalise(hat, field, raw).value == Approx(degrees).margin(1e-9));
  const int64_t released = fp::hid_raw_from_value(hat, -1.0);
  CHECK(released >= 0);
  CHECK(released < 16);
  CHECK(fp::hid_normalise(hat, field, released).is_null);
}
