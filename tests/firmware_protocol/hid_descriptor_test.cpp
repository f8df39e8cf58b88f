#include "firmware_protocol/hid_descriptor.hpp"

#include <algorithm>
#include <catch2/catch.hpp>

#include "tests/test_data.hpp"
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware_protocol/hid_report.hpp"
#include "firmware_protocol/hid_text.hpp"

namespace fp = rise::firmware_protocol;

namespace {

using rise::test::data_file;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<const fp::HidField*> fields_of(const fp::HidDescriptor& d, uint8_t id, fp::HidReportKind kind) {
  std::vector<const fp::HidField*> out;
  for (const fp::HidField& f : d.fields) {
    if (f.report_id == id && f.kind == kind) out.push_back(&f);
  }
  return out;
}

fp::HidParseResult parse(const std::vector<uint8_t>& bytes) { return fp::parse_hid_descriptor(bytes); }

}  // namespace

TEST_CASE("every HID descriptor in the test data parses without error", "[firmware_protocol]") {
  const std::string dir = data_file("hid");
  if (dir.empty()) {
    WARN("RISE_TEST_DATA/hid not found: skipped");
    return;
  }
  // Descriptor lengths as the MANIFEST and the files themselves state them.
  const std::map<std::string, std::size_t> expected_bytes = {
      {"hid-tools_AsusGamepad.hid", 193},           {"hid-tools_PS3Controller.hid", 148},
      {"hid-tools_PS4ControllerBluetooth.hid", 364}, {"hid-tools_PS4ControllerUSB.hid", 507},
      {"hid-tools_PS5ControllerBluetooth.hid", 279}, {"hid-tools_PS5ControllerUSB.hid", 257},
      {"hid-tools_SaitekGamepad.hid", 625},          {"xb1s_linux.md", 335},
  };
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && name != "MANIFEST.md") files.push_back(e.path().string());
  }
  for (const auto& e : std::filesystem::directory_iterator(dir + "/android-cts")) {
    if (e.path().filename().string().ends_with("register.json")) files.push_back(e.path().string());
  }
  REQUIRE(files.size() >= 11);
  for (const std::string& path : files) {
    INFO(path);
    const fp::HidDescriptorSource source = fp::read_hid_descriptor_file(path);
    const fp::HidParseResult result = fp::parse_hid_descriptor(source.bytes);
    INFO(fp::to_string(result.error) << " at byte " << result.error_offset);
    REQUIRE(result);
    CHECK_FALSE(result.descriptor.fields.empty());
    CHECK_FALSE(fp::hid_signals(result.descriptor, fp::HidReportKind::Input).empty());
    const auto it = expected_bytes.find(std::filesystem::path(path).filename().string());
    if (it != expected_bytes.end()) CHECK(source.bytes.size() == it->second);
    CHECK_FALSE(fp::describe_hid_descriptor(result.descriptor).empty());
  }
}

