#pragma once

// A CANopen device's electronic data sheet (EDS) or device configuration
// file (DCF), CiA 306-1 v1.3: the INI-style object dictionary, read for what
// a master of the device needs: the TPDOs and RPDOs (communication parameters
// 0x1800+n / 0x1400+n, mappings 0x1A00+n / 0x1600+n), the producer heartbeat
// time (0x1017) and the communication cycle period (0x1006).
//
// Read: object sections `[6000]` and sub-object sections `[6000sub1]` with
// ParameterName, ObjectType, DataType, AccessType, DefaultValue (a DCF's
// ParameterValue wins), PDOMapping, LowLimit, HighLimit; values decimal,
// 0x-hex or 0-octal, with `$NODEID+` formulas (CiA 306 §4.6.3); a DCF's
// [DeviceComissioning] NodeID must be the node's. Other
// sections ([FileInfo], [DeviceInfo], [MandatoryObjects], [Comments], ...)
// are skipped. Not read: CompactSubObj and CompactPDO (refused, by name),
// object links, dynamic PDO mapping at run time.
//
// A PDO's payload is its mapped objects in mapping order, packed from bit 0
// of byte 0 upwards, each little endian (CiA 301 §7.5.2.36 and §7.1.2): so
// each mapped object is a little-endian ("Intel") DbcSignal whose start bit
// is the sum of the lengths before it, and the PDO a DbcMessage, decoded by
// dbc.hpp's extract_raw / insert_raw. Worked example (held by
// tests/firmware_protocol/canopen_eds_test.cpp), TPDO1 of node 5 mapping
// 0x20000110 0x20000210 0x20000301 0x00010001 0x20000401 (INTEGER16,
// UNSIGNED16, BOOLEAN, a 1-bit dummy, BOOLEAN):
//   185#CC FF 34 12 05 -> 0x2000:01 = 0xFFCC = -52 (bits 0..15),
//   0x2000:02 = 0x1234 = 4660 (bits 16..31), 0x2000:03 = 1 (bit 32),
//   0x2000:04 = 1 (bit 34).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "firmware_protocol/dbc.hpp"

namespace rise::firmware_protocol::canopen {

/// One entry of the object dictionary: a VAR object (subindex 0) or one
/// sub-object of an ARRAY / RECORD.
struct OdEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  std::string name;          ///< ParameterName
  uint16_t data_type = 0;    ///< CiA 301 Table 44 (0x0003 INTEGER16, 0x0007 UNSIGNED32, ...)
  std::string access_type;   ///< ro, wo, rw, rwr, rww, const (lower case)
  std::string default_value; ///< as written (a DCF's ParameterValue when given)
  bool pdo_mapping = false;
  std::optional<double> low_limit;
  std::optional<double> high_limit;
  int line = 0;         ///< the section's line
  std::string section;  ///< the section's name as written ("1A00sub1")
};

/// One object mapped into a PDO.
struct PdoEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t bits = 0;
  uint32_t bit_offset = 0;       ///< from bit 0 of byte 0
  const OdEntry* entry = nullptr;  ///< nullptr for a dummy entry (index 0x0001..0x0007)
};

struct Pdo {
  bool transmit = true;   ///< TPDO (device → master) or RPDO (master → device)
  unsigned number = 1;    ///< 1-based: TPDO1 is 0x1800 / 0x1A00
  uint32_t cob_id = 0;    ///< without the flag bits
  bool extended = false;  ///< bit 29: 29-bit identifier
  uint8_t transmission_type = 0xFF;
  uint16_t inhibit_100us = 0;  ///< sub 3: least time between two event-driven sends, 100 µs units
  uint16_t event_timer_ms = 0;  ///< sub 5: sent at least this often when event-driven, 0 = only on change
  uint32_t bits = 0;      ///< sum of the mapped lengths
  std::vector<PdoEntry> entries;
  int line = 0;           ///< the mapping object's section
  std::string label() const;  ///< "TPDO1"
};

