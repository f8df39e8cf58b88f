// libFuzzer target: the recordings people replay — CAN logs (candump,
// Vector ASC, PEAK TRC; the format from the first lines, else from the
// extension the first byte picks; Vector BLF and pcap/pcapng by their magic
// bytes), Modbus transaction traces, Modbus/TCP captures (pcap) and
// hid-recorder files — each read from the same arbitrary bytes written to
// a file. The CAN log reader never throws once open and counts what it
// skips; a trace line that parses formats back to the same line's record;
// the trace and HID readers' errors are std::runtime_errors naming the
// file; nothing may crash or trigger a sanitizer.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include <unistd.h>

#include "hil/io/can_log.hpp"
#include "hil/io/hid_recording.hpp"
#include "hil/io/modbus_capture.hpp"
#include "hil/io/modbus_trace.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace io = rise::hil::io;

namespace {

// The input as a file the readers open (in memory where /dev/shm is).
std::string write_input(const std::string& name, std::string_view bytes) {
  static const std::string dir =
      (::access("/dev/shm", W_OK) == 0 ? "/dev/shm/" : "./") + std::string("rise-fuzz-") + std::to_string(::getpid()) + "-";
  const std::string path = dir + name;
  static bool cleanup = [] {
    return std::atexit([] {
      for (const char* n : {"input.log", "input.asc", "input.trc", "input.blf", "input.pcap", "input.modbus.log", "input.hid", "input.modbus.pcap"})
        std::remove((dir + n).c_str());
    }) == 0;
  }();
  (void)cleanup;
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

void can_log(std::string_view bytes, const char* extension) {
  const std::string path = write_input(std::string("input") + extension, bytes);
  try {
    io::CanLogReader reader(path);
    io::CanLogRecord record;
    for (int pass = 0; pass < 2; ++pass) {
      size_t frames = 0;
      while (reader.next(record)) {
        fuzz_check(record.frame.len <= 64);
        fuzz_check(record.line >= 1);
        ++frames;
      }
      fuzz_check(reader.bytes_consumed() <= reader.size_bytes());
      reader.rewind();
      (void)frames;
    }
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).find(path) != std::string_view::npos);
  }
}

void modbus_trace(std::string_view bytes) {
  // Line by line: a parsed line formats to a line that parses to the same record.
  size_t begin = 0;
  while (begin <= bytes.size()) {
    const size_t end = std::min(bytes.find('\n', begin), bytes.size());
    const io::ModbusTraceParse p = io::parse_modbus_trace_line(bytes.substr(begin, end - begin));
    if (p.ok && !p.skip) {
      const std::string again = io::format_modbus_trace_line(p.record);
      const io::ModbusTraceParse q = io::parse_modbus_trace_line(again);
      fuzz_check(q.ok && io::format_modbus_trace_line(q.record) == again);
    }
    begin = end + 1;
  }
  const std::string path = write_input("input.modbus.log", bytes);
  try {
    io::ModbusTraceReader reader(path);
    io::ModbusTraceRecord record;
    while (reader.next(record)) {
    }
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).starts_with(path));
  }
}

void hid_recording(std::string_view bytes) {
  const std::string path = write_input("input.hid", bytes);
  try {
    io::HidRecordingReader reader(path);
    io::HidRecordingRecord record;
    for (int pass = 0; pass < 2; ++pass) {
      while (reader.next(record)) fuzz_check(record.bytes.size() <= 4096 || record.kind == io::HidRecordingRecord::Kind::Plug);
      reader.rewind();
    }
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).starts_with(path));
  }
}

// A Modbus/TCP capture: every transaction's request starts with its function
// code; the trace records made from it format to lines that parse back.
void modbus_capture(std::string_view bytes) {
  const std::string path = write_input("input.modbus.pcap", bytes);
  (void)io::looks_like_modbus_capture(path);
  try {
    const io::ModbusCapture capture = io::read_modbus_capture(path);
    fuzz_check(capture.transactions.size() <= capture.stats.requests);
    for (const auto& t : capture.transactions) {
      fuzz_check(!t.request_pdu.empty() && t.request_pdu[0] == t.function);
      if (!t.response_us) fuzz_check(t.response_pdu.empty() && !t.exception);
    }
    for (const auto& r : io::modbus_trace_from_capture(capture, "fuzz")) {
      const std::string line = io::format_modbus_trace_line(r);
      const io::ModbusTraceParse p = io::parse_modbus_trace_line(line);
      fuzz_check(p.ok && io::format_modbus_trace_line(p.record) == line);
    }
  } catch (const std::runtime_error& e) {
    fuzz_check(std::string_view(e.what()).find(path) != std::string_view::npos);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 8) {
    case 0: can_log(bytes, ".log"); break;
    case 1: can_log(bytes, ".asc"); break;
    case 2: can_log(bytes, ".trc"); break;
    case 3: modbus_trace(bytes); break;
    case 4: hid_recording(bytes); break;
    case 5: can_log(bytes, ".blf"); break;
    case 6: can_log(bytes, ".pcap"); break;
    default: modbus_capture(bytes); break;
  }
  return 0;
}
