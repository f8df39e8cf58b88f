// libFuzzer target: the EDS/DCF reader (CiA 306) on arbitrary text for an
// arbitrary node id, then what the bridge does with what it read: look up
// each object by name and address, decode and re-encode every PDO's mapped
// objects from frames, and read heartbeats and NMT commands. A load error
// must be a std::runtime_error whose text starts with "fuzz.eds"; nothing
// else may escape, crash or trigger a sanitizer.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "firmware_protocol/canopen.hpp"
#include "firmware_protocol/canopen_eds.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace fp = rise::firmware_protocol;
namespace co = rise::firmware_protocol::canopen;

namespace {

void check_pdos(const std::vector<co::Pdo>& pdos, const std::vector<fp::DbcMessage>& messages,
                std::span<const uint8_t> frame) {
  fuzz_check(pdos.size() == messages.size());
  for (std::size_t p = 0; p < pdos.size(); ++p) {
    fuzz_check(pdos[p].bits <= 64);
    fuzz_check(messages[p].dlc <= 8);
    for (const fp::DbcSignal& s : messages[p].signals) {
      fuzz_check(fp::signal_fits(s, messages[p].dlc));
      const int64_t raw = fp::extract_raw(s, frame);
      std::vector<uint8_t> copy(8, 0);
      fp::insert_raw(s, static_cast<uint64_t>(raw), copy);
      fuzz_check(fp::extract_raw(s, copy) == raw);
    }
  }
}

void check_device(const co::EdsDevice& eds, std::span<const uint8_t> frame) {
  fuzz_check(eds.heartbeat_ms() > 0);
  check_pdos(eds.tpdos(), eds.tpdo_messages(), frame);
  check_pdos(eds.rpdos(), eds.rpdo_messages(), frame);
  for (const co::OdEntry& e : eds.entries()) {
    const co::OdLookup by_address = eds.lookup(co::od_address(e.index, e.subindex));
    fuzz_check(by_address.entry != nullptr);
    const co::OdLookup by_name = eds.lookup(e.name);
    fuzz_check(by_name.entry != nullptr || !by_name.error.empty());
    for (const bool transmit : {true, false}) {
      const co::PdoSignal s = eds.pdo_signal(e, transmit);
      fuzz_check((s.signal == nullptr) == (s.message == nullptr));
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // Byte 0: the node id; the rest: the file.
  const auto node = static_cast<uint8_t>(1 + data[0] % 127);
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  uint8_t frame[8] = {};
  for (std::size_t i = 0; i < 8; ++i) frame[i] = data[(i * 13) % size];
  // The wire readers on the same bytes.
  (void)co::read_heartbeat(node, 0x700u + node, std::span<const uint8_t>(frame, data[0] % 9));
  (void)co::read_nmt(0, std::span<const uint8_t>(frame, data[0] % 3));
  try {
    check_device(co::EdsDevice::parse(text, "fuzz.eds", node), frame);
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).starts_with("fuzz.eds"));
  }
  return 0;
}