TEST_CASE("Xbox One S descriptor matches the bit layout table of xb1s_linux.md", "[firmware_protocol]") {
  const std::string path = data_file("hid/xb1s_linux.md");
  if (path.empty()) {
    WARN("xb1s_linux.md not found: skipped");
    return;
  }
  const fp::HidDescriptor d = fp::load_hid_descriptor_file(path);
  CHECK(d.uses_report_ids);

  // The doc's "Sz" rows list, per report, the data bits of each field and
  // "(n)" padding after it, "a : b" for elements of one field, then the total.
  struct Expected {
    uint32_t bits;
    bool padding;
  };
  std::map<int, std::vector<Expected>> table;
  std::map<int, uint32_t> totals;
  std::istringstream in(slurp(path));
  std::string line;
  int id = -1;
  const std::regex id_row(R"(^([0-9A-Fa-f]{2})\s+\|)");
  const std::regex pad_cell(R"(^\s*(\d+)\+\((\d+)\)\s*$)");
  const std::regex num(R"(\d+)");
  const std::regex total_cell(R"(^\s*(\d+) Bits)");
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, id_row)) id = std::stoi(m[1].str(), nullptr, 16);
    if (!line.starts_with("Sz") || id < 0) continue;
    std::stringstream cells(line.substr(line.find('|') + 1));
    std::string cell;
    while (std::getline(cells, cell, '|')) {
      if (std::regex_search(cell, m, total_cell)) {
        totals[id] = static_cast<uint32_t>(std::stoul(m[1].str()));
      } else if (std::regex_search(cell, m, pad_cell)) {
        table[id].push_back({static_cast<uint32_t>(std::stoul(m[1].str())), false});
        table[id].push_back({static_cast<uint32_t>(std::stoul(m[2].str())), true});
      } else {
        uint32_t sum = 0;
        for (auto it = std::sregex_iterator(cell.begin(), cell.end(), num); it != std::sregex_iterator(); ++it) {
          sum += static_cast<uint32_t>(std::stoul(it->str()));
        }
        if (sum > 0) table[id].push_back({sum, false});
      }
    }
  }
  REQUIRE(table.size() == 4);
  for (const auto& [report_id, expected] : table) {
    INFO("report " << report_id);
    const auto rid = static_cast<uint8_t>(report_id);
    // Report 3 is the rumble output report; the others are inputs.
    const fp::HidReportKind kind = report_id == 3 ? fp::HidReportKind::Output : fp::HidReportKind::Input;
    const std::vector<const fp::HidField*> fields = fields_of(d, rid, kind);
    REQUIRE(fields.size() == expected.size());
    uint32_t offset = 0;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      INFO("field " << i);
      CHECK(fields[i]->bit_offset == offset);
      CHECK(fields[i]->bit_size * fields[i]->count == expected[i].bits);
      CHECK(fields[i]->is_constant() == expected[i].padding);
      offset += expected[i].bits;
    }
    CHECK(offset == totals.at(report_id));
    CHECK(d.report_length(rid, kind) == totals.at(report_id) / 8 + 1);
  }

  // Facts of the "Rng" row: sticks 0-65535 (the doc writes 0-65534), triggers 0-1023, hat 1..8 with null state.
  const std::vector<const fp::HidField*> r1 = fields_of(d, 1, fp::HidReportKind::Input);
  CHECK(r1[0]->logical_max == 65535);
  CHECK(r1[0]->usage_at(0) == fp::hid_usage(0x01, 0x30));
  CHECK(r1[0]->usage_at(1) == fp::hid_usage(0x01, 0x31));
  CHECK(r1[2]->usage_at(0) == fp::hid_usage(0x02, 0xC5));
  CHECK(r1[2]->logical_max == 1023);
  CHECK(r1[6]->usage_at(0) == fp::hid_usage(0x01, 0x39));
  CHECK(r1[6]->has_null_state());
  CHECK(r1[6]->physical_max == 315);
  CHECK(r1[0]->collection_path.size() == 2);
  CHECK(r1[0]->collection_path[0].type == static_cast<uint8_t>(fp::HidCollectionType::Application));
  CHECK(r1[0]->collection_path[0].usage == fp::hid_usage(0x01, 0x05));

  // The same bytes (without the trailing 0x00) are the Android CTS register file.
  const std::string cts = data_file("hid/android-cts/microsoft_xboxones_register.json");
  if (!cts.empty()) {
    const fp::HidDescriptorSource md = fp::read_hid_descriptor_file(path);
    const fp::HidDescriptorSource json = fp::read_hid_descriptor_file(cts);
    REQUIRE(md.bytes.size() == json.bytes.size() + 1);
    CHECK(std::equal(json.bytes.begin(), json.bytes.end(), md.bytes.begin()));
    CHECK(md.bytes.back() == 0x00);
    CHECK(json.vendor_id == 0x045e);
    CHECK(json.product_id == 0x02fd);
  }
}

