#include "firmware_protocol/canopen.hpp"

#include <limits>

namespace rise::firmware_protocol::canopen {

Frame nmt_frame(NmtCommand command, uint8_t node) {
  Frame f;
  f.cob_id = kNmtCobId;
  f.len = 2;
  f.data[0] = static_cast<uint8_t>(command);
  f.data[1] = node;
  return f;
}

Frame sync_frame() {
  Frame f;
  f.cob_id = kSyncCobId;
  return f;
}

Frame heartbeat_frame(uint8_t node, NmtState state) {
  Frame f;
  f.cob_id = kHeartbeatBase + node;
  f.len = 1;
  f.data[0] = static_cast<uint8_t>(state);
  return f;
}

HeartbeatResult read_heartbeat(uint8_t node, uint32_t cob_id, std::span<const uint8_t> data) {
  HeartbeatResult r;
  if (cob_id != kHeartbeatBase + node) return r;
  if (data.size() != 1) {
    r.read = HeartbeatRead::BadLength;
    return r;
  }
  switch (data[0]) {
    case 0x00:
    case 0x04:
    case 0x05:
    case 0x7F:
      r.read = HeartbeatRead::Ok;
      r.state = static_cast<NmtState>(data[0]);
      return r;
    default: r.read = HeartbeatRead::BadState; return r;
  }
}

NmtRequest read_nmt(uint32_t cob_id, std::span<const uint8_t> data) {
  NmtRequest r;
  if (cob_id != kNmtCobId || data.size() != 2 || data[1] > 127) return r;
  switch (data[0]) {
    case 0x01:
    case 0x02:
    case 0x80:
    case 0x81:
    case 0x82:
      r.ok = true;
      r.command = static_cast<NmtCommand>(data[0]);
      r.node = data[1];
      return r;
    default: return r;
  }
}

NmtState next_state(NmtState state, NmtCommand command) {
  switch (command) {
    case NmtCommand::Start: return NmtState::Operational;
    case NmtCommand::Stop: return NmtState::Stopped;
    case NmtCommand::EnterPreOperational: return NmtState::PreOperational;
    case NmtCommand::ResetNode:
    case NmtCommand::ResetCommunication: return NmtState::BootUp;
  }
  return state;
}

std::string_view to_string(NmtState state) {
  switch (state) {
    case NmtState::BootUp: return "boot-up";
    case NmtState::Stopped: return "stopped";
    case NmtState::Operational: return "operational";
    case NmtState::PreOperational: return "pre-operational";
  }
  return "unknown";
}

uint32_t default_tpdo_cob_id(unsigned n, uint8_t node) {
  return n >= 1 && n <= 4 ? kTpdoBase[n - 1] + node : 0;
}

uint32_t default_rpdo_cob_id(unsigned n, uint8_t node) {
  return n >= 1 && n <= 4 ? kRpdoBase[n - 1] + node : 0;
}

NmtMaster::NmtMaster(uint8_t node, int64_t heartbeat_timeout_us, int64_t sync_period_us)
    : node_(node), heartbeat_timeout_us_(heartbeat_timeout_us), sync_period_us_(sync_period_us) {}

void NmtMaster::opened(int64_t now_us) {
  pending_ = NmtCommand::ResetCommunication;
  state_ = NmtState::BootUp;
  last_heartbeat_us_ = 0;
  next_sync_us_ = now_us;
}

void NmtMaster::on_frame(uint32_t cob_id, std::span<const uint8_t> data, int64_t now_us) {
  const HeartbeatResult hb = read_heartbeat(node_, cob_id, data);
  if (hb.read != HeartbeatRead::Ok) return;
  const bool returned = last_heartbeat_us_ == 0 || now_us - last_heartbeat_us_ > heartbeat_timeout_us_;
  if (hb.state == NmtState::BootUp || (returned && hb.state != NmtState::Operational))
    pending_ = NmtCommand::Start;
  state_ = hb.state;
  last_heartbeat_us_ = now_us;
}

std::optional<Frame> NmtMaster::next(int64_t now_us) {
  if (pending_) {
    const NmtCommand command = *pending_;
    pending_.reset();
    if (command == NmtCommand::Start) ++starts_sent_;
    return nmt_frame(command, node_);
  }
  if (sync_period_us_ <= 0 || now_us < next_sync_us_) return std::nullopt;
  next_sync_us_ += sync_period_us_;
  // Late by more than a period (a stalled thread): no burst of SYNCs.
  if (next_sync_us_ <= now_us) next_sync_us_ = now_us + sync_period_us_;
  ++syncs_sent_;
  return sync_frame();
}

int64_t NmtMaster::next_due_us() const {
  if (pending_) return 0;
  return sync_period_us_ > 0 ? next_sync_us_ : std::numeric_limits<int64_t>::max();
}

}  // namespace rise::firmware_protocol::canopen
