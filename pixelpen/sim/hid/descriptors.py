"""Report descriptors of the simulated HID devices, written item by item from the HID 1.11 spec and the usage tables.

Sources: Device Class Definition for HID 1.11 (§6.2.2 items, Appendix B.1 boot keyboard, B.2 boot mouse,
Appendix E.10 joystick), HID Usage Tables 1.4 (Generic Desktop 0x01, Simulation 0x02, Keyboard 0x07, LED
0x08, Button 0x09, Consumer 0x0C, Digitizers 0x0D; Resolution Multiplier §4.3.1), and Microsoft's sample
descriptors (pen and multitouch digitizers, "Enhanced Wheel Support").  Each constant's docstring gives the
report layout it produces, byte by byte, so tests can pack reports by hand.  Multi-byte fields are little
endian; "bit 0" is the least significant bit.  Numbered reports start with their report ID byte.
"""

from __future__ import annotations

BOOT_MOUSE = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x02,        # Usage (Mouse)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x01,        #   Usage (Pointer)
    0xA1, 0x00,        #   Collection (Physical)
    0x05, 0x09,        #     Usage Page (Button)
    0x19, 0x01,        #     Usage Minimum (Button 1)
    0x29, 0x03,        #     Usage Maximum (Button 3)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x95, 0x03,        #     Report Count (3)
    0x75, 0x01,        #     Report Size (1)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): the three buttons
    0x95, 0x01,        #     Report Count (1)
    0x75, 0x05,        #     Report Size (5)
    0x81, 0x01,        #     Input (Constant): 5 bits of padding
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x09, 0x30,        #     Usage (X)
    0x09, 0x31,        #     Usage (Y)
    0x15, 0x81,        #     Logical Minimum (-127)
    0x25, 0x7F,        #     Logical Maximum (127)
    0x75, 0x08,        #     Report Size (8)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x06,        #     Input (Data, Variable, Relative): X, Y
    0xC0,              #   End Collection
    0xC0,              # End Collection
])
"""HID 1.11 Appendix B.2 boot mouse (50 bytes). Input report, unnumbered, 3 bytes:

byte 0 bit 0 button 1 (left), bit 1 button 2 (right), bit 2 button 3 (middle), bits 3-7 padding;
byte 1 X int8 (-127..127, relative counts); byte 2 Y int8 (down is positive).
"""

