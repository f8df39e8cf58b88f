// libFuzzer target: the DBC parser on arbitrary text, then every parsed
// message decoded from (and encoded into) frames. A load error must be a
// std::runtime_error whose text starts with "fuzz.dbc:"; nothing else may
// escape, crash or trigger a sanitizer.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "firmware_protocol/dbc.hpp"

namespace fp = rise::firmware_protocol;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fp::DbcDatabase db;
  try {
    db = fp::DbcDatabase::parse(text, "fuzz.dbc");
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.dbc:"));
    return 0;
  }
  std::vector<uint8_t> frame(64);
  for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = size > 0 ? data[(i * 7) % size] : 0;
  for (const fp::DbcMessage& m : db.messages()) {
    check(m.dlc <= 64);
    for (const std::size_t length : {std::size_t{m.dlc}, std::size_t{8}, std::size_t{64}}) {
      for (const fp::DecodedSignal& d : db.decode(m, std::span(frame).first(length))) {
        check(fp::signal_fits(*d.signal, length));
        // Integer signals survive a raw round trip.
        if (d.signal->value_type == fp::SignalValueType::Integer) {
          std::vector<uint8_t> copy(length, 0);
          fp::insert_raw(*d.signal, static_cast<uint64_t>(d.raw), copy);
          check(fp::extract_raw(*d.signal, copy) == d.raw);
        }
        (void)d.label();
      }
    }
    for (const fp::DbcSignal& s : m.signals) {
      const fp::SignalValue v[] = {{s.name, s.offset}};
      try {
        (void)db.encode(m, v);
      } catch (const std::out_of_range&) {
        // a signal outside the DLC, or offset not representable
      } catch (const std::invalid_argument&) {
        // duplicate names inside VECTOR__INDEPENDENT_SIG_MSG resolve to the first
      }
    }
  }
  return 0;
}
