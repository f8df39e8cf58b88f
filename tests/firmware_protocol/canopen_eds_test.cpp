#include "firmware_protocol/canopen_eds.hpp"

#include <catch2/catch.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace fp = rise::firmware_protocol;
namespace co = rise::firmware_protocol::canopen;

namespace {

const std::string kShippedEds = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console_canopen.eds";

// A VAR section.
std::string var(const std::string& section, const std::string& name, const std::string& type,
                const std::string& value, bool mappable = false, const std::string& extra = "") {
  return "[" + section + "]\nParameterName=" + name + "\nObjectType=0x7\nDataType=" + type +
         "\nAccessType=rw\nDefaultValue=" + value + "\nPDOMapping=" + (mappable ? "1" : "0") + "\n" + extra + "\n";
}

// A small device: heartbeat 100 ms, TPDO1 with `mapping` (0xIIIISSLL values),
// objects 0x2000 (INTEGER16, UNSIGNED16, two BOOLEANs, UNSIGNED8) to map.
std::string device(const std::vector<std::string>& mapping, const std::string& cob_id = "$NODEID+0x180",
                   const std::string& extra = "") {
  std::string text = "[FileInfo]\nFileName=t.eds\n\n[DeviceInfo]\nProductName=Test console\n\n";
  text += var("1017", "Producer heartbeat time", "0x0006", "100");
  text += "[1800]\nParameterName=TPDO1 communication parameter\nObjectType=0x9\nSubNumber=3\n\n";
  text += var("1800sub0", "Highest sub-index supported", "0x0005", "2");
  text += var("1800sub1", "COB-ID used by TPDO", "0x0007", cob_id);
  text += var("1800sub2", "Transmission type", "0x0005", "0xFE");
  text += "[1A00]\nParameterName=TPDO1 mapping parameter\nObjectType=0x9\nSubNumber=9\n\n";
  text += var("1A00sub0", "Number of mapped objects", "0x0005", std::to_string(mapping.size()));
  for (std::size_t i = 0; i < mapping.size(); ++i)
    text += var("1A00sub" + std::to_string(i + 1), "Mapped object", "0x0007", mapping[i]);
  text += "[2000]\nParameterName=Inputs\nObjectType=0x9\nSubNumber=6\n\n";
  text += var("2000sub0", "Highest sub-index supported", "0x0005", "5");
  text += var("2000sub1", "Stick X", "0x0003", "0", true, "LowLimit=-1000\nHighLimit=1000");
  text += var("2000sub2", "Wheel", "0x0006", "0", true);
  text += var("2000sub3", "Button A", "0x0001", "0", true);
  text += var("2000sub4", "Button B", "0x0001", "0", true);
  text += var("2000sub5", "Selector", "0x0005", "0", false);
  return text + extra;
}

std::string error_of(const std::string& text) {
  try {
    co::EdsDevice::parse(text, "t.eds", 5);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// The line of the first occurrence of `needle` in `text` (1-based).
int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

}  // namespace

TEST_CASE("the shipped console EDS reads as two TPDOs and one RPDO", "[firmware_protocol][canopen]") {
  const co::EdsDevice eds = co::EdsDevice::load(kShippedEds, 5);
  CHECK(eds.product_name() == "RISE operator console (CANopen)");
  CHECK(eds.heartbeat_ms() == 100);
  CHECK(eds.sync_period_us() == 10000);
  CHECK(eds.has_sync_tpdo());
  REQUIRE(eds.tpdos().size() == 2);
  REQUIRE(eds.rpdos().size() == 1);
  const co::Pdo& sticks = eds.tpdos()[0];
  CHECK(sticks.cob_id == 0x185);  // $NODEID+0x180 for node 5
  CHECK(sticks.transmission_type == 1);
  CHECK(sticks.bits == 64);
  const co::Pdo& buttons = eds.tpdos()[1];
  CHECK(buttons.cob_id == 0x285);
  CHECK(buttons.transmission_type == 0xFE);
  CHECK(buttons.event_timer_ms == 100);
  CHECK(buttons.inhibit_100us == 50);
  CHECK(buttons.bits == 16);
  // Three dummy entries (0x0001, BOOLEAN) pad the buttons to a byte.
  CHECK(buttons.entries[5].entry == nullptr);
  CHECK(buttons.entries[8].bit_offset == 8);
  CHECK(eds.tpdo_messages()[1].signals.size() == 6);
  CHECK(eds.rpdos()[0].cob_id == 0x205);
  CHECK(eds.rpdo_messages()[0].dlc == 3);
  const co::OdLookup speed = eds.lookup("Speed display");
  REQUIRE(speed.entry);
  const co::PdoSignal s = eds.pdo_signal(*speed.entry, false);
  REQUIRE(s.signal);
  CHECK(s.signal->start_bit == 8);
  CHECK(s.signal->length_bits == 16);
  CHECK(s.signal->is_signed);
  CHECK_FALSE(eds.pdo_signal(*speed.entry, true).signal);
  // firmware_protocol/README.md's worked example: 285#0302.
  const std::vector<uint8_t> tpdo2{0x03, 0x02};
  const auto& m = eds.tpdo_messages()[1];
  CHECK(fp::extract_raw(m.signals[0], tpdo2) == 1);  // Dead-man
  CHECK(fp::extract_raw(m.signals[1], tpdo2) == 1);  // E-stop
  CHECK(fp::extract_raw(m.signals[2], tpdo2) == 0);  // Horn
  CHECK(m.signals[5].name == "Camera select");
  CHECK(fp::extract_raw(m.signals[5], tpdo2) == 2);
}

TEST_CASE("PDO objects unpack at their bit offsets, little endian, signed or not", "[firmware_protocol][canopen]") {
  // The worked example of canopen_eds.hpp: INTEGER16 0x2000:01, UNSIGNED16
  // 0x2000:02, BOOLEAN 0x2000:03, a 1-bit dummy, BOOLEAN 0x2000:04.
  const std::string text =
      device({"0x20000110", "0x20000210", "0x20000301", "0x00010001", "0x20000401"});
  const co::EdsDevice eds = co::EdsDevice::parse(text, "t.eds", 5);
  REQUIRE(eds.tpdo_messages().size() == 1);
  const fp::DbcMessage& m = eds.tpdo_messages()[0];
  CHECK(m.id == 0x185);
  CHECK(m.dlc == 5);
  REQUIRE(m.signals.size() == 4);
  const std::vector<uint8_t> frame{0xCC, 0xFF, 0x34, 0x12, 0x05};  // 185#CCFF341205
  CHECK(fp::extract_raw(m.signals[0], frame) == -52);       // 0xFFCC as INTEGER16
  CHECK(fp::extract_raw(m.signals[1], frame) == 0x1234);    // UNSIGNED16, low byte first
  CHECK(fp::extract_raw(m.signals[2], frame) == 1);         // bit 32
  CHECK(m.signals[3].start_bit == 34);                      // after the 1-bit dummy
  CHECK(fp::extract_raw(m.signals[3], frame) == 1);         // bit 34
  CHECK(m.signals[0].minimum == -1000);
  CHECK(m.signals[0].maximum == 1000);
  SECTION("an unsigned 16-bit object never reads negative") {
    const std::vector<uint8_t> high{0x00, 0x80, 0xFF, 0xFF, 0x00};
    CHECK(fp::extract_raw(m.signals[0], high) == -32768);
    CHECK(fp::extract_raw(m.signals[1], high) == 65535);
    CHECK(fp::extract_raw(m.signals[2], high) == 0);
  }
  SECTION("insert_raw writes what extract_raw reads") {
    std::vector<uint8_t> out(5, 0);
    fp::insert_raw(m.signals[0], static_cast<uint64_t>(int64_t{-2}), out);
    fp::insert_raw(m.signals[3], 1, out);
    CHECK(out == std::vector<uint8_t>{0xFE, 0xFF, 0x00, 0x00, 0x04});
  }
}

TEST_CASE("EDS values take $NODEID formulas, hex, octal and a DCF's ParameterValue", "[firmware_protocol][canopen]") {
  const std::string dcf = device({"0x20000110"}, "0x180+$NODEID") +
                          "[2100]\nParameterName=Configured\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\n"
                          "DefaultValue=010\nParameterValue=0x20\nPDOMapping=0\n";
  const co::EdsDevice eds = co::EdsDevice::parse(dcf, "t.dcf", 0x10);
  CHECK(eds.tpdos()[0].cob_id == 0x190);
  CHECK(eds.value(0x2100, 0) == 0x20u);
  CHECK(co::EdsDevice::parse(device({"0x20000110"}, "0x80000180"), "t.eds", 5).tpdos().empty());  // bit 31: not used
  const co::EdsDevice octal = co::EdsDevice::parse(device({"0x20000110"}) + var("2200", "Octal", "0x0005", "017"), "t.eds", 5);
  CHECK(octal.value(0x2200, 0) == 15u);
  CHECK(co::EdsDevice::parse(device({"0x20000110"}, "0x2000018A"), "t.eds", 5).tpdos()[0].extended);
}

TEST_CASE("objects are found by index:subindex or by a unique ParameterName", "[firmware_protocol][canopen]") {
  const co::EdsDevice eds = co::EdsDevice::parse(device({"0x20000110"}), "t.eds", 5);
  for (const char* address : {"0x2000:01", "2000:1", "2000sub1", "0x2000sub01", "0x2000:0x01"}) {
    INFO(address);
    REQUIRE(eds.lookup(address).entry);
    CHECK(eds.lookup(address).entry->name == "Stick X");
  }
  CHECK(eds.lookup("Stick X").entry->subindex == 1);
  CHECK(eds.lookup("0x2000:09").error == "no object 0x2000:09 in t.eds");
  CHECK(eds.lookup("Nope").error == "no object 'Nope' (a ParameterName or index:subindex) in t.eds");
  CHECK(eds.lookup("Highest sub-index supported").error.find("names 2 objects (0x1800:00, 0x2000:00): bind one by index:subindex") !=
        std::string::npos);
  CHECK(co::od_address(0x1A00, 0x0B) == "0x1A00:0B");
  CHECK_FALSE(co::parse_od_address("Stick X"));
  CHECK_FALSE(co::parse_od_address("200:1"));
  CHECK_FALSE(co::parse_od_address("2000:100"));
}

TEST_CASE("EDS mistakes name file:line, the section and the key", "[firmware_protocol][canopen]") {
  SECTION("a mapping to a missing object") {
    const std::string text = device({"0x20000910"});
    CHECK(error_of(text) == "t.eds:" + std::to_string(line_of(text, "[1A00sub1]")) +
                                ": [1A00sub1] DefaultValue: TPDO1 maps 0x2000:09: the EDS has no such object");
  }
  SECTION("a mapping to an object that is not PDO-mappable") {
    CHECK_THAT(error_of(device({"0x20000508"})),
               Catch::Contains("[1A00sub1] DefaultValue: TPDO1 maps 0x2000:05: 'Selector' is not PDO-mappable"));
  }
  SECTION("a mapping length that is not the data type's") {
    CHECK_THAT(error_of(device({"0x20000108"})),
               Catch::Contains("TPDO1 maps 0x2000:01: length 8 bits, but its data type has 16"));
  }
  SECTION("a PDO over 64 bits") {
    CHECK_THAT(error_of(device({"0x20000110", "0x20000210", "0x20000110", "0x20000210", "0x20000301"})),
               Catch::Contains("[1A00sub5] DefaultValue: TPDO1 maps 0x2000:03: the PDO's mapping exceeds 64 bits"));
  }
  SECTION("a count of mapped objects without their entries") {
    std::string text = device({"0x20000110"});
    text.replace(text.find("DefaultValue=1\nPDOMapping=0\n\n[1A00sub1]"), 14, "DefaultValue=2");
    CHECK_THAT(error_of(text), Catch::Contains("TPDO1 maps 2 objects but 0x1A00sub2 is missing"));
  }
  SECTION("a value that is no number") {
    const std::string text = device({"0x20000110"}, "$NODE+0x180");
    CHECK(error_of(text) == "t.eds:" + std::to_string(line_of(text, "[1800sub1]")) +
                                ": [1800sub1] DefaultValue: '$NODE+0x180' is not a number (decimal, 0x-hex, "
                                "0-octal, $NODEID+N)");
  }
  SECTION("a DCF of another node") {
    const std::string text = "[DeviceComissioning]\nNodeID=6\nBaudrate=500\n\n" + device({"0x20000110"});
    CHECK(error_of(text) == "t.eds:2: [DeviceComissioning] NodeID: the DCF configures node 6, not node 5");
    CHECK(co::EdsDevice::parse(text, "t.dcf", 6).tpdos()[0].cob_id == 0x186);
  }
  SECTION("a value beyond its object's type") {
    std::string text = device({"0x20000110"});
    text.replace(text.find("DefaultValue=100"), 16, "DefaultValue=70000");
    CHECK(error_of(text) == "t.eds:" + std::to_string(line_of(text, "[1017]")) +
                                ": [1017] DefaultValue: 70000 is out of range 0..65535");
    CHECK_THAT(error_of(device({"0x20000110"}, "0x100000180")),
               Catch::Contains("[1800sub1] DefaultValue: 4294967680 is out of range 0..4294967295"));
  }
  SECTION("a line that is not key=value, a key before any section, a section or key twice") {
    CHECK(error_of("[FileInfo]\nFileName\n") == "t.eds:2: [FileInfo] expected key=value or [section]");
    CHECK(error_of("FileName=x\n") == "t.eds:1: FileName: key before the first [section]");
    CHECK(error_of("[1017]\nParameterName=a\n[1017]\n") ==
          "t.eds:3: [1017] section given twice (first at line 1)");
    CHECK(error_of("[1017]\nParameterName=a\nparametername=b\n") ==
          "t.eds:3: [1017] parametername: given twice in this section");
    CHECK(error_of("[1017\n") == "t.eds:1: section header without ']'");
  }
  SECTION("an object without ParameterName or DataType") {
    CHECK(error_of("[1017]\nDataType=0x0006\nDefaultValue=100\n") == "t.eds:1: [1017] ParameterName: missing");
    CHECK(error_of("[1017]\nParameterName=HB\nDefaultValue=100\n") == "t.eds:1: [1017] DataType: missing");
  }
  SECTION("no heartbeat: node guarding is not supported") {
    CHECK_THAT(error_of("[FileInfo]\nFileName=t.eds\n"),
               Catch::Contains("no object 0x1017 (Producer heartbeat time)"));
    std::string text = device({"0x20000110"});
    text.replace(text.find("DefaultValue=100"), 16, "DefaultValue=0");
    CHECK(error_of(text) == "t.eds:" + std::to_string(line_of(text, "[1017]")) +
                                ": [1017] DefaultValue: producer heartbeat time 0: the bridge watches the node by its "
                                "heartbeat (node guarding is not supported)");
  }
  SECTION("compact storage is refused by name") {
    CHECK_THAT(error_of(device({"0x20000110"}) + "[2300]\nParameterName=C\nObjectType=0x8\nCompactSubObj=4\n"),
               Catch::Contains("[2300] compactsubobj: compact storage is not supported"));
  }
  SECTION("a node id outside 1..127") {
    CHECK_THROWS_WITH(co::EdsDevice::parse(device({"0x20000110"}), "t.eds", 0), "t.eds: node id 0 is not 1..127");
  }
  SECTION("a file that is not there") {
    CHECK_THROWS_WITH(co::EdsDevice::load("/nonexistent/x.eds", 5), "/nonexistent/x.eds: cannot open");
  }
}

TEST_CASE("an EDS as CANopen tools write it reads: empty values, lower-case sub-indices, comments",
          "[firmware_protocol][canopen]") {
  // As CANopenNode's and CANopen Magic's EDS files: ;-comment keys, empty
  // DefaultValue on error fields, subA hex sub-indices, SubNumber in hex,
  // CRLF line ends, RPDOs marked not used by bit 31.
  std::string text = device({"0x20000110"}) +
                     "[1003]\r\nParameterName=Pre-defined error field\r\nObjectType=0x8\r\n;StorageLocation=RAM\r\n"
                     "SubNumber=0xB\r\n\r\n"
                     "[1003subA]\r\nParameterName=Standard error field\r\nObjectType=0x7\r\nDataType=0x0007\r\n"
                     "AccessType=ro\r\nDefaultValue=\r\nPDOMapping=0\r\n\r\n" +
                     var("1400sub1", "COB-ID used by RPDO", "0x0007", "0x80000200+$NODEID") +
                     var("1600sub0", "Number of mapped objects", "0x0005", "0");
  const co::EdsDevice eds = co::EdsDevice::parse(text, "t.eds", 5);
  REQUIRE(eds.find(0x1003, 0x0A));
  CHECK(eds.find(0x1003, 0x0A)->default_value.empty());
  CHECK(eds.rpdos().empty());
  CHECK(eds.tpdos().size() == 1);
}