TRACKBALL = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x02,        # Usage (Mouse)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x09, 0x01,        #   Usage (Pointer)
    0xA1, 0x00,        #   Collection (Physical)
    0x05, 0x09,        #     Usage Page (Button)
    0x19, 0x01,        #     Usage Minimum (Button 1)
    0x29, 0x05,        #     Usage Maximum (Button 5)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x95, 0x05,        #     Report Count (5)
    0x75, 0x01,        #     Report Size (1)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): buttons 1-5
    0x95, 0x01,        #     Report Count (1)
    0x75, 0x03,        #     Report Size (3)
    0x81, 0x03,        #     Input (Constant, Variable): 3 bits of padding
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x09, 0x30,        #     Usage (X)
    0x09, 0x31,        #     Usage (Y)
    0x16, 0x00, 0x83,  #     Logical Minimum (-32000)
    0x26, 0x00, 0x7D,  #     Logical Maximum (32000)
    0x36, 0xC0, 0xE0,  #     Physical Minimum (-8000)
    0x46, 0x40, 0x1F,  #     Physical Maximum (8000)
    0x65, 0x13,        #     Unit (English Linear: inch)
    0x55, 0x0E,        #     Unit Exponent (-2): physical in 1/100 inch, so 64000 counts per 160 in = 400 cpi
    0x75, 0x10,        #     Report Size (16)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x06,        #     Input (Data, Variable, Relative): X, Y
    0x65, 0x00,        #     Unit (None)
    0x55, 0x00,        #     Unit Exponent (0)
    0xA1, 0x02,        #     Collection (Logical): the wheel and its multiplier
    0x85, 0x02,        #       Report ID (2)
    0x09, 0x48,        #       Usage (Resolution Multiplier)
    0x15, 0x00,        #       Logical Minimum (0)
    0x25, 0x01,        #       Logical Maximum (1)
    0x35, 0x01,        #       Physical Minimum (1)
    0x45, 0x08,        #       Physical Maximum (8): set to 1, the wheel counts 1/8 detents
    0x75, 0x02,        #       Report Size (2)
    0x95, 0x01,        #       Report Count (1)
    0xA4,              #       Push (report ID 2, the multiplier's sizes and ranges)
    0xB1, 0x02,        #       Feature (Data, Variable, Absolute): the wheel's multiplier
    0x85, 0x01,        #       Report ID (1)
    0x35, 0x00,        #       Physical Minimum (0)
    0x45, 0x00,        #       Physical Maximum (0)
    0x09, 0x38,        #       Usage (Wheel)
    0x15, 0x81,        #       Logical Minimum (-127)
    0x25, 0x7F,        #       Logical Maximum (127)
    0x75, 0x08,        #       Report Size (8)
    0x81, 0x06,        #       Input (Data, Variable, Relative): wheel
    0xC0,              #     End Collection
    0xA1, 0x02,        #     Collection (Logical): AC Pan and its multiplier
    0xB4,              #       Pop (report ID 2, 2 bits, 0..1 -> 1..8)
    0x09, 0x48,        #       Usage (Resolution Multiplier)
    0xB1, 0x02,        #       Feature (Data, Variable, Absolute): the pan's multiplier
    0x75, 0x04,        #       Report Size (4)
    0xB1, 0x03,        #       Feature (Constant, Variable): 4 bits of padding
    0x85, 0x01,        #       Report ID (1)
    0x35, 0x00,        #       Physical Minimum (0)
    0x45, 0x00,        #       Physical Maximum (0)
    0x05, 0x0C,        #       Usage Page (Consumer)
    0x0A, 0x38, 0x02,  #       Usage (AC Pan)
    0x15, 0x81,        #       Logical Minimum (-127)
    0x25, 0x7F,        #       Logical Maximum (127)
    0x75, 0x08,        #       Report Size (8)
    0x81, 0x06,        #       Input (Data, Variable, Relative): horizontal scroll
    0xC0,              #     End Collection
    0xC0,              #   End Collection
    0xC0,              # End Collection
])
"""A 5-button trackball, 400 counts per inch, hi-res wheel and AC Pan (Microsoft "Enhanced Wheel Support").

Input report 1, 8 bytes: byte 0 = 0x01; byte 1 bits 0-4 buttons 1-5, bits 5-7 padding; bytes 2-3 X int16
(-32000..32000 counts, 400 per inch = 15.75 per mm); bytes 4-5 Y int16; byte 6 wheel int8 (-127..127, in
1/multiplier detents); byte 7 AC Pan int8.
Feature report 2, 2 bytes: byte 0 = 0x02; byte 1 bits 0-1 wheel Resolution Multiplier, bits 2-3 pan
Resolution Multiplier (logical 0..1 -> physical 1..8: 1 means 8 counts per detent), bits 4-7 padding.
The pan's multiplier lands in report 2 because Pop restores the report ID with the other globals (as the
kernel and Microsoft's sample have it; hid-tools 0.12 keeps the ID outside Push/Pop and files it under 1).
"""

JOYSTICK = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x04,        # Usage (Joystick)
    0xA1, 0x01,        # Collection (Application)
    0x09, 0x01,        #   Usage (Pointer)
    0xA1, 0x00,        #   Collection (Physical)
    0x09, 0x30,        #     Usage (X)
    0x09, 0x31,        #     Usage (Y)
    0x15, 0x81,        #     Logical Minimum (-127)
    0x25, 0x7F,        #     Logical Maximum (127)
    0x75, 0x08,        #     Report Size (8)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): X, Y
    0xC0,              #   End Collection
    0x05, 0x02,        #   Usage Page (Simulation Controls)
    0x09, 0xBB,        #   Usage (Throttle)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): throttle, -127..127
    0x05, 0x01,        #   Usage Page (Generic Desktop)
    0x09, 0x39,        #   Usage (Hat Switch)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x07,        #   Logical Maximum (7)
    0x35, 0x00,        #   Physical Minimum (0)
    0x46, 0x3B, 0x01,  #   Physical Maximum (315)
    0x65, 0x14,        #   Unit (English Rotation: degrees)
    0x75, 0x04,        #   Report Size (4)
    0x81, 0x42,        #   Input (Data, Variable, Absolute, Null State): hat, 8 = centred
    0x65, 0x00,        #   Unit (None)
    0x45, 0x00,        #   Physical Maximum (0)
    0x05, 0x09,        #   Usage Page (Button)
    0x19, 0x01,        #   Usage Minimum (Button 1)
    0x29, 0x04,        #   Usage Maximum (Button 4)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x04,        #   Report Count (4)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): buttons 1-4
    0xC0,              # End Collection
])
"""A joystick after HID 1.11 Appendix E.10 with an 8-way hat. Input report, unnumbered, 4 bytes:

byte 0 X int8 (-127..127, right positive); byte 1 Y int8 (forward is negative); byte 2 throttle int8
(Simulation Controls 0xBB, -127..127); byte 3 bits 0-3 hat (0 north, 1 north-east, … 7 north-west, 45° each;
8..15 outside 0..7: centred, the null state), bits 4-7 buttons 1-4.
"""