/// A PDO-mapped object as a signal of its PDO's message.
struct PdoSignal {
  const Pdo* pdo = nullptr;
  const DbcMessage* message = nullptr;
  const DbcSignal* signal = nullptr;
  const OdEntry* entry = nullptr;
};

/// An object named by a panel definition: `0x2000:01`, `2000:1`,
/// `2000sub1` or a ParameterName.
struct OdLookup {
  const OdEntry* entry = nullptr;
  std::string error;  ///< why none was found ("no object 0x2000:09", "'Button' names 3 objects: ...")
};

class EdsDevice {
 public:
  /// Reads an EDS or DCF for the node `node_id` (1..127; $NODEID). Throws
  /// std::runtime_error "path:line: [section] key: what" for every mistake
  /// (a line that is no key=value, a bad number, a mapping to an object
  /// that is missing, not PDO-mappable or of another length, a PDO over 64
  /// bits, a missing mandatory entry, a heartbeat time of 0).
  static EdsDevice load(const std::string& path, uint8_t node_id);
  static EdsDevice parse(std::string_view text, const std::string& file, uint8_t node_id);

  const std::string& file() const { return file_; }
  uint8_t node_id() const { return node_id_; }
  const std::string& product_name() const { return product_name_; }
  const std::vector<OdEntry>& entries() const { return entries_; }
  const std::vector<Pdo>& tpdos() const { return tpdos_; }
  const std::vector<Pdo>& rpdos() const { return rpdos_; }
  /// The PDOs as messages whose signals are the mapped objects, in the
  /// order of tpdos() / rpdos() (dummy entries have no signal).
  const std::vector<DbcMessage>& tpdo_messages() const { return tpdo_messages_; }
  const std::vector<DbcMessage>& rpdo_messages() const { return rpdo_messages_; }
  /// 0x1017 Producer heartbeat time, ms (> 0: load refuses 0).
  uint16_t heartbeat_ms() const { return heartbeat_ms_; }
  /// 0x1006 Communication cycle period, µs (0 = not given).
  uint32_t sync_period_us() const { return sync_period_us_; }
  /// Whether a TPDO is synchronous (needs SYNC from the master).
  bool has_sync_tpdo() const;

  const OdEntry* find(uint16_t index, uint8_t subindex) const;
  OdLookup lookup(std::string_view name_or_address) const;
  /// Where `entry` is mapped in a TPDO (`transmit`) or RPDO; all null when
  /// it is not.
  PdoSignal pdo_signal(const OdEntry& entry, bool transmit) const;
  /// Integer value of an entry's DefaultValue ($NODEID resolved); nullopt
  /// when it is empty or not a number.
  std::optional<uint64_t> value(uint16_t index, uint8_t subindex) const;

 private:
  std::string file_;
  uint8_t node_id_ = 1;
  std::string product_name_;
  std::vector<OdEntry> entries_;
  std::vector<Pdo> tpdos_;
  std::vector<Pdo> rpdos_;
  std::vector<DbcMessage> tpdo_messages_;
  std::vector<DbcMessage> rpdo_messages_;
  uint16_t heartbeat_ms_ = 0;
  uint32_t sync_period_us_ = 0;

  friend class EdsReader;
};

/// "0x2000:01", "2000:1", "0x2000sub1", "2000" (subindex 0) → index and
/// subindex; nullopt when the text is not such an address.
std::optional<std::pair<uint16_t, uint8_t>> parse_od_address(std::string_view text);
/// "0x2000:01".
std::string od_address(uint16_t index, uint8_t subindex);
/// Bits of a data type in a PDO (CiA 301 Table 44); 0 for one that cannot
/// be mapped (strings, domains).
uint8_t data_type_bits(uint16_t data_type);
bool data_type_signed(uint16_t data_type);
bool data_type_real(uint16_t data_type);

}  // namespace rise::firmware_protocol::canopen