TEST_CASE("Gravis GamePad Pro descriptor has 8-bit X/Y and 10 buttons", "[firmware_protocol]") {
  const std::string path = data_file("hid/android-cts/gravis_gamepadprousb_register.json");
  if (path.empty()) {
    WARN("gravis_gamepadprousb_register.json not found: skipped");
    return;
  }
  const fp::HidDescriptorSource source = fp::read_hid_descriptor_file(path);
  CHECK(source.name == "Gravis GamePad Pro USB (Test)");
  CHECK(source.vendor_id == 0x0428);
  CHECK(source.product_id == 0x4001);
  const fp::HidDescriptor d = fp::load_hid_descriptor_file(path);
  CHECK_FALSE(d.uses_report_ids);
  REQUIRE(d.fields.size() == 3);
  CHECK(d.fields[0].bit_offset == 0);
  CHECK(d.fields[0].bit_size == 8);
  CHECK(d.fields[0].count == 2);
  CHECK(d.fields[1].bit_offset == 16);
  CHECK(d.fields[1].bit_size == 1);
  CHECK(d.fields[1].count == 10);
  CHECK(d.fields[2].is_constant());
  CHECK(d.report_length(0, fp::HidReportKind::Input) == 4);

  const std::vector<fp::HidSignal> signals = fp::hid_signals(d, fp::HidReportKind::Input);
  REQUIRE(signals.size() == 12);
  CHECK(signals[0].name == "x");
  CHECK(signals[1].name == "y");
  for (int b = 1; b <= 10; ++b) {
    CHECK(signals[static_cast<std::size_t>(b + 1)].name == "button_" + std::to_string(b));
    CHECK(signals[static_cast<std::size_t>(b + 1)].kind == fp::HidSignalKind::Button);
  }
}

TEST_CASE("hidapi's Xbox One descriptor has 16-bit axes, 16 buttons, a hat and padding", "[firmware_protocol]") {
  const std::string path = data_file("hid/045E_02FF_0005_0001_real.rpt_desc");
  if (path.empty()) {
    WARN("045E_02FF_0005_0001_real.rpt_desc not found: skipped");
    return;
  }
  const fp::HidDescriptorSource source = fp::read_hid_descriptor_file(path);
  // The file's own trailer states the length ("// 120 bytes").
  std::smatch m;
  const std::string text = slurp(path);
  REQUIRE(std::regex_search(text, m, std::regex(R"(// (\d+) bytes)")));
  CHECK(source.bytes.size() == std::stoul(m[1].str()));

  const fp::HidDescriptor d = fp::load_hid_descriptor_file(path);
  const fp::HidReportDecoder decoder(d);
  const std::vector<std::string> axes = {"x", "y", "rx", "ry", "z"};
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const std::size_t k = decoder.find(axes[i]);
    REQUIRE(k < decoder.signals().size());
    CHECK(decoder.signals()[k].bit_offset == 16 * i);
    CHECK(decoder.signals()[k].bit_size == 16);
  }
  CHECK(decoder.find("button_16") < decoder.signals().size());
  const std::size_t hat = decoder.find("hat_switch");
  REQUIRE(hat < decoder.signals().size());
  CHECK(decoder.signals()[hat].bit_offset == 96);
  CHECK(decoder.signals()[hat].kind == fp::HidSignalKind::Hat);
  // Two full padding bytes at the end (the file's header comment): 15 bytes.
  CHECK(d.report_length(0, fp::HidReportKind::Input) == 15);
  CHECK(d.fields.back().is_constant());
  CHECK(d.fields.back().bit_size * d.fields.back().count == 16);
}

