#pragma once

// Input faults: what a worn stick, a broken wire or a flaky connector does
// to one control, applied by the PanelMapper between decode and the
// transforms/safety rules (the console's firmware reported the value; the
// fault changes what the daemon believes it read). Deterministic: a fault's
// randomness is a pure function of its seed and the time since it started,
// so the same fault at the same times gives the same values.
//
// | kind          | axis                              | button          | switch           |
// |---------------|-----------------------------------|-----------------|------------------|
// | stuck_at      | reads `value` (-1..1)             | pressed = value≠0 | position `value` |
// | offset        | + `value`, clamped to -1..1       | —               | —                |
// | drift         | + `rate`·t (per second), clamped  | —               | —                |
// | noise         | + N(0, `value`) per 1 ms, clamped | —               | —                |
// | out_of_range  | reads `value` (default 1.5): refused as out of range → safe, failsafe | — | an unknown position → failsafe |
// | intermittent  | lost in each `rate`-second slot (default 0.1) with probability `value` (default 0.5) | same | same |
// | disconnect    | lost: safe value, panel failsafe "<control>: disconnected (fault)" | same | same |

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace rise::hil {

enum class InputFaultKind { StuckAt, Offset, Drift, Noise, OutOfRange, Intermittent, Disconnect };
/// snake_case name ("stuck_at", ...).
const char* to_string(InputFaultKind kind);
std::optional<InputFaultKind> parse_input_fault_kind(std::string_view name);

struct InputFault {
  std::string id;           ///< the instance's name (clear names it)
  InputFaultKind kind = InputFaultKind::StuckAt;
  std::size_t control = 0;  ///< index into PanelDefinition::controls
  double value = 0.0;       ///< see the table above
  double rate = 0.0;
  uint64_t seed = 0;
  int64_t start_us = 0;     ///< monotonic time it takes effect
  int64_t end_us = 0;       ///< monotonic time it clears by itself; 0 = until cleared

  bool active(int64_t now_us) const { return now_us >= start_us && (end_us == 0 || now_us < end_us); }
};

/// What the faults of one control did to its value.
enum class FaultEffect { None, Changed, Lost, OutOfRange };

/// Applies the active faults of control `control` at now_us, in injection
/// order, to an axis value (-1..1, before shaping). No throw, no allocation.
FaultEffect apply_axis_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us, float& unit);
/// The same for a button's raw state and a switch's raw position.
FaultEffect apply_button_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us,
                                bool& pressed);
FaultEffect apply_switch_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us,
                                uint8_t& position);

/// A uniform number in [0, 1) from (seed, index) — splitmix64, so every
/// layer's seeded faults draw the same way.
double seeded_uniform(uint64_t seed, uint64_t index);
/// A standard normal number from (seed, index) (Box–Muller on two uniforms).
double seeded_normal(uint64_t seed, uint64_t index);

}  // namespace rise::hil
