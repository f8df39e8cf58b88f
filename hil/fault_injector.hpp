#pragma once

// The daemon's fault switchboard: takes an instructor's fault (already
// verified, msgs/command_auth.hpp) and applies it where it belongs —
// input faults to the PanelMapper through the Bridge (hil/input_fault.hpp),
// wire faults to the source's decorated transport (hil/io/wire_fault.hpp),
// transport faults to the PanelState publisher (TransportFaults below).
// Faults of the sim's layers (motor_failure, ...) are not the daemon's: it
// refuses them, as rise-sim refuses the daemon's.

#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hil/bridge.hpp"
#include "hil/io/wire_fault.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::hil {

/// One fault as the instructor names it (FaultCommand's fields).
struct FaultSpec {
  std::string id;
  std::string kind;    ///< e.g. "stuck_at", "can_drop", "lcm_loss"
  std::string target;  ///< control (input), source (wire), "panel_state" or "" (transport)
  double value = 0.0;
  double rate = 0.0;
  double duration_s = 0.0;  ///< 0 = until cleared
  uint64_t seed = 0;
};

enum class FaultLayer { Input, Wire, Transport, Physics, Sensor };
/// The layer of a kind name; nullopt for a name no layer knows.
std::optional<FaultLayer> fault_layer(std::string_view kind);

/// LCM faults of the PanelState stream: `lcm_loss` drops a message with
/// probability `value` (seeded), `lcm_latency` holds every message `rate` ms
/// (default 100) before it is published. Thread-safe.
class TransportFaults {
 public:
  struct Fault {
    std::string id;
    bool loss = true;  ///< false: latency
    double value = 0.0;
    double rate = 0.0;
    uint64_t seed = 0;
    int64_t start_us = 0;
    int64_t end_us = 0;
    bool active(int64_t now_us) const { return now_us >= start_us && (end_us == 0 || now_us < end_us); }
  };
  void inject(Fault fault);
  std::size_t clear(const std::string& id, int64_t now_us);
  std::vector<Fault> active(int64_t now_us) const;
  /// Takes one message at now_us; returns those due for publishing now, in
  /// order (none while it is lost or held back).
  std::vector<rise_msgs::PanelState> pass(rise_msgs::PanelState message, int64_t now_us);
  /// Held messages due by now_us (call on every publisher wake-up).
  std::vector<rise_msgs::PanelState> due(int64_t now_us);
  int64_t lost() const;

 private:
  mutable std::mutex mutex_;
  std::vector<Fault> faults_;
  std::deque<std::pair<int64_t, rise_msgs::PanelState>> held_;
  uint64_t messages_ = 0;
  int64_t lost_ = 0;
};

class FaultInjector {
 public:
  /// `wires[i]`: the decorated transport of source i (null: no wire faults
  /// there); `transport`: the publisher's faults (null: none).
  FaultInjector(Bridge& bridge, std::vector<io::WireFaultSet*> wires, TransportFaults* transport);

  /// Applies `spec` from now_us (monotonic, msgs::monotonic_us) for its
  /// duration. Returns "" or why it was refused (unknown kind, target or a
  /// layer that is not the daemon's). Thread-safe.
  std::string inject(const FaultSpec& spec, int64_t now_us);
  /// Clears `id` ("" = every fault of every layer); returns how many.
  std::size_t clear(const std::string& id, int64_t now_us);
  /// Wire and transport faults in effect, "<id>: <kind> <target>" (input
  /// faults are in the Bridge's snapshots).
  std::vector<std::string> active(int64_t now_us) const;

 private:
  Bridge& bridge_;
  std::vector<io::WireFaultSet*> wires_;
  TransportFaults* transport_;
};

}  // namespace rise::hil
