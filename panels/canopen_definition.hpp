#pragma once

// The `protocol: canopen` parts of a panel definition, read for
// panel_definition.cpp: the source's EDS, node id and SYNC period, a
// control's object (by ParameterName or index:subindex, mapped into a
// TPDO) and a feedback output's object (mapped into an RPDO). Every
// mistake throws "file:line: key: what" through the YamlReader.

#include <yaml-cpp/yaml.h>

#include <string>

#include "panels/panel_definition.hpp"
#include "panels/yaml_reader.hpp"

namespace rise::panels {

/// The keys only a canopen source has.
inline constexpr const char* kCanopenSourceKeys[] = {"eds", "sync_ms"};

/// Reads `eds:` (relative to the definition `file`) for the node `s.node`
/// (1..127, required), `sync_ms:`, and the heartbeat consumer time
/// (timeout_ms, given or 1.5 × the EDS's heartbeat time). Call once
/// s.protocol is canopen.
void parse_canopen_source(const YamlReader& ctx, const YAML::Node& node, const std::string& where,
                          const std::string& file, SourceDefinition& s);

/// A canopen source's control: `signal:` names a TPDO-mapped object; an
/// axis' range from the YAML or the object's LowLimit/HighLimit.
void parse_canopen_binding(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                           const std::string& where, ControlDefinition& c);

/// A canopen source's LED or display: `signal:` names an RPDO-mapped object
/// (an LED: any integer object, written 1 / 0; a display: an integer object).
void parse_canopen_output(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                          const std::string& where, const firmware_protocol::DbcMessage*& message,
                          const firmware_protocol::DbcSignal*& signal);

}  // namespace rise::panels
