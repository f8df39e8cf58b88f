#include "hil/app/verify_command.hpp"

#include <chrono>
#include <cstdio>

#include "hil/panel_state_message.hpp"
#include "hil/replay_verify.hpp"
#include "msgs/channels.hpp"
#include "panels/data_path.hpp"

namespace rise::hil {

int verify_command(const VerifyOptions& o, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  VerifyReport report;
  PanelStateLog golden;
  std::string golden_file = o.golden;
  try {
    const panels::PanelDefinition definition = panels::load_panel_definition(panels::find_data_file(o.panel));
    std::vector<Capture> captures;
    if (!o.record_dir.empty()) {
      captures = captures_in(definition, o.record_dir);
      if (golden_file.empty()) golden_file = o.record_dir + "/panel_state.lcmlog";
    }
    for (const auto& c : o.captures) captures.push_back(capture_for(definition, c));
    if (captures.empty()) throw std::invalid_argument("no capture: give --capture FILE or --record-dir DIR");
    if (golden_file.empty()) throw std::invalid_argument("no golden: give --golden FILE or --record-dir DIR");
    golden = read_panel_state_log(golden_file, o.id.empty() ? "" : rise::msgs::panel_state_channel(o.id));
    VerifySettings settings;
    settings.axis_tolerance = static_cast<float>(o.axis_tolerance);
    settings.time_tolerance_us = static_cast<int64_t>(o.time_tolerance_ms * 1000.0);
    report = verify_replay(definition, std::move(captures), golden.messages, settings);
  } catch (const std::exception& e) {
    err << "rise-hild verify: " << e.what() << "\n";
    return 2;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char summary[256];
  std::snprintf(summary, sizeof summary, "%zu of %zu PanelState messages on %s matched (%zu only off their utime, within the time "
                "tolerance); %lld capture records replayed in %.3f s",
                report.messages, golden.messages.size(), golden.channel.c_str(), report.off_time,
                static_cast<long long>(report.records), seconds);
  if (report.passed()) {
    out << "pass: " << summary << "\n";
    return 0;
  }
  out << "FAIL: first difference at " << describe(*report.difference) << "\n" << summary << "\n";
  return 1;
}

}  // namespace rise::hil
