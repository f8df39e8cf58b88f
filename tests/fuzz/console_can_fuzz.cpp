// libFuzzer target: one Decoder fed a sequence of frames. Input layout:
//   byte 0: node id (low nibble), max_counter_delta (high nibble)
//   then records: id (2 bytes LE), length byte, data (length % 16 bytes);
//   a length byte of 0xFF calls reset() instead.
// Checks beyond "no crash, no UB": an accepted frame re-encodes to a frame the
// decoder accepts with the same content, and errors are in range.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "firmware_protocol/console_can.hpp"

namespace fp = rise::firmware_protocol;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

bool same_payload(const fp::WireFrame& a, const fp::WireFrame& b) {
  // Bytes 2..7 minus the reserved ones are the message; byte 1 low nibble the counter.
  if (a.can_id != b.can_id || (a.data[1] & 0x0F) != (b.data[1] & 0x0F)) return false;
  for (std::size_t i = 2; i < fp::kFrameLength; ++i)
    if (a.data[i] != b.data[i]) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const auto node = static_cast<uint8_t>(data[0] & 0x0F);
  fp::Decoder decoder(node, static_cast<uint8_t>(data[0] >> 4));
  std::size_t at = 1;
  while (at + 3 <= size) {
    const uint32_t id = static_cast<uint32_t>(data[at] | (data[at + 1] << 8));
    const uint8_t length_byte = data[at + 2];
    at += 3;
    if (length_byte == 0xFF) {
      decoder.reset();
      continue;
    }
    std::size_t length = length_byte % 16;
    if (length > size - at) length = size - at;
    const std::span<const uint8_t> frame(data + at, length);
    at += length;

    const fp::DecodeResult r = decoder.decode(id, frame);
    check(static_cast<std::size_t>(r.error) < fp::kDecodeErrorCount);
    if (r.error == fp::DecodeError::UnknownId) continue;
    check(fp::can_id(r.type, node) == id);
    if (r.error == fp::DecodeError::BadLength) check(length != fp::kFrameLength);
    if (!r.ok()) continue;

    check(fp::frame_type_of(r.message) == r.type);
    check(r.counter == (frame[1] & 0x0F));
    const fp::WireFrame again = fp::encode(r.message, node, r.counter);
    fp::WireFrame original{id, {}};
    for (std::size_t i = 0; i < fp::kFrameLength; ++i) original.data[i] = frame[i];
    // Reserved bytes may differ (the sender writes 0, the receiver ignores them).
    const bool reserved_zero = (frame[1] & 0xF0) == 0 &&
                               !(r.type == fp::FrameType::Buttons && (frame[6] | frame[7]) != 0) &&
                               !(r.type == fp::FrameType::Indicators && frame[7] != 0);
    if (reserved_zero) check(same_payload(again, original) && again.data[0] == frame[0]);
    fp::Decoder fresh(node);
    const fp::DecodeResult r2 = fresh.decode(again.can_id, again.data);
    check(r2.ok() && r2.type == r.type && r2.counter == r.counter);
    check(fp::encode(r2.message, node, r2.counter).data == again.data);
  }
  return 0;
}