TEST_CASE("descriptor readers accept hex text, recorder, JSON and binary forms", "[firmware_protocol]") {
  const std::vector<uint8_t> expected = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0xC0};
  SECTION("plain and C-style hex text") {
    for (const std::string text : {"05 01 09 05 a1 01 c0", "0x05, 0x01, // Usage Page\n0x09,0x05,\n# c\n0xA1 0x01 /* x */ 0xC0"}) {
      const fp::HidDescriptorSource s = fp::read_hid_descriptor(text, fp::detect_hid_format(text, "t.txt"), "t.txt");
      CHECK(s.bytes == expected);
    }
  }
  SECTION("hid-recorder lines") {
    const std::string text = "# c\nN: Pad\nI: 3 046d c215\nR: 7 05 01 09 05 a1 01 c0\nE: 0.0 1 00\n";
    REQUIRE(fp::detect_hid_format(text, "p.hid") == fp::HidTextFormat::HidRecorder);
    const fp::HidDescriptorSource s = fp::read_hid_descriptor(text, fp::HidTextFormat::HidRecorder, "p.hid");
    CHECK(s.bytes == expected);
    CHECK(s.name == "Pad");
    CHECK(s.bus == 3);
    CHECK(s.vendor_id == 0x046d);
    CHECK(s.product_id == 0xc215);
  }
  SECTION("binary") {
    const std::string text(expected.begin(), expected.end());
    REQUIRE(fp::detect_hid_format(text, "report_descriptor") == fp::HidTextFormat::Binary);
    CHECK(fp::read_hid_descriptor(text, fp::HidTextFormat::Binary, "rd").bytes == expected);
  }
  SECTION("errors name the file and line") {
    CHECK_THROWS_WITH(fp::read_hid_descriptor("05 01\n09 zz\n", fp::HidTextFormat::HexText, "a.txt"),
                      Catch::StartsWith("a.txt:2: descriptor:"));
    CHECK_THROWS_WITH(fp::read_hid_descriptor("N: x\nR: 3 05 01\n", fp::HidTextFormat::HidRecorder, "b.hid"),
                      Catch::StartsWith("b.hid:2: R:"));
    CHECK_THROWS_WITH(fp::read_hid_descriptor("{\"name\": \"x\"}", fp::HidTextFormat::CtsJson, "c.json"),
                      Catch::StartsWith("c.json:0: descriptor:"));
    CHECK_THROWS_WITH(fp::load_hid_descriptor_file("/nonexistent/d.rpt"),
                      "/nonexistent/d.rpt: cannot open: No such file or directory");
  }
}

TEST_CASE("malformed descriptors give typed errors with byte offsets", "[firmware_protocol]") {
  using E = fp::HidParseError;
  struct Case {
    std::vector<uint8_t> bytes;
    E error;
    std::size_t offset;
  };
  const Case c = GENERATE(values<Case>({
      {{0x05, 0x01, 0x26, 0xFF}, E::TruncatedItem, 2},                     // 2-byte Logical Maximum cut short
      {{0x05, 0x01, 0xFE, 0x10, 0x00, 0x01}, E::TruncatedItem, 2},         // long item runs past the end
      {{0x05, 0x01, 0xB4}, E::PopWithoutPush, 2},
      {{0x75, 0x00, 0x95, 0x02, 0x81, 0x02}, E::ZeroReportSizeWithCount, 4},
      {{0x05, 0x01, 0xC0}, E::EndCollectionWithoutCollection, 2},
      {{0xA1, 0x01, 0x09, 0x30}, E::UnclosedCollection, 4},
      {{0x75, 0x21, 0x95, 0x01, 0x81, 0x02}, E::FieldTooWide, 4},
      {{0x75, 0x08, 0x97, 0xFF, 0xFF, 0xFF, 0x7F, 0x81, 0x02}, E::ReportTooLong, 7},  // huge Report Count
      {{0x75, 0x20, 0x96, 0x00, 0x08, 0x81, 0x02, 0x81, 0x02, 0x81, 0x02}, E::ReportTooLong, 7},
      {{0x85, 0x00}, E::BadReportId, 0},
      {{0xA9, 0x00}, E::DelimiterMismatch, 0},
  }));
  const fp::HidParseResult r = parse(c.bytes);
  CHECK(r.error == c.error);
  CHECK(r.error_offset == c.offset);
  CHECK_FALSE(r);
}

