#pragma once

// A console described as data: its device sources, its named controls with
// the signal each is bound to and the value it takes when unsafe, and its
// feedback outputs. Loaded from YAML (panels/definitions/rise_console.yaml).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "panels/modbus_point.hpp"

namespace rise::firmware_protocol {
class DbcDatabase;
class SdlControllerDb;
struct DbcMessage;
struct DbcSignal;
namespace canopen {
class EdsDevice;
}
}  // namespace rise::firmware_protocol

namespace rise::panels {

enum class ControlKind { Axis, Button, Switch };

/// What the bridge does with a control beyond passing it on.
enum class ControlRole {
  None,
  Deadman,  ///< released → every motion control at its safe value
  Estop,    ///< pressed → panel failsafe
};

/// Where a control's raw value comes from: a source and one of its signals.
/// For protocols rise-can-v1 and rise-modbus-v1 the signals are axis.0..5,
/// button.0..31, switch.0..5.
struct SignalRef {
  enum class Kind { Axis, Button, Switch } kind = Kind::Axis;
  uint8_t index = 0;
};

/// How a button's raw state becomes the control's value.
enum class ButtonBehaviour {
  Direct,     ///< pressed while held
  Toggle,     ///< each press flips the value (latching function on a momentary button)
  LongPress,  ///< pressed once held for long_press_ms
  Edge,       ///< pressed for pulse_ms after each press
};

/// How a switch wired to several inputs reads its position.
enum class BitsEncoding { Binary, OneHot };

struct ControlDefinition {
  std::string name;
  ControlKind kind = ControlKind::Axis;
  ControlRole role = ControlRole::None;
  std::size_t source = 0;     ///< index into PanelDefinition::sources
  SignalRef signal;
  bool motion = false;        ///< zeroed (safe value) while the dead-man is released
  // Axes: value = clamp(scale * deadband(invert ? -raw : raw)); the deadband
  // is rescaled so the output stays continuous (|x| ≤ d → 0, else (|x|-d)/(1-d)).
  float deadband = 0.0f;
  bool invert = false;
  float scale = 1.0f;
  float expo = 0.0f;        ///< 0 linear .. 1 cubic (after the deadband, before the scale)
  float lowpass_ms = 0.0f;  ///< first-order low-pass time constant, 0 = none
  // Buttons.
  ButtonBehaviour behaviour = ButtonBehaviour::Direct;
  uint32_t debounce_ms = 0;
  uint32_t long_press_ms = 800;
  uint32_t pulse_ms = 100;
  // Switches read from several button inputs instead of a switch signal
  // (e.g. a 3-position rotary switch on two inputs): `bits: [button.4, button.5]`.
  std::vector<uint8_t> bits;
  BitsEncoding encoding = BitsEncoding::Binary;
  // Safe value: axes use safe_axis, buttons safe_button, switches safe_switch.
  float safe_axis = 0.0f;
  bool safe_button = false;
  uint8_t safe_switch = 0;
  std::vector<std::string> positions;  ///< switch position labels
  // Controls of a "dbc" source: the signal (pointers into the source's
  // shared database) and, for axes, the physical range that maps to -1..1.
  const firmware_protocol::DbcMessage* dbc_message = nullptr;
  const firmware_protocol::DbcSignal* dbc_signal = nullptr;
  double range_min = 0.0;
  double range_max = 0.0;
  // Controls of a "hid" source: a signal name of the device's report
  // descriptor (firmware_protocol::hid_signals: x, hat_switch, button_3...)
  // or, through evdev://, of the kernel's codes (abs_x, btn_south, hat0_up)
  // and SDL's (sdl.leftx; hil/io/evdev_signals.hpp). Known only once the
  // device is open: the bridge checks it then (an sdl.NAME at load).
  std::string hid_signal;
  // Controls of a "modbus" source: the point read (axes: range_min..max of
  // its number → -1..1; buttons: pressed when ≠ 0; switches: the number is
  // the position) and how a whole register reads as a number.
  std::optional<ModbusPoint> modbus_point;
  ModbusValueType modbus_type = ModbusValueType::UInt16;
  int line = 0;                        ///< line in the definition file (for messages)
};

struct SourceDefinition {
  std::string name;
  std::string protocol;           ///< "rise-can-v1", "rise-modbus-v1", "modbus", "dbc", "j1939", "hid" or "canopen"
  uint8_t node = 0;               ///< console node id on the bus: rise-can-v1 0..15, canopen 1..127
  double poll_hz = 50.0;          ///< Modbus: input polls per second
  uint8_t unit = 1;               ///< Modbus: slave / unit id (1..247)
  uint32_t timeout_ms = 50;       ///< stale when no valid frame within this
  uint32_t recovery_frames = 3;   ///< valid frames in a row to leave a failed check
  uint8_t max_counter_delta = 1;  ///< alive counter jump tolerated (1 = none lost)
  /// protocol "dbc": any CAN device a DBC file describes; controls bind
  /// MESSAGE.SIGNAL names. The database is shared by copies of the definition.
  std::string dbc_file;
  std::shared_ptr<const firmware_protocol::DbcDatabase> dbc;
  /// protocol "j1939": an SAE J1939 console whose J1939 DBC (`dbc:`) names
  /// its PGNs' signals. The bridge claims `address` with NAME `j1939_name`
  /// (hil/j1939_source.hpp) and takes the console's messages from the
  /// address its NAME `console_name` claims (followed when it moves), or
  /// from the fixed `console_address` while no NAME is given or heard.
  uint8_t j1939_address = 0x80;
  uint64_t j1939_name = 0x8000000000001939ull;  ///< arbitrary address capable, identity 0x1939
  std::optional<uint64_t> console_name;
  uint8_t console_address = 254;  ///< 254 = none: only the console's NAME finds it
  /// protocol "hid": a USB HID device (joystick, gamepad); controls bind the
  /// names of its report descriptor's signals. `device` is its hid:// URL
  /// (optional here; the daemon's --source URL wins). timeout_ms defaults to
  /// 1000 (many gamepads send reports only on change); 0 = never stale, only
  /// a disconnect makes the source unsafe.
  std::string device;
  /// A hid source read through evdev:// (a device the kernel drives) may
  /// name its controls as SDL2's game controller API does: `mapping: sdl`
  /// with `sdl_db:` SDL_GameControllerDB's gamecontrollerdb.txt (relative to
  /// the definition file); controls then bind sdl.leftx, sdl.a, sdl.dpup...
  /// (firmware_protocol/sdl_mapping.hpp) from the line of the device's GUID.
  std::string mapping;  ///< "" or "sdl"
  std::string sdl_db_file;
  std::shared_ptr<const firmware_protocol::SdlControllerDb> sdl_db;
  /// protocol "canopen": a CANopen node (CiA 301) its EDS/DCF describes
  /// (`eds:`, beside the definition; `node:` 1..127). Controls bind objects
  /// its TPDOs map (by ParameterName or index:subindex), read as the dbc
  /// path reads signals (`eds->tpdo_messages()`); feedback writes objects
  /// its RPDOs map. timeout_ms is the heartbeat consumer time (default 1.5
  /// times the EDS's producer heartbeat time, 0x1017); `sync_period_us` the
  /// SYNC the bridge produces when a TPDO is synchronous (the EDS's 0x1006
  /// unless `sync_ms:` gives it), 0 = none.
  std::string eds_file;
  std::shared_ptr<const firmware_protocol::canopen::EdsDevice> eds;
  uint32_t sync_period_us = 0;
  bool is_canopen() const { return protocol == "canopen"; }
  bool is_hid() const { return protocol == "hid"; }
  /// On a Modbus link: our register map (rise-modbus-v1) or any device's (modbus).
  bool is_modbus() const { return protocol == "rise-modbus-v1" || protocol == "modbus"; }
  /// protocol "modbus": a third-party device whose controls bind its points
  /// (panels/modbus_point.hpp); no alive counter or CRC of ours: stale when
  /// no poll was answered within timeout_ms.
  bool is_generic_modbus() const { return protocol == "modbus"; }
  /// Controls bind MESSAGE.SIGNAL of a DBC file: a plain CAN device (dbc)
  /// or a J1939 one (j1939, messages matched by PGN and source address).
  bool is_dbc() const { return protocol == "dbc" || is_j1939(); }
  bool is_j1939() const { return protocol == "j1939"; }
};

struct LedDefinition {
  std::string name;
  std::size_t source = 0;
  uint8_t bit = 0;  ///< rise-can-v1 / rise-modbus-v1: bit of the indicators frame
  /// hid sources: the output signal of the device's report descriptor that
  /// lights it (firmware_protocol::hid_signals, e.g. usage_0008_0001 for the
  /// LED page's first usage); known only once the device is open.
  std::string hid_signal;
  /// modbus sources: the coil (or holding register, written 1 / 0) that lights it.
  std::optional<ModbusPoint> modbus_point;
  /// canopen sources: the RPDO-mapped object that lights it (1 / 0).
  const firmware_protocol::DbcMessage* pdo_message = nullptr;
  const firmware_protocol::DbcSignal* pdo_signal = nullptr;
  int line = 0;  ///< line in the definition file (for messages)
};
/// Rumble / force feedback of a hid source: PanelFeedback.rumble (0..1) is
/// written into this output signal of the device's report descriptor (e.g.
/// a vendor motor byte, vendor_ff00_0002), scaled to its logical range.
struct RumbleDefinition {
  std::string name;
  std::size_t source = 0;
  std::string hid_signal;
  int line = 0;  ///< line in the definition file (for messages)
};
struct DisplayDefinition {
  std::string name;
  std::size_t source = 0;
  uint8_t index = 0;
  uint8_t decimals = 0;
  /// modbus sources: the holding register written with the raw value
  /// (value · 10^decimals, saturated to the type's range).
  std::optional<ModbusPoint> modbus_point;
  ModbusValueType modbus_type = ModbusValueType::UInt16;
  /// canopen sources: the RPDO-mapped object written with the raw value
  /// (value · 10^decimals, saturated to the object's type).
  const firmware_protocol::DbcMessage* pdo_message = nullptr;
  const firmware_protocol::DbcSignal* pdo_signal = nullptr;
};

struct PanelDefinition {
  std::string name;
  std::string file;               ///< where it was loaded from
  double publish_hz = 100.0;
  std::vector<SourceDefinition> sources;
  std::vector<ControlDefinition> controls;
  std::vector<LedDefinition> leds;
  std::vector<DisplayDefinition> displays;
  std::vector<RumbleDefinition> rumbles;
  std::optional<std::size_t> buzzer_source;

  /// Index of a control by name, or nullopt.
  std::optional<std::size_t> find_control(const std::string& name) const;
  std::optional<std::size_t> find_source(const std::string& name) const;
  /// Publish period in microseconds.
  int64_t publish_period_us() const { return static_cast<int64_t>(1e6 / publish_hz); }
};

/// Loads a panel definition. Throws std::runtime_error naming file:line and
/// the key for every mistake (unknown key, wrong type, bad range, unknown
/// source or signal, a signal bound twice, duplicate names, motion controls
/// without a dead-man).
PanelDefinition load_panel_definition(const std::string& path);

/// Same, from text; `file` is used in messages.
PanelDefinition parse_panel_definition(const std::string& text, const std::string& file);

/// "axis.1" → SignalRef; nullopt if malformed or out of the protocol's range.
std::optional<SignalRef> parse_signal(const std::string& text);
std::string to_string(const SignalRef& signal);

}  // namespace rise::panels
