#include "hil/io/can_error.hpp"

#include <linux/can.h>
#include <linux/can/error.h>

#include <utility>

namespace rise::hil::io {

std::string_view to_string(CanBusState state) {
  switch (state) {
    case CanBusState::Active: return "error-active";
    case CanBusState::Warning: return "error-warning";
    case CanBusState::Passive: return "error-passive";
    case CanBusState::BusOff: return "bus-off";
  }
  return "?";
}

CanErrorReport describe_can_error(const CanFrame& frame) {
  CanErrorReport r;
  if (!frame.error) return r;
  r.classes = frame.id & CAN_ERR_MASK;
  const auto byte = [&](unsigned i) -> uint8_t { return i < frame.len ? frame.data[i] : 0; };
  // The most severe news wins: bus-off over a controller state, a restart
  // (which follows bus-off) over both.
  if ((r.classes & CAN_ERR_CRTL) != 0) {
    const uint8_t c = byte(1);
    if ((c & CAN_ERR_CRTL_ACTIVE) != 0) r.state = CanBusState::Active;
    if ((c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0) r.state = CanBusState::Warning;
    if ((c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) r.state = CanBusState::Passive;
  }
  if ((r.classes & CAN_ERR_BUSOFF) != 0) r.state = CanBusState::BusOff;
  if ((r.classes & CAN_ERR_RESTARTED) != 0) r.state = CanBusState::Active;
#ifdef CAN_ERR_CNT
  // Linux ≥ 5.19 marks frames whose data[6..7] carry the counters.
  if ((r.classes & CAN_ERR_CNT) != 0) {
    r.tx_errors = byte(6);
    r.rx_errors = byte(7);
  }
#endif
  return r;
}

std::string can_error_text(const CanFrame& frame) {
  const CanErrorReport r = describe_can_error(frame);
  std::string out;
  const auto add = [&](const char* text) {
    if (!out.empty()) out += ", ";
    out += text;
  };
  if (r.classes & CAN_ERR_TX_TIMEOUT) add("tx-timeout");
  if (r.classes & CAN_ERR_LOSTARB) add("lost-arbitration");
  if (r.classes & CAN_ERR_CRTL) {
    std::string c;
    const uint8_t b = frame.len > 1 ? frame.data[1] : 0;
    const std::pair<uint8_t, const char*> bits[] = {
        {CAN_ERR_CRTL_RX_OVERFLOW, "rx-overflow"}, {CAN_ERR_CRTL_TX_OVERFLOW, "tx-overflow"},
        {CAN_ERR_CRTL_RX_WARNING, "rx-error-warning"}, {CAN_ERR_CRTL_TX_WARNING, "tx-error-warning"},
        {CAN_ERR_CRTL_RX_PASSIVE, "rx-error-passive"}, {CAN_ERR_CRTL_TX_PASSIVE, "tx-error-passive"},
        {CAN_ERR_CRTL_ACTIVE, "back-to-error-active"}};
    for (const auto& [bit, name] : bits)
      if (b & bit) c += (c.empty() ? "" : ",") + std::string(name);
    add(("controller-problem{" + c + "}").c_str());
  }
  if (r.classes & CAN_ERR_PROT) add("protocol-violation");
  if (r.classes & CAN_ERR_TRX) add("transceiver-status");
  if (r.classes & CAN_ERR_ACK) add("no-acknowledgement-on-tx");
  if (r.classes & CAN_ERR_BUSOFF) add("bus-off");
  if (r.classes & CAN_ERR_BUSERROR) add("bus-error");
  if (r.classes & CAN_ERR_RESTARTED) add("restarted-after-bus-off");
  if (r.tx_errors || r.rx_errors)
    add(("error-counter-tx-rx{{" + std::to_string(r.tx_errors.value_or(0)) + "}{" +
         std::to_string(r.rx_errors.value_or(0)) + "}}")
            .c_str());
  return out.empty() ? "error frame" : out;
}

}  // namespace rise::hil::io
