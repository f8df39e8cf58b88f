// hid-recorder's format (hil/io/hid_recording.hpp): what the recorder
// writes reads back exactly, the header's worked example is what it writes,
// hid-tools' own files read (the shared data's, and one as hid-recorder
// writes events), and a line that is not hid-recorder's is refused with its
// file and line.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "firmware_protocol/hid_text.hpp"
#include "hil/io/hid_recording.hpp"
#include "tests/hid_test_devices.hpp"

using namespace rise::hil::io;
using Kind = HidRecordingRecord::Kind;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rise_hidrec_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}

std::vector<HidRecordingRecord> read_all(const std::string& path) {
  HidRecordingReader reader(path);
  std::vector<HidRecordingRecord> out;
  HidRecordingRecord r;
  while (reader.next(r)) out.push_back(r);
  return out;
}

const std::vector<uint8_t> gravis(std::begin(rise::test::gravis_descriptor), std::end(rise::test::gravis_descriptor));
const std::string gravis_hex =
    "05 01 09 05 a1 01 05 01 09 01 a1 00 09 30 09 31 15 00 26 ff 00 75 08 95 02 81 02 c0 05 09 19 01 29 0a 15 00 "
    "25 01 75 01 95 0a 81 02 95 01 75 06 81 01 c0";

HidIdentity uhid_gravis() {
  HidIdentity id;
  id.name = "Gravis GamePad Pro (uhid)";
  id.bus = 5;
  id.vendor_id = 0x0428;
  id.product_id = 0x4001;
  return id;
}

constexpr int64_t t0 = 1'700'000'000'000'000;

}  // namespace