TEST_CASE("parser keeps global state across Push and Pop and skips long items", "[firmware_protocol]") {
  const std::vector<uint8_t> bytes = {
      0x05, 0x01, 0x15, 0x81, 0x25, 0x7F, 0x75, 0x08,  // page 1, -127..127, 8 bits
      0xA4,                                            // Push
      0x05, 0x09, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01,  // buttons 0..1, 1 bit
      0x19, 0x01, 0x29, 0x08, 0x95, 0x08, 0x81, 0x02,  // 8 buttons
      0xB4,                                            // Pop
      0xFE, 0x02, 0x00, 0xAA, 0xBB,                    // a long item
      0x09, 0x30, 0x95, 0x01, 0x81, 0x06,              // relative X
  };
  const fp::HidParseResult r = parse(bytes);
  REQUIRE(r);
  REQUIRE(r.descriptor.fields.size() == 2);
  const fp::HidField& x = r.descriptor.fields[1];
  CHECK(x.bit_offset == 8);
  CHECK(x.bit_size == 8);
  CHECK(x.logical_min == -127);
  CHECK(x.is_signed());
  CHECK(x.is_relative());
  CHECK(x.usage_at(0) == fp::hid_usage(0x01, 0x30));
  CHECK(r.descriptor.fields[0].usage_count() == 8);
  CHECK(r.descriptor.fields[0].usage_at(7) == fp::hid_usage(0x09, 0x08));
}

TEST_CASE("describe lists every field with its signals", "[firmware_protocol]") {
  const std::vector<uint8_t> bytes = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x00,
                                      0x26, 0xFF, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0x75, 0x08,
                                      0x95, 0x01, 0x81, 0x01, 0xC0};
  const fp::HidParseResult r = parse(bytes);
  REQUIRE(r);
  const std::string text = fp::describe_hid_descriptor(r.descriptor);
  CHECK_THAT(text, Catch::Contains("input report 0: 3 bytes"));
  CHECK_THAT(text, Catch::Contains("bit 0 size 8 count 2"));
  CHECK_THAT(text, Catch::Contains("logical 0..255"));
  CHECK_THAT(text, Catch::Contains("-> x y"));
  CHECK_THAT(text, Catch::Contains("-> padding"));
  CHECK_THAT(text, Catch::Contains("Application(0x01:0x05)"));
}

TEST_CASE("Xbox Elite 2 report sizes match the totals of xbe2_linux.md", "[firmware_protocol]") {
  const std::string path = data_file("hid/xbe2_linux.md");
  if (path.empty()) {
    WARN("xbe2_linux.md not found: skipped");
    return;
  }
  const fp::HidDescriptor d = fp::load_hid_descriptor_file(path);
  // "NN | ..." rows name the report, the following "Sz" row ends in "<n> Bits".
  std::map<int, uint32_t> totals;
  std::istringstream in(slurp(path));
  std::string line;
  int id = -1;
  const std::regex id_row(R"(^([0-9A-Fa-f]{2})\s+\|)");
  const std::regex total(R"((\d+) Bits\s*$)");
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, id_row)) id = std::stoi(m[1].str(), nullptr, 16);
    if (line.starts_with("Sz") && id >= 0 && std::regex_search(line, m, total)) {
      totals[id] = static_cast<uint32_t>(std::stoul(m[1].str()));
    }
  }
  REQUIRE(totals.size() == 10);
  // Rows 05 and 0A disagree with the doc's own hex dump: 05 lists only the
  // modifier byte of the 8-byte keyboard report, and 0A's cells add up to 88
  // bits where its total says 78. They are left out.
  totals.erase(0x05);
  totals.erase(0x0A);
  for (const auto& [report_id, bits] : totals) {
    INFO("report " << report_id);
    uint32_t found = 0;
    for (const fp::HidReportLayout& r : d.reports) {
      if (r.report_id == report_id) found = r.size_bits;
    }
    CHECK(found == bits);
  }
  // The doc's "0x01 .. 0x13" vendor (0xFF00) usages become vendor signals.
  const std::vector<fp::HidSignal> features = fp::hid_signals(d, fp::HidReportKind::Feature);
  const auto named = [&](const std::string& name) {
    return std::any_of(features.begin(), features.end(), [&](const fp::HidSignal& s) { return s.name == name; });
  };
  CHECK(named("vendor_ff00_0001"));
  CHECK(named("vendor_ff00_0004_60"));
  CHECK_FALSE(named("vendor_ff00_0004_61"));
}
