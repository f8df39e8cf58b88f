#include <catch2/catch.hpp>

#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

#include "hil/io/can_bus.hpp"

using namespace rise::hil::io;

namespace {

// PF_CAN and CAN_RAW from <linux/can.h>, spelled out so the test states
// what it probes.
constexpr int kPfCan = 29;
constexpr int kCanRaw = 1;

bool kernel_has_can() {
  const int fd = ::socket(kPfCan, SOCK_RAW, kCanRaw);
  if (fd >= 0) {
    ::close(fd);
    return true;
  }
  return errno != EAFNOSUPPORT;
}

}  // namespace

TEST_CASE("opening socketcan fails with a clear message when it cannot work", "[hil_io]") {
  if (!kernel_has_can()) {
    // This kernel was built without the CAN stack (CI containers).
    try {
      open_can_bus("socketcan://vcan0");
      FAIL("opened socketcan://vcan0 on a kernel without CAN");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::StartsWith("socketcan://vcan0: "));
      CHECK_THAT(e.what(), Catch::Contains("this kernel has no CAN support (socket: "));
    }
  } else {
    try {
      open_can_bus("socketcan://rise_nosuch0");
      FAIL("opened a CAN interface that does not exist");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains("socketcan://rise_nosuch0"));
      CHECK_THAT(e.what(), Catch::Contains("no such CAN interface 'rise_nosuch0'"));
    }
  }
}
