// libFuzzer target: the rest of what a user hands the programs — a console
// script (rise-panel's timeline, against the shipped console), a pose graph
// (g2o / TORO), an instructor key file and the transports' URLs (CAN,
// Modbus, hid://, evdev://). An error must be the exception each documents,
// its text naming the file or the URL; nothing may crash, hang or trigger
// a sanitizer.
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hil/io/can_url.hpp"
#include "hil/io/evdev_device.hpp"
#include "hil/io/hid_device.hpp"
#include "hil/io/modbus_url.hpp"
#include "msgs/command_auth.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "semantic/pose_graph_io.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace {

const rise::panels::PanelDefinition& console() {
  static const auto definition = rise::panels::load_panel_definition(RISE_FUZZ_ROOT "/panels/definitions/rise_console.yaml");
  return definition;
}

// The readers that take a path: the input goes through a file of this
// process, private (0600) as an instructor key must be.
std::string as_file(const std::string& text) {
  static const std::string path = "/dev/shm/rise-fuzz-inputs-" + std::to_string(::getpid());
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  ::chmod(path.c_str(), 0600);
  return path;
}

template <typename Error, typename Parse>
void parse_one(std::string_view must_name, Parse parse) {
  try {
    parse();
  } catch (const Error& e) {
    fuzz_check(std::string_view(e.what()).find(must_name) != std::string_view::npos);
  }
}

void url(const std::string& text) {
  parse_one<std::invalid_argument>("", [&] { rise::hil::io::parse_can_url(text); });
  parse_one<std::invalid_argument>("", [&] { rise::hil::io::parse_modbus_url(text); });
  std::string error;
  const auto hid = rise::hil::io::parse_hid_url(text, &error);
  fuzz_check(hid.has_value() || !error.empty());
  error.clear();
  const auto evdev = rise::hil::io::parse_evdev_url(text, &error);
  fuzz_check(evdev.has_value() || !error.empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  // The first byte picks the reader.
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 4) {
    case 0:
      parse_one<std::runtime_error>("fuzz.script", [&] { rise::panels::parse_timeline(text, "fuzz.script", console()); });
      break;
    case 1: {
      const std::string path = as_file(text);
      parse_one<std::runtime_error>(path, [&] { rise::semantic::read_pose_graph(path); });
      break;
    }
    case 2: {
      const std::string path = as_file(text);
      parse_one<std::runtime_error>(path, [&] { rise::msgs::load_instructor_key(path); });
      break;
    }
    default: url(text); break;
  }
  return 0;
}