GAMEPAD = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x05,        # Usage (Game Pad)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x09, 0x30,        #   Usage (X): left stick
    0x09, 0x31,        #   Usage (Y): left stick
    0x09, 0x32,        #   Usage (Z): right stick X
    0x09, 0x35,        #   Usage (Rz): right stick Y
    0x15, 0x00,        #   Logical Minimum (0)
    0x26, 0xFF, 0x00,  #   Logical Maximum (255)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x04,        #   Report Count (4)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): the two sticks
    0x09, 0x39,        #   Usage (Hat Switch)
    0x25, 0x07,        #   Logical Maximum (7)
    0x35, 0x00,        #   Physical Minimum (0)
    0x46, 0x3B, 0x01,  #   Physical Maximum (315)
    0x65, 0x14,        #   Unit (English Rotation: degrees)
    0x75, 0x04,        #   Report Size (4)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x42,        #   Input (Data, Variable, Absolute, Null State): d-pad, 8 = centred
    0x65, 0x00,        #   Unit (None)
    0x45, 0x00,        #   Physical Maximum (0)
    0x05, 0x09,        #   Usage Page (Button)
    0x19, 0x01,        #   Usage Minimum (Button 1)
    0x29, 0x0E,        #   Usage Maximum (Button 14)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x0E,        #   Report Count (14)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): buttons 1-14
    0x95, 0x06,        #   Report Count (6)
    0x81, 0x03,        #   Input (Constant, Variable): 6 bits of padding
    0x05, 0x01,        #   Usage Page (Generic Desktop)
    0x09, 0x33,        #   Usage (Rx): left trigger
    0x09, 0x34,        #   Usage (Ry): right trigger
    0x26, 0xFF, 0x00,  #   Logical Maximum (255)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x02,        #   Report Count (2)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): the two triggers
    0xC0,              # End Collection
])
"""A DualShock-style game pad: two sticks, a d-pad hat, 14 buttons, two analogue triggers.

Input report 1, 10 bytes: byte 0 = 0x01; bytes 1-4 left X, left Y, right X (Z), right Y (Rz), uint8
0..255 (centre 0x80, up/left low); byte 5 bits 0-3 hat (0 north … 7 north-west, 8 centred), bits 4-7
buttons 1-4; byte 6 buttons 5-12; byte 7 bits 0-1 buttons 13-14, bits 2-7 padding; byte 8 left trigger
(Rx) uint8; byte 9 right trigger (Ry) uint8.
"""

