#pragma once

// The web server's virtual panels by trainee id: the pages' requests update
// them, their own thread publishes every panel's PanelState at the console
// definition's rate (so a page that stops sending is failsafe within one
// period after its timeout), and the LCM thread hands them the fault
// commands meant for them. Thread-safe.

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "instructor/virtual_panel.hpp"
#include "msgs/command_auth.hpp"
#include "panels/panel_definition.hpp"
#include "msgs/publisher_session.hpp"
#include "rise_msgs/FaultCommand.hpp"

namespace lcm {
class LCM;
}

namespace rise::instructor {

/// Why a page's update was not taken.
struct VirtualRefusal {
  /// Another process publishes the trainee's panel_state: a virtual panel
  /// there would mix with it (else: the controls were refused).
  bool channel_taken = false;
  /// The update came from a page that has already said it closed (a request
  /// it sent before closing, overtaken by its close): not taken.
  bool page_closed = false;
  std::string message;
};

class VirtualPanels {
 public:
  /// Each panel copies `console` (checked here: one source) and fails safe
  /// `timeout_ms` after its page's last update. Fault commands are checked
  /// against `key` (none: every one is rejected); `publishers` tells who
  /// else publishes a trainee's panel_state. Throws std::runtime_error for
  /// a console definition a virtual panel cannot copy.
  VirtualPanels(panels::PanelDefinition console, uint32_t timeout_ms, const std::optional<msgs::InstructorKey>& key,
                lcm::LCM& lcm, const msgs::PublisherWatch& publishers);
  ~VirtualPanels();
  VirtualPanels(const VirtualPanels&) = delete;
  VirtualPanels& operator=(const VirtualPanels&) = delete;

  /// Starts publishing on rise/<id>/panel_state.
  void start();
  /// Stops publishing; publishes nothing more.
  void stop();

  /// Takes trainee `id`'s page's controls (from `client`; `page` names the
  /// page load that sent them, empty: unnamed), opening its panel on the
  /// first update unless another process publishes there.
  std::optional<VirtualRefusal> update(const std::string& id, const VirtualControls& controls,
                                       const std::string& client, const std::string& page = {});
  /// The page of `id` closed: its panel fails safe, and updates still on
  /// their way from that `page` (if named) are refused, so a request the page
  /// sent before closing cannot revive the panel after it. False if there is
  /// no panel.
  bool disconnect(const std::string& id, const std::string& page = {});
  /// A FaultCommand heard on rise/<trainee>/fault_command. A virtual panel
  /// is a receiver like rise-hild: it takes signed input faults and reports
  /// the rest; commands for other trainees are not ours.
  void on_fault_command(const std::string& trainee, const rise_msgs::FaultCommand& command);

  bool has(const std::string& id) const;
  std::set<std::string> ids() const;

 private:
  void publish_loop();

  panels::PanelDefinition console_;
  uint32_t timeout_ms_;
  lcm::LCM& lcm_;
  const msgs::PublisherWatch& publishers_;
  // Checks the fault commands meant for these panels (they come back over
  // LCM like any receiver's; only the LCM thread uses it).
  std::unique_ptr<msgs::CommandVerifier> verifier_;
  mutable std::mutex mutex_;
  std::map<std::string, std::unique_ptr<VirtualPanel>> panels_;
  // By trainee id: the page load that last closed there.
  std::map<std::string, std::string> closed_page_;
  std::atomic<bool> publishing_{false};
  std::thread thread_;
};

}  // namespace rise::instructor
