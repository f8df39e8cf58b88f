#pragma once

// A reader for Vector DBC files (the de-facto CAN database format; grammar as
// in Vector's "DBC File Format Documentation" 1.0.5 and as cantools reads it)
// and a signal codec for the messages it describes.
//
// Read: VERSION, BU_, BO_ (bit 31 of the id = extended frame), SG_ with simple
// multiplexing (M / mN), VAL_, SIG_VALTYPE_ (IEEE float signals) and the
// "GenMsgCycleTime" BA_ attribute. Everything else (NS_, BS_, CM_, BA_DEF_,
// other BA_, VAL_TABLE_, SG_MUL_VAL_, ...) is skipped.

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rise::firmware_protocol {

enum class ByteOrder : uint8_t {
  LittleEndian,  ///< "@1", Intel: start bit is the least significant bit
  BigEndian,     ///< "@0", Motorola: start bit is the most significant bit
};

enum class SignalValueType : uint8_t { Integer, Float32, Float64 };

struct DbcSignal {
  std::string name;
  uint32_t start_bit = 0;    ///< as written in the file (DBC bit numbering)
  uint32_t length_bits = 0;  ///< 1..64
  ByteOrder byte_order = ByteOrder::LittleEndian;
  bool is_signed = false;
  SignalValueType value_type = SignalValueType::Integer;
  double factor = 1.0;  ///< physical = raw * factor + offset
  double offset = 0.0;
  double minimum = 0.0;  ///< physical range as written ([0|0] = not given)
  double maximum = 0.0;
  std::string unit;
  std::vector<std::string> receivers;
  bool is_multiplexer = false;  ///< "M": selects which multiplexed signals are present
  bool is_multiplexed = false;  ///< "mN": present only when the multiplexer reads N
  uint32_t multiplexer_value = 0;
  std::map<int64_t, std::string> value_names;  ///< VAL_: raw value → text
  int line = 0;                                ///< where the SG_ line is in the file
};

struct DbcMessage {
  uint32_t id = 0;        ///< without the extended flag
  bool extended = false;  ///< 29-bit identifier (bit 31 set in the file)
  std::string name;
  uint8_t dlc = 0;  ///< length in bytes (0..64)
  std::string transmitter;
  uint32_t cycle_time_ms = 0;  ///< BA_ "GenMsgCycleTime", 0 if not given
  std::vector<DbcSignal> signals;
  int line = 0;

  /// The signal called `signal_name`, or nullptr.
  const DbcSignal* signal(std::string_view signal_name) const;
};

/// One signal read from a frame. Points into the DbcDatabase that decoded it.
struct DecodedSignal {
  const DbcSignal* signal = nullptr;
  int64_t raw = 0;     ///< sign-extended when the signal is signed; the bit pattern for floats
  double value = 0.0;  ///< physical value (raw * factor + offset)
  /// The VAL_ text of the raw value, or empty.
  std::string_view label() const;
};

/// A physical value to encode into a signal.
struct SignalValue {
  std::string_view name;
  double value = 0.0;
};

class DbcDatabase {
 public:
  /// Reads a DBC file. Throws std::runtime_error "path:line: key: message".
  static DbcDatabase load(const std::string& path);
  /// Parses DBC text; errors name `name_for_errors` as the file.
  static DbcDatabase parse(std::string_view text, const std::string& name_for_errors);

  const std::string& version() const { return version_; }
  const std::vector<std::string>& nodes() const { return nodes_; }
  const std::vector<DbcMessage>& messages() const { return messages_; }

  /// The message with this identifier, or nullptr (never Vector's
  /// VECTOR__INDEPENDENT_SIG_MSG, which is listed in messages() but not sent).
  const DbcMessage* find(uint32_t id, bool extended) const;
  /// The message called `name`, or nullptr.
  const DbcMessage* find(std::string_view name) const;

  /// Reads the signals of `message` from `data`. A multiplexed signal is
  /// returned only when the multiplexer carries its value; a signal that does
  /// not lie inside `data` (short frame) is left out. Does not throw, but
  /// allocates the result: not for the cyclic path.
  std::vector<DecodedSignal> decode(const DbcMessage& message, std::span<const uint8_t> data) const;

  /// Writes physical values into a zeroed frame of message.dlc bytes; signals
  /// not named stay raw 0. The caller names the multiplexer value that fits
  /// the multiplexed signals it gives. Throws std::invalid_argument for an
  /// unknown signal name and std::out_of_range for a value that does not fit
  /// the signal's bits or a signal that lies beyond message.dlc bytes.
  std::vector<uint8_t> encode(const DbcMessage& message, std::span<const SignalValue> values) const;

 private:
  std::string version_;
  std::vector<std::string> nodes_;
  std::vector<DbcMessage> messages_;
};

/// Raw bits of a signal from a frame (sign-extended if signed). The signal
/// must lie inside `data` (see signal_fits). Safe in the cyclic path.
int64_t extract_raw(const DbcSignal& signal, std::span<const uint8_t> data);
/// Writes raw bits of a signal into a frame. Safe in the cyclic path.
void insert_raw(const DbcSignal& signal, uint64_t raw, std::span<uint8_t> data);
/// Whether every bit of the signal lies inside a frame of `size_bytes`.
bool signal_fits(const DbcSignal& signal, std::size_t size_bytes);
/// Physical value of a raw value (handles IEEE float signals).
double physical_value(const DbcSignal& signal, int64_t raw);

}  // namespace rise::firmware_protocol
