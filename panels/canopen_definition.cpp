#include "panels/canopen_definition.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "firmware_protocol/canopen.hpp"
#include "firmware_protocol/canopen_eds.hpp"

namespace rise::panels {
namespace {

namespace co = rise::firmware_protocol::canopen;

// The object `signal:` names and its place in a PDO of the direction asked.
co::PdoSignal mapped_object(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                            const std::string& where, bool transmit) {
  const auto text = ctx.require<std::string>(node, "signal", where);
  const co::OdLookup found = source.eds->lookup(text);
  if (!found.entry) ctx.fail(node["signal"], where + ".signal", found.error);
  const co::PdoSignal pdo = source.eds->pdo_signal(*found.entry, transmit);
  if (!pdo.signal) {
    const bool other = source.eds->pdo_signal(*found.entry, !transmit).signal != nullptr;
    ctx.fail(node["signal"], where + ".signal",
             co::od_address(found.entry->index, found.entry->subindex) + " '" + found.entry->name + "' is not in a " +
                 (transmit ? "TPDO" : "RPDO") + " of " + source.eds_file +
                 (other ? std::string(" (an ") + (transmit ? "RPDO" : "TPDO") + " maps it: " +
                              (transmit ? "the console reads it" : "the console sends it") + ")"
                        : std::string(" (a control reads what the node sends in a TPDO, feedback writes an RPDO)")));
  }
  return pdo;
}

}  // namespace

void parse_canopen_source(const YamlReader& ctx, const YAML::Node& node, const std::string& where,
                          const std::string& file, SourceDefinition& s) {
  if (!node["node"]) ctx.fail(node, where + ".node", "missing (the CANopen node id, 1..127)");
  if (!co::is_node_id(s.node)) ctx.fail(node["node"], where + ".node", "a CANopen node id is 1..127");
  for (const char* k : {"max_counter_delta", "recovery_frames"})
    if (node[k]) ctx.fail(node[k], where + "." + k, "not used by protocol canopen (no alive counter or CRC)");
  s.eds_file = beside(file, ctx.require<std::string>(node, "eds", where));
  try {
    s.eds = std::make_shared<const co::EdsDevice>(co::EdsDevice::load(s.eds_file, s.node));
  } catch (const std::exception& e) {
    ctx.fail(node["eds"], where + ".eds", e.what());
  }
  // Heartbeat consumer time: CiA 301 §7.2.8.3.2.2 wants it longer than the
  // producer's; 1.5 periods tolerate one late heartbeat, not a lost one.
  if (!node["timeout_ms"]) s.timeout_ms = (3u * s.eds->heartbeat_ms() + 1u) / 2u;
  else if (s.timeout_ms <= s.eds->heartbeat_ms())
    ctx.fail(node["timeout_ms"], where + ".timeout_ms",
             "the heartbeat consumer time must exceed the node's producer heartbeat time (" +
                 std::to_string(s.eds->heartbeat_ms()) + " ms, 0x1017 in " + s.eds_file + ")");
  const double sync_ms = ctx.get<double>(node, "sync_ms", where, s.eds->sync_period_us() / 1000.0);
  if (!(sync_ms == 0.0 || (sync_ms >= 1.0 && sync_ms <= 10000.0)))
    ctx.fail(node["sync_ms"], where + ".sync_ms", "must be 1..10000 (or 0: no SYNC)");
  s.sync_period_us = static_cast<uint32_t>(std::lround(sync_ms * 1000.0));
  if (s.eds->has_sync_tpdo() && s.sync_period_us == 0)
    ctx.fail(node["sync_ms"] ? node["sync_ms"] : node["eds"], where + (node["sync_ms"] ? ".sync_ms" : ".eds"),
             "a TPDO of " + s.eds_file + " is synchronous but no SYNC period is given (0x1006 or sync_ms)");
}

void parse_canopen_binding(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                           const std::string& where, ControlDefinition& c) {
  if (node["bits"]) ctx.fail(node["bits"], where + ".bits", "not for a canopen source");
  const co::PdoSignal pdo = mapped_object(ctx, source, node, where, true);
  c.dbc_message = pdo.message;
  c.dbc_signal = pdo.signal;
  if (c.kind != ControlKind::Axis) {
    if (node["range"]) ctx.fail(node["range"], where + ".range", "only for an axis");
    return;
  }
  if (const YAML::Node range = node["range"]) {
    if (!range.IsSequence() || range.size() != 2) ctx.fail(range, where + ".range", "expected [min, max]");
    c.range_min = ctx.as<double>(range[0], where + ".range");
    c.range_max = ctx.as<double>(range[1], where + ".range");
  } else if (pdo.entry->low_limit && pdo.entry->high_limit) {
    c.range_min = *pdo.entry->low_limit;
    c.range_max = *pdo.entry->high_limit;
  }
  if (!(c.range_max > c.range_min))
    ctx.fail(node["range"] ? node["range"] : node, where + ".range",
             "needs min < max (the EDS gives no LowLimit/HighLimit for " +
                 co::od_address(pdo.entry->index, pdo.entry->subindex) + ")");
}

void parse_canopen_output(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                          const std::string& where, const firmware_protocol::DbcMessage*& message,
                          const firmware_protocol::DbcSignal*& signal) {
  const co::PdoSignal pdo = mapped_object(ctx, source, node, where, false);
  if (pdo.signal->value_type != firmware_protocol::SignalValueType::Integer)
    ctx.fail(node["signal"], where + ".signal", "a REAL object cannot be written by feedback (an integer object)");
  message = pdo.message;
  signal = pdo.signal;
}

}  // namespace rise::panels
