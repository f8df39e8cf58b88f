#pragma once

// SDL2's game controller database (SDL_GameControllerDB's gamecontrollerdb.txt,
// SDL 2.0.16+ format): one mapping a line,
//
//   GUID,NAME,TARGET:INPUT,...,platform:Linux,
//
// GUID: 32 hex digits (or "xinput", SDL's Windows XInput fallback), the 16 bytes of SDL_JoystickGUID. On Linux SDL2 builds
// it from the evdev device's input_id (SDL_CreateJoystickGUID in
// src/joystick/SDL_joystick.c, 2.26): eight little-endian 16-bit words
// bus, crc16(name), vendor, 0, product, 0, version, driver; the database
// writes 0 for the CRC (any name matches) and the driver word.
// TARGET: a button (a, b, x, y, back, guide, start, leftstick, rightstick,
// leftshoulder, rightshoulder, dpup, dpdown, dpleft, dpright, misc1..6,
// paddle1..4, touchpad) or an axis (leftx, lefty, rightx, righty,
// lefttrigger, righttrigger), with +/- for half of an axis target. INPUT: bN
// (button N), aN (axis N; +aN / -aN its half, aN~ inverted), hN.M (hat N,
// direction mask M: 1 up, 2 right, 4 down, 8 left), N counted as SDL's
// joystick driver enumerates the device (hil/io/evdev_signals.hpp).
// A malformed line is counted and skipped with its file:line; nothing here throws for the
// content of a line.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rise::firmware_protocol {

/// SDL_JoystickGUID: 16 bytes.
using SdlGuid = std::array<uint8_t, 16>;

/// The GUID SDL2 gives a Linux evdev device (CRC and driver words 0, as the
/// database writes them).
SdlGuid sdl_linux_guid(uint16_t bus, uint16_t vendor, uint16_t product, uint16_t version);
/// 32 lowercase hex digits, as the database writes it.
std::string to_string(const SdlGuid& guid);
/// From 32 hex digits; nullopt when malformed.
std::optional<SdlGuid> parse_sdl_guid(std::string_view text);

/// One end of a mapping element: what SDL's joystick reports.
struct SdlInput {
  enum class Kind : uint8_t { Button, Axis, Hat } kind = Kind::Button;
  int index = 0;        ///< button, axis or hat number
  int hat_mask = 0;     ///< hats: 1 up, 2 right, 4 down, 8 left
  int half = 0;         ///< axes: 0 whole, +1 upper half (+aN), -1 lower half (-aN)
  bool invert = false;  ///< axes: aN~
};

/// TARGET:INPUT. `target` is the SDL name (leftx, a, dpup...).
struct SdlBinding {
  std::string target;
  int target_half = 0;  ///< +leftx / -leftx: the input drives half of the target axis
  SdlInput input;
};

struct SdlMapping {
  SdlGuid guid{};
  std::string name;
  std::string platform;  ///< "" when the line names none
  std::vector<SdlBinding> bindings;
  int line = 0;
};

/// Whether `name` is one of SDL2's game controller axes / buttons.
bool is_sdl_axis(std::string_view name);
bool is_sdl_button(std::string_view name);
/// "a, b, x, ..." every SDL name, axes first, for messages.
std::string sdl_names();

/// Parses one mapping line (without its newline). nullopt, with `error`
/// set, when it is malformed. No throw.
std::optional<SdlMapping> parse_sdl_mapping(std::string_view line, std::string* error = nullptr);

class SdlControllerDb {
 public:
  /// Reads `path`; comments (#) and blank lines skipped, malformed lines
  /// counted in problems(). Throws std::runtime_error "PATH: cannot read"
  /// when the file cannot be read.
  static SdlControllerDb load(const std::string& path);
  /// Same, from text; `file` is used in problems().
  static SdlControllerDb parse(std::string_view text, const std::string& file);

  const std::vector<SdlMapping>& mappings() const { return mappings_; }
  /// "FILE:LINE: what" for every malformed line.
  const std::vector<std::string>& problems() const { return problems_; }
  const std::string& file() const { return file_; }
  std::size_t count_platform(std::string_view platform) const;

  /// The Linux mapping of an evdev device, as SDL2 looks it up: the exact
  /// GUID first, then one whose version word is 0 or differs (SDL's second
  /// pass, SDL_PrivateGetControllerMappingForGUID). Lines for other
  /// platforms are never taken; the last of equal lines wins, as when SDL
  /// adds them in order. nullptr when there is none.
  const SdlMapping* find_linux(uint16_t bus, uint16_t vendor, uint16_t product, uint16_t version) const;

 private:
  std::string file_;
  std::vector<SdlMapping> mappings_;
  std::vector<std::string> problems_;
};

}  // namespace rise::firmware_protocol