PEN_TABLET = bytes([
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x01,        # Usage (Digitizer)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x02,        #   Report ID (2)
    0x09, 0x20,        #   Usage (Stylus)
    0xA1, 0x00,        #   Collection (Physical)
    0x09, 0x42,        #     Usage (Tip Switch)
    0x09, 0x44,        #     Usage (Barrel Switch)
    0x09, 0x3C,        #     Usage (Invert)
    0x09, 0x45,        #     Usage (Eraser)
    0x09, 0x5A,        #     Usage (Secondary Barrel Switch)
    0x09, 0x32,        #     Usage (In Range)
    0x15, 0x00,        #     Logical Minimum (0)
    0x25, 0x01,        #     Logical Maximum (1)
    0x75, 0x01,        #     Report Size (1)
    0x95, 0x06,        #     Report Count (6)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): the six switches
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x03,        #     Input (Constant, Variable): 2 bits of padding
    0xA4,              #     Push (Digitizers page, 1-bit 0..1, no unit)
    0x05, 0x01,        #     Usage Page (Generic Desktop)
    0x65, 0x11,        #     Unit (SI Linear: cm)
    0x55, 0x0D,        #     Unit Exponent (-3, the nibble form): physical in 10 µm
    0x35, 0x00,        #     Physical Minimum (0)
    0x46, 0x80, 0x57,  #     Physical Maximum (22400): 224 mm
    0x27, 0x00, 0xAF, 0x00, 0x00,  # Logical Maximum (44800): 200 counts per mm
    0x75, 0x10,        #     Report Size (16)
    0x95, 0x01,        #     Report Count (1)
    0x09, 0x30,        #     Usage (X)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): X
    0x46, 0xB0, 0x36,  #     Physical Maximum (14000): 140 mm
    0x27, 0x60, 0x6D, 0x00, 0x00,  # Logical Maximum (28000): 200 counts per mm
    0x09, 0x31,        #     Usage (Y)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): Y
    0xB4,              #     Pop (back to Digitizers, no unit, physical 0..0)
    0x09, 0x30,        #     Usage (Tip Pressure)
    0x26, 0xFF, 0x1F,  #     Logical Maximum (8191)
    0x75, 0x10,        #     Report Size (16)
    0x95, 0x01,        #     Report Count (1)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): pressure
    0x09, 0x3D,        #     Usage (X Tilt)
    0x09, 0x3E,        #     Usage (Y Tilt)
    0x15, 0xC0,        #     Logical Minimum (-64)
    0x25, 0x3F,        #     Logical Maximum (63)
    0x35, 0xC0,        #     Physical Minimum (-64)
    0x45, 0x3F,        #     Physical Maximum (63)
    0x65, 0x14,        #     Unit (English Rotation: degrees)
    0x55, 0x00,        #     Unit Exponent (0): one count per degree, 57 per radian
    0x75, 0x08,        #     Report Size (8)
    0x95, 0x02,        #     Report Count (2)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): tilt X, Y
    0x65, 0x00,        #     Unit (None)
    0x35, 0x00,        #     Physical Minimum (0)
    0x45, 0x00,        #     Physical Maximum (0)
    0x09, 0x5B,        #     Usage (Transducer Serial Number)
    0x15, 0x00,        #     Logical Minimum (0)
    0x27, 0xFF, 0xFF, 0xFF, 0x7F,  # Logical Maximum (2147483647)
    0x75, 0x20,        #     Report Size (32)
    0x95, 0x01,        #     Report Count (1)
    0x81, 0x02,        #     Input (Data, Variable, Absolute): the pen's serial number
    0xC0,              #   End Collection
    0xC0,              # End Collection
])
"""A Wacom-style pen tablet, 224 x 140 mm at 200 counts/mm, 8192 pressure levels, tilt in degrees.

Input report 2, 14 bytes: byte 0 = 0x02; byte 1 bit 0 tip switch, bit 1 barrel, bit 2 invert (eraser end
in range), bit 3 eraser (eraser touching), bit 4 2nd barrel, bit 5 in range, bits 6-7 padding; bytes 2-3 X
uint16 0..44800 (unit cm, exponent -3: 0..22.4 cm); bytes 4-5 Y uint16 0..28000 (0..14 cm); bytes 6-7 tip
pressure uint16 0..8191; byte 8 X tilt int8 -64..63 degrees (right positive); byte 9 Y tilt int8 (towards
the user positive); bytes 10-13 transducer serial uint32 0..2^31-1.
"""


def _finger() -> list[int]:
    """One finger's logical collection of TOUCHSCREEN (Microsoft's multitouch sample), 6 bytes of report."""
    return [
        0x05, 0x0D,        #   Usage Page (Digitizers)
        0x09, 0x22,        #   Usage (Finger)
        0xA1, 0x02,        #   Collection (Logical)
        0x09, 0x42,        #     Usage (Tip Switch)
        0x09, 0x47,        #     Usage (Confidence)
        0x15, 0x00,        #     Logical Minimum (0)
        0x25, 0x01,        #     Logical Maximum (1)
        0x75, 0x01,        #     Report Size (1)
        0x95, 0x02,        #     Report Count (2)
        0x81, 0x02,        #     Input (Data, Variable, Absolute): tip switch, confidence
        0x95, 0x06,        #     Report Count (6)
        0x81, 0x03,        #     Input (Constant, Variable): 6 bits of padding
        0x09, 0x51,        #     Usage (Contact Identifier)
        0x25, 0x7F,        #     Logical Maximum (127)
        0x75, 0x08,        #     Report Size (8)
        0x95, 0x01,        #     Report Count (1)
        0x81, 0x02,        #     Input (Data, Variable, Absolute): contact id
        0xA4,              #     Push (Digitizers page, 8 bits, 0..127, no unit)
        0x05, 0x01,        #     Usage Page (Generic Desktop)
        0x65, 0x11,        #     Unit (SI Linear: cm)
        0x55, 0x0E,        #     Unit Exponent (-2): physical in 0.1 mm
        0x35, 0x00,        #     Physical Minimum (0)
        0x46, 0xD0, 0x07,  #     Physical Maximum (2000): 200 mm
        0x26, 0x80, 0x0C,  #     Logical Maximum (3200): 16 counts per mm
        0x75, 0x10,        #     Report Size (16)
        0x09, 0x30,        #     Usage (X)
        0x81, 0x02,        #     Input (Data, Variable, Absolute): X
        0x46, 0xE2, 0x04,  #     Physical Maximum (1250): 125 mm
        0x26, 0xD0, 0x07,  #     Logical Maximum (2000): 16 counts per mm
        0x09, 0x31,        #     Usage (Y)
        0x81, 0x02,        #     Input (Data, Variable, Absolute): Y
        0xB4,              #     Pop
        0xC0,              #   End Collection
    ]


