#pragma once

// HID report descriptors shared by the tests (firmware_protocol, panels,
// hil, and the HID tests under qemu).

#include <cstdint>

namespace rise::test {

// Gravis GamePad Pro USB (0428:4001), the bytes of Android's CTS test file
// android-cts/gravis_gamepadprousb_register.json (so tests that need no CTS
// oracle run without the shared data): x, y (8 bits each), buttons 1..10,
// no report ids, no output report.
inline constexpr uint8_t gravis_descriptor[] = {
    0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x05, 0x01, 0x09, 0x01, 0xa1, 0x00, 0x09, 0x30, 0x09, 0x31, 0x15,
    0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0xc0, 0x05, 0x09, 0x19, 0x01, 0x29, 0x0a,
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0a, 0x81, 0x02, 0x95, 0x01, 0x75, 0x06, 0x81, 0x01, 0xc0};

// A test pad with all three report kinds and report ids (pid.codes' test
// VID:PID 1209:0001), written for these tests:
inline constexpr uint8_t led_pad_descriptor[] = {
    0x05, 0x01,        // Usage Page (Generic Desktop)
    0x09, 0x05,        // Usage (Game Pad)
    0xA1, 0x01,        // Collection (Application)
    0x85, 0x01,        //   Report ID (1): input, 3 bytes after the id
    0x09, 0x30,        //   Usage (X)
    0x09, 0x31,        //   Usage (Y)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x02,        //   Report Count (2)
    0x81, 0x02,        //   Input (Data, Variable, Absolute): x, y
    0x05, 0x09,        //   Usage Page (Button)
    0x19, 0x01,        //   Usage Minimum (1)
    0x29, 0x08,        //   Usage Maximum (8)
    0x25, 0x01,        //   Logical Maximum (1)
    0x75, 0x01,        //   Report Size (1)
    0x95, 0x08,        //   Report Count (8)
    0x81, 0x02,        //   Input (Data, Variable, Absolute): button_1..button_8
    0x85, 0x02,        //   Report ID (2): output, 1 byte after the id
    0x05, 0x08,        //   Usage Page (LEDs)
    0x19, 0x01,        //   Usage Minimum (1: Num Lock)
    0x29, 0x04,        //   Usage Maximum (4: Compose)
    0x95, 0x04,        //   Report Count (4)
    0x91, 0x02,        //   Output (Data, Variable, Absolute): usage_0008_0001..usage_0008_0004, bits 0..3
    0x95, 0x01,        //   Report Count (1)
    0x75, 0x04,        //   Report Size (4)
    0x91, 0x01,        //   Output (Constant): padding, bits 4..7
    0x85, 0x03,        //   Report ID (3): feature, 1 byte after the id
    0x06, 0x00, 0xFF,  //   Usage Page (Vendor 0xFF00)
    0x09, 0x01,        //   Usage (1)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x01,        //   Report Count (1)
    0xB1, 0x02,        //   Feature (Data, Variable, Absolute): vendor_ff00_0001
    0xC0,              // End Collection
};

// A pad with LEDs and a rumble motor in one output report, no report ids,
// written for these tests: input x, y (8 bits each); output 4 LED bits,
// 4 bits padding, then the motor's strength, a vendor byte 0..255
// (vendor_ff00_0002).
inline constexpr uint8_t rumble_pad_descriptor[] = {
    0x05, 0x01,        // Usage Page (Generic Desktop)
    0x09, 0x05,        // Usage (Game Pad)
    0xA1, 0x01,        // Collection (Application)
    0x09, 0x30,        //   Usage (X)
    0x09, 0x31,        //   Usage (Y)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x02,        //   Report Count (2)
    0x81, 0x02,        //   Input (Data, Variable, Absolute): x, y
    0x05, 0x08,        //   Usage Page (LEDs)
    0x19, 0x01,        //   Usage Minimum (1)
    0x29, 0x04,        //   Usage Maximum (4)
    0x25, 0x01,        //   Logical Maximum (1)
    0x75, 0x01,        //   Report Size (1)
    0x95, 0x04,        //   Report Count (4)
    0x91, 0x02,        //   Output (Data, Variable, Absolute): usage_0008_0001..4, bits 0..3
    0x75, 0x04,        //   Report Size (4)
    0x95, 0x01,        //   Report Count (1)
    0x91, 0x01,        //   Output (Constant): padding, bits 4..7
    0x06, 0x00, 0xFF,  //   Usage Page (Vendor 0xFF00)
    0x09, 0x02,        //   Usage (2)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x95, 0x01,        //   Report Count (1)
    0x91, 0x02,        //   Output (Data, Variable, Absolute): vendor_ff00_0002, byte 1
    0xC0,              // End Collection
};

}  // namespace rise::test
