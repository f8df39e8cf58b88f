// libFuzzer target: the rise-modbus-v1 map's decoders. Input layout:
//   bytes 0..35: input registers 0..17 (big endian), 36..39: discrete bits
//   (little endian), 40: flag (bit 0: a last counter follows in 41..42, BE),
//   then a feedback block: 4 bytes coils (LE), 50 bytes holding registers (BE).
// Missing bytes read as 0. Checks beyond "no crash, no UB": an accepted block
// re-encodes to the same registers and bits, and decode_feedback/encode_feedback
// round-trip exactly.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "firmware_protocol/console_modbus.hpp"

namespace fp = rise::firmware_protocol;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

struct Reader {
  const uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  uint8_t byte() { return at < size ? data[at++] : (at++, uint8_t{0}); }
  uint16_t be16() {
    const uint8_t hi = byte();
    return static_cast<uint16_t>((hi << 8) | byte());
  }
  uint32_t le32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(byte()) << (8 * i);
    return v;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  Reader in{data, size};
  std::array<uint16_t, fp::modbus_ir::kCount> regs{};
  for (auto& r : regs) r = in.be16();
  const uint32_t bits = in.le32();
  const uint8_t flag = in.byte();
  std::optional<uint16_t> last;
  if (flag & 1u) last = in.be16();

  const fp::ModbusInputsResult r = fp::decode_inputs(regs, bits, last);
  check(static_cast<std::size_t>(r.error) < fp::kModbusDecodeErrorCount);
  if (r.ok() || r.error == fp::ModbusDecodeError::StaleCounter) {
    const fp::ModbusInputBlock again = fp::encode_inputs(r.inputs);
    check(again.registers == regs);
    check(again.discrete_bits == bits);
    check(r.ok() == !(last && *last == r.inputs.alive_counter));
  }

  fp::ModbusFeedbackBlock fb;
  fb.coil_bits = in.le32();
  for (auto& h : fb.holding) h = in.be16();
  const fp::ModbusFeedbackResult f = fp::decode_feedback(fb);
  check(f.error == fp::ModbusDecodeError::None || f.error == fp::ModbusDecodeError::BadValue);
  if (f.ok()) {
    const fp::ModbusFeedbackBlock again = fp::encode_feedback(f.indicators, f.displays);
    check(again.coil_bits == fb.coil_bits);
    check(again.holding == fb.holding);
  }
  return 0;
}