TOUCHSCREEN = bytes([
    0x05, 0x0D,        # Usage Page (Digitizers)
    0x09, 0x04,        # Usage (Touch Screen)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    *_finger(),        #   finger 1: Logical collection, 6 bytes of report
    *_finger(),        #   finger 2: the same collection again
    0x05, 0x0D,        #   Usage Page (Digitizers)
    0xA4,              #   Push (Digitizers page, no unit)
    0x09, 0x56,        #   Usage (Scan Time)
    0x66, 0x01, 0x10,  #   Unit (SI Linear: seconds)
    0x55, 0x0C,        #   Unit Exponent (-4): 100 µs counts
    0x35, 0x00,        #   Physical Minimum (0)
    0x47, 0xFF, 0xFF, 0x00, 0x00,  # Physical Maximum (65535)
    0x15, 0x00,        #   Logical Minimum (0)
    0x27, 0xFF, 0xFF, 0x00, 0x00,  # Logical Maximum (65535)
    0x75, 0x10,        #   Report Size (16)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): scan time of the frame, wraps at 65536
    0xB4,              #   Pop
    0x09, 0x54,        #   Usage (Contact Count)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x7F,        #   Logical Maximum (127)
    0x75, 0x08,        #   Report Size (8)
    0x95, 0x01,        #   Report Count (1)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): contacts in the frame (0 after the first report)
    0x85, 0x02,        #   Report ID (2)
    0x09, 0x55,        #   Usage (Contact Count Maximum)
    0x25, 0x0A,        #   Logical Maximum (10)
    0xB1, 0x02,        #   Feature (Data, Variable, Absolute): how many contacts the screen tracks
    0x85, 0x03,        #   Report ID (3)
    0x09, 0x52,        #   Usage (Input Mode)
    0xB1, 0x02,        #   Feature (Data, Variable, Absolute): 0 mouse, 1 single-input, 2 multi-input
    0xC0,              # End Collection
])
"""A multitouch screen, 200 x 125 mm at 16 counts/mm, two fingers per report (hybrid mode beyond two).

Input report 1, 16 bytes: byte 0 = 0x01; per finger (bytes 1-6, then 7-12): bit 0 tip switch, bit 1
confidence, bits 2-7 padding; a contact id uint8 0..127; X uint16 0..3200 (cm, exponent -2: 0..20 cm); Y
uint16 0..2000 (0..12.5 cm); bytes 13-14 scan time uint16 in 100 µs; byte 15 contact count uint8 (hybrid
mode: the frame's count in its first report, 0 in the others).
Feature report 2, 2 bytes: byte 0 = 0x02; byte 1 Contact Count Maximum 0..10.
Feature report 3, 2 bytes: byte 0 = 0x03; byte 1 Input Mode 0..10 (0 mouse, 1 single-input, 2 multi-input, as
Microsoft's touch devices have it; the kernel's hid-multitouch finds the usage in any feature report and sets 2).
Windows samples put Input Mode in a Device Configuration (0x0D 0x0E) application of its own; here it stays in the
touch screen's application so the device has one kind.
"""

