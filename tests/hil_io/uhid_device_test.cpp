// UhidDevice on the host: what can be checked without the kernel's uhid
// (this host and CI have no /dev/uhid; tests/vcan/hid_vm_test.cpp drives a
// real one under qemu).

#include <catch2/catch.hpp>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "hil/io/uhid_device.hpp"

namespace io = rise::hil::io;

namespace {
io::UhidSettings settings() {
  io::UhidSettings s;
  s.descriptor = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0xC0};
  return s;
}
}  // namespace

TEST_CASE("uhid device refuses names and descriptors that do not fit uhid's fields", "[hil_io]") {
  CHECK_NOTHROW(io::UhidDevice(settings()));
  io::UhidSettings s = settings();
  SECTION("name") {
    s.name = std::string(128, 'n');
    CHECK_THROWS_WITH(io::UhidDevice(s), "uhid: name longer than 127 bytes");
  }
  SECTION("uniq") {
    s.uniq = std::string(64, 'u');
    CHECK_THROWS_WITH(io::UhidDevice(s), "uhid: uniq longer than 63 bytes");
  }
  SECTION("descriptor") {
    s.descriptor = GENERATE(std::vector<uint8_t>{}, std::vector<uint8_t>(4097, 0));
    CHECK_THROWS_WITH(io::UhidDevice(s), Catch::StartsWith("uhid: the report descriptor must be 1..4096 bytes"));
  }
}

TEST_CASE("uhid device that is not created reports errors instead of throwing", "[hil_io]") {
  io::UhidDevice device(settings());
  CHECK_FALSE(device.is_created());
  const uint8_t report[] = {0x00, 0x01};
  CHECK(device.send_input(report) == io::IoStatus::Error);
  CHECK(device.last_error() == "uhid: not created");
  io::UhidEvent event;
  CHECK(device.poll(event, 0) == io::IoStatus::Disconnected);
  if (!std::filesystem::exists("/dev/uhid")) {
    CHECK(device.create() == io::IoStatus::Error);
    CHECK(device.last_error() == "/dev/uhid: No such file or directory");
    CHECK_FALSE(device.is_created());
  }
  device.destroy();  // harmless when not created
  CHECK_FALSE(device.is_started());
}
