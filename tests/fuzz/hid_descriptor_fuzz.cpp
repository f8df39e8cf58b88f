// libFuzzer target: the HID report-descriptor parser on arbitrary bytes, then
// every input report of a parsed descriptor decoded from (and every output
// field encoded into) bytes of the same input; the text readers on the same
// bytes. A parse error must carry an offset inside the input; a reader error
// must be a std::runtime_error naming "fuzz.txt:"; nothing may crash or
// trigger a sanitizer.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "firmware_protocol/hid_descriptor.hpp"
#include "firmware_protocol/hid_report.hpp"
#include "firmware_protocol/hid_text.hpp"

namespace fp = rise::firmware_protocol;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::span<const uint8_t> bytes(data, size);
  const fp::HidParseResult result = fp::parse_hid_descriptor(bytes);
  // Naming tens of thousands of 1-bit elements is correct but slow under the
  // sanitizers; such descriptors are only parsed, to keep the run bounded.
  uint64_t elements = 0;
  for (const fp::HidField& f : result.descriptor.fields) elements += f.count;
  if (!result) {
    check(result.error_offset <= size);
  } else if (elements <= 1024) {
    const fp::HidDescriptor& d = result.descriptor;
    const fp::HidReportDecoder decoder(d);
    const fp::HidInputEncoder input_encoder(d);
    std::vector<fp::HidSignalValue> values(decoder.signals().size());
    std::vector<uint8_t> report(64);
    for (std::size_t i = 0; i < report.size(); ++i) report[i] = size > 0 ? data[(i * 7) % size] : 0;
    for (const fp::HidReportLayout& r : d.reports) {
      if (r.kind != fp::HidReportKind::Input) continue;
      const std::size_t length = d.report_length(r.report_id, r.kind);
      std::vector<uint8_t> input(length);
      for (std::size_t i = 0; i < length; ++i) input[i] = report[i % report.size()];
      if (d.uses_report_ids) input[0] = r.report_id;
      check(decoder.decode(input, values) == fp::HidDecodeStatus::Ok);
      // Re-encoding what was decoded gives a report that decodes the same.
      std::vector<int64_t> raw(values.size());
      for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = values[i].raw;
      std::vector<uint8_t> again(length);
      check(input_encoder.encode_report(r.report_id, raw, again) == length);
      std::vector<fp::HidSignalValue> again_values(values.size());
      check(decoder.decode(again, again_values) == fp::HidDecodeStatus::Ok);
      for (const uint32_t k : decoder.signals_of(r.report_id)) check(again_values[k].raw == values[k].raw);
      if (length > 0) {
        check(decoder.decode(std::span<const uint8_t>(input).first(length - 1), values) !=
              fp::HidDecodeStatus::Ok);
      }
    }
    const fp::HidOutputEncoder encoder(d);
    for (std::size_t i = 0; i < encoder.signals().size() && i < 256; ++i) {
      const fp::HidSignal& s = encoder.signals()[i];
      std::vector<uint8_t> out(encoder.report_length(s.report_id));
      const int64_t raw = fp::hid_raw_from_value(s, 0.5);
      check(encoder.encode(i, raw, out));
      const std::span<const uint8_t> payload = d.uses_report_ids ? std::span<const uint8_t>(out).subspan(1)
                                                                 : std::span<const uint8_t>(out);
      const uint64_t mask = s.bit_size >= 64 ? ~uint64_t{0} : (uint64_t{1} << s.bit_size) - 1;
      check((static_cast<uint64_t>(fp::hid_extract(s, payload)) & mask) == (static_cast<uint64_t>(raw) & mask));
    }
    check(!fp::describe_hid_descriptor(d).empty());
  }

  // The text readers see the same bytes as text.
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const fp::HidDescriptorSource source =
        fp::read_hid_descriptor(text, fp::detect_hid_format(text, "fuzz.txt"), "fuzz.txt");
    check(source.bytes.size() == source.lines.size());
  } catch (const std::runtime_error& e) {
    check(std::string_view(e.what()).starts_with("fuzz.txt:"));
  }
  return 0;
}