BOOT_KEYBOARD = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x06,        # Usage (Keyboard)
    0xA1, 0x01,        # Collection (Application)
    0x05, 0x07,        #   Usage Page (Keyboard/Keypad)
    0x19, 0xE0,        #   Usage Minimum (Left Control)
    0x29, 0xE7,        #   Usage Maximum (Right GUI)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x08,        #   Report Count (8)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): modifier byte
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x08,        #   Report Size (8)
    0x81, 0x01,        #   Input (Constant): reserved byte
    0x95, 0x05,        #   Report Count (5)
    0x75, 0x01,        #   Report Size (1)
    0x05, 0x08,        #   Usage Page (LEDs)
    0x19, 0x01,        #   Usage Minimum (Num Lock)
    0x29, 0x05,        #   Usage Maximum (Kana)
    0x91, 0x02,        #   Output (Data, Variable, Absolute): LED report
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x03,        #   Report Size (3)
    0x91, 0x01,        #   Output (Constant): LED report padding
    0x95, 0x06,        #   Report Count (6)
    0x75, 0x08,        #   Report Size (8)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x65,        #   Logical Maximum (101)
    0x05, 0x07,        #   Usage Page (Keyboard/Keypad)
    0x19, 0x00,        #   Usage Minimum (Reserved: no event)
    0x29, 0x65,        #   Usage Maximum (Keyboard Application)
    0x81, 0x00,        #   Input (Data, Array): the key array
    0xC0,              # End Collection
])
"""HID 1.11 Appendix B.1 / E.6 boot keyboard (63 bytes).

Input report, unnumbered, 8 bytes: byte 0 modifiers (bit 0 LeftCtrl 0xE0, 1 LeftShift, 2 LeftAlt, 3 LeftGUI,
4 RightCtrl, 5 RightShift, 6 RightAlt, 7 RightGUI 0xE7); byte 1 reserved (0); bytes 2-7 usages of the keys
down (0x00 none, 0x01 ErrorRollOver in all six when more are down, 0x04 'a' … 0x65).
Output report, unnumbered, 1 byte: bit 0 Num Lock, 1 Caps Lock, 2 Scroll Lock, 3 Compose, 4 Kana, 5-7 padding.
"""

NKRO_KEYBOARD = bytes([
    0x05, 0x01,        # Usage Page (Generic Desktop)
    0x09, 0x06,        # Usage (Keyboard)
    0xA1, 0x01,        # Collection (Application)
    0x85, 0x01,        #   Report ID (1)
    0x05, 0x07,        #   Usage Page (Keyboard/Keypad)
    0x19, 0xE0,        #   Usage Minimum (Left Control)
    0x29, 0xE7,        #   Usage Maximum (Right GUI)
    0x15, 0x00,        #   Logical Minimum (0)
    0x25, 0x01,        #   Logical Maximum (1)
    0x75, 0x01,        #   Report Size (1)
    0x95, 0x08,        #   Report Count (8)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): modifier byte
    0x19, 0x00,        #   Usage Minimum (0x00)
    0x29, 0x97,        #   Usage Maximum (0x97, Keyboard LANG8)
    0x95, 0x98,        #   Report Count (152)
    0x81, 0x02,        #   Input (Data, Variable, Absolute): one bit per key usage 0x00..0x97
    0x05, 0x08,        #   Usage Page (LEDs)
    0x19, 0x01,        #   Usage Minimum (Num Lock)
    0x29, 0x05,        #   Usage Maximum (Kana)
    0x95, 0x05,        #   Report Count (5)
    0x91, 0x02,        #   Output (Data, Variable, Absolute): LED report
    0x95, 0x01,        #   Report Count (1)
    0x75, 0x03,        #   Report Size (3)
    0x91, 0x03,        #   Output (Constant, Variable): LED report padding
    0xC0,              # End Collection
])
"""An N-key-rollover keyboard: a bitmap of every key, report ID 1 for input and output.

Input report 1, 21 bytes: byte 0 = 0x01; byte 1 modifiers (bit 0 LeftCtrl 0xE0 … bit 7 RightGUI 0xE7);
bytes 2-20 the key bitmap: usage u is bit u % 8 of byte 2 + u // 8 (usages 0x00..0x97; 0x00-0x03 stay 0).
Output report 1, 2 bytes: byte 0 = 0x01; byte 1 bit 0 Num Lock, 1 Caps Lock, 2 Scroll Lock, 3 Compose,
4 Kana, bits 5-7 padding.
"""

DESCRIPTORS: dict[str, bytes] = {
    "boot_mouse": BOOT_MOUSE,
    "trackball": TRACKBALL,
    "joystick": JOYSTICK,
    "gamepad": GAMEPAD,
    "pen_tablet": PEN_TABLET,
    "touchscreen": TOUCHSCREEN,
    "boot_keyboard": BOOT_KEYBOARD,
    "nkro_keyboard": NKRO_KEYBOARD,
}
"""Every descriptor above by a lower-case name (for tests, benchmarks and ``pixelpen hid dump``)."""
