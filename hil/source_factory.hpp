#pragma once

// A panel's source transports from their URLs, as rise-hild opens them:
// each URL checked against its source's protocol, a Modbus unit the URL
// does not name taken from the definition, wire faults
// (hil/io/wire_fault.hpp) right around each CAN bus and Modbus link and,
// when recording, the recorder (session_recorder.hpp) above them: a
// recording holds what the daemon read, so `verify` replays a faulted
// session as it was. Nothing here is for the cyclic path.

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "hil/io/wire_fault.hpp"
#include "hil/session_recorder.hpp"
#include "hil/source_transport.hpp"
#include "panels/panel_definition.hpp"

namespace rise::hil {

/// Source `source`'s transport from `url`, adapted for the bridge
/// (CanSource, ModbusSource, HidSource), without wire faults or recorder.
/// A hid source's URL "-" is its definition's `device:`. Throws
/// std::runtime_error naming the source when the URL is not one of its
/// protocol's, and what the io openers throw (std::invalid_argument for a
/// malformed URL, std::runtime_error for a replay file that cannot be read
/// or a socketcan interface that is not there).
std::unique_ptr<SourceTransport> open_source(const panels::PanelDefinition& definition, std::size_t source,
                                             const std::string& url);

/// The sources of a panel, opened and decorated as rise-hild runs them.
struct PanelSources {
  std::vector<std::unique_ptr<SourceTransport>> transports;  ///< one per source, in order (for the Bridge)
  std::vector<std::string> urls;          ///< each source's URL; a hid source's "-" replaced by its device:
  std::vector<io::WireFaultSet*> wires;   ///< each source's wire faults (FaultInjector); null for a hid source
  std::unique_ptr<SessionRecorder> recorder;  ///< set when recording
  std::vector<std::string> notes;         ///< lines for the log: how each hid source is reached
};

/// Every source of `definition` from its URL (one per source, in order):
/// open_source(), wire faults and, when `record_dir` is not empty, a
/// SessionRecorder into it that records each. Throws std::runtime_error
/// for a count of URLs that is not the panel's, and what open_source() and
/// the SessionRecorder throw.
PanelSources open_panel_sources(const panels::PanelDefinition& definition, std::vector<std::string> urls,
                                const std::string& record_dir);

}  // namespace rise::hil