TEST_CASE("hid recording writes the header's worked example and reads it back exactly", "[hil_io]") {
  const std::string path = temp_path("worked.hid");
  {
    HidRecordingWriter w(path, "pad");
    w.plug(t0 + 100'000, gravis, uhid_gravis());
    w.report(t0 + 250'000, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00});
    w.report(t0 + 258'000, std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02});
    w.unplug(t0 + 1'000'000, "/dev/hidraw0: read failed (device gone)");
    w.plug(t0 + 1'500'000, gravis, uhid_gravis());
    w.report(t0 + 1'550'000, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00});
    w.end(t0 + 2'000'000);
    CHECK(w.reports() == 3);
    CHECK(w.errors() == 0);
  }
  const std::string block = "R: 51 " + gravis_hex + "\nN: Gravis GamePad Pro (uhid)\nI: 5 0428 4001\n";
  CHECK(read_text(path) ==
        "# rise-hild hid recording v1: source 'pad'; hid-recorder's format, see hil/io/hid_recording.hpp\n"
        "# plugged at 1700000000.100000\n" +
            block +
            "# start 1700000000.250000 (the wall-clock time of E: 000000.000000)\n"
            "E: 000000.000000 4 7f 7f 00 00\n"
            "E: 000000.008000 4 00 ff 05 02\n"
            "# unplugged at 1700000001.000000: /dev/hidraw0: read failed (device gone)\n"
            "# plugged at 1700000001.500000\n" +
            block +
            "E: 000001.300000 4 7f 7f 00 00\n"
            "# end at 1700000002.000000\n");

  HidRecordingReader reader(path);
  CHECK(reader.epoch_clock());
  CHECK(reader.reports() == 3);
  CHECK(reader.plugs() == 2);
  const auto records = read_all(path);
  REQUIRE(records.size() == 7);
  const std::vector<std::pair<Kind, int64_t>> expected = {
      {Kind::Plug, t0 + 100'000},      {Kind::Report, t0 + 250'000}, {Kind::Report, t0 + 258'000},
      {Kind::Unplug, t0 + 1'000'000}, {Kind::Plug, t0 + 1'500'000}, {Kind::Report, t0 + 1'550'000},
      {Kind::End, t0 + 2'000'000}};
  for (std::size_t i = 0; i < records.size(); ++i) {
    INFO("record " << i);
    CHECK(records[i].kind == expected[i].first);
    CHECK(records[i].time_us == expected[i].second);
  }
  CHECK(records[0].bytes == gravis);
  CHECK(records[0].identity == uhid_gravis());
  CHECK(records[0].line == 3);
  CHECK(records[2].bytes == std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02});
  CHECK(records[4].bytes == gravis);
  CHECK(records[6].line == 15);
  std::filesystem::remove(path);
}

TEST_CASE("hid recording round-trips reports of every length and times of every size", "[hil_io]") {
  const std::size_t length = GENERATE(1, 2, 63, 64, 4096);
  const int64_t since_first = GENERATE(int64_t{0}, int64_t{1}, int64_t{999'999}, int64_t{1'000'000},
                                       int64_t{86'400'000'000}, int64_t{1'234'567'890'123'456});
  std::vector<uint8_t> report(length);
  for (std::size_t i = 0; i < length; ++i) report[i] = static_cast<uint8_t>(i * 37 + 11);
  const std::string path = temp_path("roundtrip.hid");
  HidIdentity id = uhid_gravis();
  id.phys = "usb-0000:00:14.0-2/input0";
  {
    HidRecordingWriter w(path, "pad");
    w.plug(t0, gravis, id);
    w.report(t0 + 5, std::vector<uint8_t>{1});
    w.report(t0 + 5 + since_first, report);
  }
  const auto records = read_all(path);
  REQUIRE(records.size() == 3);
  CHECK(records[0].identity == id);
  CHECK(records[2].kind == Kind::Report);
  CHECK(records[2].time_us == t0 + 5 + since_first);
  CHECK(records[2].bytes == report);
  std::filesystem::remove(path);
}

TEST_CASE("hid recording reads a file as hid-recorder writes it, timed from its first report", "[hil_io]") {
  // hidtools/hidraw.py's dump(): the name and the parsed descriptor as
  // comments, the device block, then each event with its decoded fields.
  const std::string path = write_text("hidtools.hid",
                                      "# Gravis GamePad Pro USB \n"
                                      "# 0x05, 0x01,                    // Usage Page (Generic Desktop)        0\n"
                                      "R: 51 " + gravis_hex + "\n"
                                      "N: Gravis GamePad Pro USB \n"
                                      "P: usb-0000:00:14.0-2/input0\n"
                                      "I: 3 0428 4001\n"
                                      "# X:    0 | Y:  255 | Button: 1  0  1  0  0  0  0  0  0  1 | #\n"
                                      "E: 000000.000000 4 00 ff 05 02\n"
                                      "# X:  127 | Y:  127 | Button: 0  0  0  0  0  0  0  0  0  0 | #\n"
                                      "E: 000002.016011 4 7f 7f 00 00\n");
  HidRecordingReader reader(path);
  CHECK_FALSE(reader.epoch_clock());
  const auto records = read_all(path);
  REQUIRE(records.size() == 3);
  CHECK(records[0].kind == Kind::Plug);
  CHECK(records[0].time_us == 0);
  CHECK(records[0].bytes == gravis);
  CHECK(records[0].identity.name == "Gravis GamePad Pro USB");
  CHECK(records[0].identity.phys == "usb-0000:00:14.0-2/input0");
  CHECK(records[0].identity.bus == 3);
  CHECK(records[1].time_us == 0);
  CHECK(records[2].time_us == 2'016'011);
  CHECK(records[2].line == 10);
  // Several devices (hid-recorder given two nodes): only device 0's lines.
  const std::string two = write_text("two.hid",
                                     "D: 0\nR: 2 05 01\nN: a\nI: 3 1 2\nD: 1\nR: 3 05 01 09\nN: b\nI: 3 3 4\n"
                                     "D: 1\nE: 000000.000000 1 11\nD: 0\nE: 000000.500000 1 22\n");
  const auto mixed = read_all(two);
  REQUIRE(mixed.size() == 2);
  CHECK(mixed[0].identity.name == "a");
  CHECK(mixed[0].bytes == std::vector<uint8_t>{0x05, 0x01});
  CHECK(mixed[1].bytes == std::vector<uint8_t>{0x22});
  CHECK(mixed[1].time_us == 500'000);
  std::filesystem::remove(path);
  std::filesystem::remove(two);
}

TEST_CASE("hid recording refuses a line that is not hid-recorder's, naming the file and line", "[hil_io]") {
  const auto [body, message] = GENERATE(table<std::string, std::string>({
      {"E: 000000.000000 1 00\n", ":1: E: a report before any R: descriptor"},
      {"R: 3 05 01\n", ":1: R: the length does not match the bytes after it"},
      {"R: 2 05 01\nE: 0.5 1 00\n", ":2: E: the time is not SEC.USEC with six digits of microseconds"},
      {"R: 2 05 01\nE: 000000.000000 2 00\n", ":2: E: the length does not match the bytes after it"},
      {"R: 2 05 01\nE: 000000.000000 1 0x100\n", ":2: E: a byte that is not one or two hex digits"},
      {"R: 2 05 01\nE: 000000.000000 0\n", ":2: E: an empty report"},
      {"R: 2 05 01\nI: 3 0428\n", ":2: I: expected '<bus> <vid> <pid>' in hex"},
      {"R: 2 05 01\nX: what\n", ":2: X: not a hid-recorder line"},
      {"R: 2 05 01\n(1700000000.000000) can0 123#00\n", ":2: (: not a hid-recorder line"},
      {"# plugged at 17000.5\nR: 2 05 01\n", ":1: #: the time is not SEC.USEC"},
      {"D: x\n", ":1: D: expected a device number"},
  }));
  INFO(body);
  const std::string path = write_text("bad.hid", body);
  CHECK_THROWS_WITH(HidRecordingReader(path), Catch::StartsWith(path + message));
  std::filesystem::remove(path);
}

TEST_CASE("hid recording refuses a file without a descriptor and one that is missing", "[hil_io]") {
  const std::string none = write_text("none.hid", "# nothing\n\n");
  CHECK_THROWS_WITH(HidRecordingReader(none), none + ": no 'R:' descriptor line: not a hid-recorder file");
  CHECK_FALSE(looks_like_hid_recording(none));
  CHECK_THROWS_WITH(HidRecordingReader(none + ".missing"), none + ".missing: cannot open: No such file or directory");
  std::filesystem::remove(none);
}

TEST_CASE("hid recording reads hid-tools' device files of the shared data as hid_text does", "[hil_io]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string name = GENERATE("hid-tools_AsusGamepad.hid", "hid-tools_PS3Controller.hid",
                                    "hid-tools_PS4ControllerBluetooth.hid", "hid-tools_PS4ControllerUSB.hid",
                                    "hid-tools_PS5ControllerBluetooth.hid", "hid-tools_PS5ControllerUSB.hid",
                                    "hid-tools_SaitekGamepad.hid");
  const std::string path = root ? std::string(root) + "/hid/" + name : std::string();
  if (path.empty() || !std::filesystem::exists(path)) {
    WARN("RISE_TEST_DATA has no hid/" << name << ": skipped");
    return;
  }
  INFO(path);
  const rise::firmware_protocol::HidDescriptorSource oracle = rise::firmware_protocol::read_hid_descriptor_file(path);
  CHECK(looks_like_hid_recording(path));
  HidRecordingReader reader(path);
  CHECK(reader.plugs() == 1);
  CHECK(reader.reports() == 0);  // R:/N:/I: only: no E: line
  const auto records = read_all(path);
  REQUIRE(records.size() == 1);
  CHECK(records[0].kind == Kind::Plug);
  CHECK(records[0].bytes == oracle.bytes);
  CHECK(records[0].identity.name == oracle.name);
  CHECK(records[0].identity.bus == oracle.bus);
  CHECK(records[0].identity.vendor_id == oracle.vendor_id);
  CHECK(records[0].identity.product_id == oracle.product_id);
}

TEST_CASE("hid recording on a full disk counts the lost lines and goes on", "[hil_io]") {
  // /dev/full takes the writes into the stream's buffer and fails its flushes,
  // which come at least every 100 ms.
  HidRecordingWriter w("/dev/full", "pad");
  w.plug(t0, gravis, uhid_gravis());
  const std::vector<uint8_t> report = {0x7f, 0x7f, 0x00, 0x00};
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  int64_t written = 0;
  do {
    w.report(t0 + ++written * 1000, report);
  } while (w.errors() == 0 && std::chrono::steady_clock::now() < give_up);
  CHECK(w.errors() > 0);
  CHECK(w.reports() < written);  // the failed line is not counted as recorded
}
