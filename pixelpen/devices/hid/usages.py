"""Names of HID usage pages and usages, from the HID Usage Tables 1.4 (HUT).

``usage_name(0x00010030)`` is ``"X"``; ``page_name(0x0D)`` is ``"Digitizers"``.  The tables cover Generic
Desktop, Simulation Controls, Keyboard/Keypad, LED, Button, Ordinal, the common Consumer usages and
Digitizers; other pages have their page name only, and vendor-defined pages (0xFF00..0xFFFF) are named as
such.  Keyboard names drop the HUT's leading "Keyboard " (``0x00070004`` is ``"a and A"``); keypad names
keep "Keypad ".  A usage not in the tables is named by its page and hex ID (``"Generic Desktop 0x00FF"``).

Longer than 600 lines because it is data: the usage tables, one name per line, as the HUT lists them.
"""

from __future__ import annotations

PAGE_NAMES: dict[int, str] = {
    0x01: "Generic Desktop", 0x02: "Simulation Controls", 0x03: "VR Controls", 0x04: "Sport Controls",
    0x05: "Game Controls", 0x06: "Generic Device Controls", 0x07: "Keyboard/Keypad", 0x08: "LED",
    0x09: "Button", 0x0A: "Ordinal", 0x0B: "Telephony Device", 0x0C: "Consumer", 0x0D: "Digitizers",
    0x0E: "Haptics", 0x0F: "Physical Input Device", 0x10: "Unicode", 0x11: "SoC", 0x12: "Eye and Head Trackers",
    0x14: "Auxiliary Display", 0x20: "Sensors", 0x40: "Medical Instrument", 0x41: "Braille Display",
    0x59: "Lighting And Illumination", 0x80: "Monitor", 0x81: "Monitor Enumerated", 0x82: "VESA Virtual Controls",
    0x84: "Power", 0x85: "Battery System", 0x8C: "Barcode Scanner", 0x8D: "Scales", 0x8E: "Magnetic Stripe Reader",
    0x90: "Camera Control", 0x91: "Arcade", 0x92: "Gaming Device", 0xF1D0: "FIDO Alliance",
}
"""Usage page names (HUT 1.4 §3, table 1); 0xFF00..0xFFFF are vendor-defined."""

VENDOR_PAGES = range(0xFF00, 0x10000)
"""The vendor-defined usage pages."""


def _table(text: str) -> dict[int, str]:
    """``HEX Name`` lines to a dict (the tables below are written this way to stay compact)."""
    out = {}
    for line in text.strip().splitlines():
        key, _, name = line.strip().partition(" ")
        out[int(key, 16)] = name
    return out


_GENERIC_DESKTOP = _table("""
    00 Undefined
    01 Pointer
    02 Mouse
    04 Joystick
    05 Gamepad
    06 Keyboard
    07 Keypad
    08 Multi-axis Controller
    09 Tablet PC System Controls
    0A Water Cooling Device
    0B Computer Chassis Device
    0C Wireless Radio Controls
    0D Portable Device Control
    0E System Multi-Axis Controller
    0F Spatial Controller
    10 Assistive Control
    11 Device Dock
    12 Dockable Device
    13 Call State Management Control
    30 X
    31 Y
    32 Z
    33 Rx
    34 Ry
    35 Rz
    36 Slider
    37 Dial
    38 Wheel
    39 Hat Switch
    3A Counted Buffer
    3B Byte Count
    3C Motion Wakeup
    3D Start
    3E Select
    40 Vx
    41 Vy
    42 Vz
    43 Vbrx
    44 Vbry
    45 Vbrz
    46 Vno
    47 Feature Notification
    48 Resolution Multiplier
    49 Qx
    4A Qy
    4B Qz
    4C Qw
    80 System Control
    81 System Power Down
    82 System Sleep
    83 System Wake Up
    84 System Context Menu
    85 System Main Menu
    86 System App Menu
    87 System Menu Help
    88 System Menu Exit
    89 System Menu Select
    8A System Menu Right
    8B System Menu Left
    8C System Menu Up
    8D System Menu Down
    8E System Cold Restart
    8F System Warm Restart
    90 D-pad Up
    91 D-pad Down
    92 D-pad Right
    93 D-pad Left
    94 Index Trigger
    95 Palm Trigger
    96 Thumbstick
    97 System Function Shift
    98 System Function Shift Lock
    99 System Function Shift Lock Indicator
    9A System Dismiss Notification
    9B System Do Not Disturb
    A0 System Dock
    A1 System Undock
    A2 System Setup
    A3 System Break
    A4 System Debugger Break
    A5 Application Break
    A6 Application Debugger Break
    A7 System Speaker Mute
    A8 System Hibernate
    B0 System Display Invert
    B1 System Display Internal
    B2 System Display External
    B3 System Display Both
    B4 System Display Dual
    B5 System Display Toggle Int/Ext
    B6 System Display Swap Primary/Secondary
    B7 System Display LCD Autoscale
    C0 Sensor Zone
    C1 RPM
    C2 Coolant Level
    C3 Coolant Critical Level
    C4 Coolant Pump
    C5 Chassis Enclosure
    C6 Wireless Radio Button
    C7 Wireless Radio LED
    C8 Wireless Radio Slider Switch
    C9 System Display Rotation Lock Button
    CA System Display Rotation Lock Slider Switch
    CB Control Enable
""")

_SIMULATION = _table("""
    00 Undefined
    01 Flight Simulation Device
    02 Automobile Simulation Device
    03 Tank Simulation Device
    04 Spaceship Simulation Device
    05 Submarine Simulation Device
    06 Sailing Simulation Device
    07 Motorcycle Simulation Device
    08 Sports Simulation Device
    09 Airplane Simulation Device
    0A Helicopter Simulation Device
    0B Magic Carpet Simulation Device
    0C Bicycle Simulation Device
    20 Flight Control Stick
    21 Flight Stick
    22 Cyclic Control
    23 Cyclic Trim
    24 Flight Yoke
    25 Track Control
    B0 Aileron
    B1 Aileron Trim
    B2 Anti-Torque Control
    B3 Autopilot Enable
    B4 Chaff Release
    B5 Collective Control
    B6 Dive Brake
    B7 Electronic Countermeasures
    B8 Elevator
    B9 Elevator Trim
    BA Rudder
    BB Throttle
    BC Flight Communications
    BD Flare Release
    BE Landing Gear
    BF Toe Brake
    C0 Trigger
    C1 Weapons Arm
    C2 Weapons Select
    C3 Wing Flaps
    C4 Accelerator
    C5 Brake
    C6 Clutch
    C7 Shifter
    C8 Steering
    C9 Turret Direction
    CA Barrel Elevation
    CB Dive Plane
    CC Ballast
    CD Bicycle Crank
    CE Handle Bars
    CF Front Brake
    D0 Rear Brake
""")

_KEYBOARD = _table("""
    00 Reserved
    01 ErrorRollOver
    02 POSTFail
    03 ErrorUndefined
    28 Return (ENTER)
    29 ESCAPE
    2A DELETE (Backspace)
    2B Tab
    2C Spacebar
    2D - and (underscore)
    2E = and +
    2F [ and {
    30 ] and }
    31 \\ and |
    32 Non-US # and ~
    33 ; and :
    34 ' and "
    35 Grave Accent and Tilde
    36 , and <
    37 . and >
    38 / and ?
    39 Caps Lock
    46 PrintScreen
    47 Scroll Lock
    48 Pause
    49 Insert
    4A Home
    4B PageUp
    4C Delete Forward
    4D End
    4E PageDown
    4F RightArrow
    50 LeftArrow
    51 DownArrow
    52 UpArrow
    53 Keypad Num Lock and Clear
    54 Keypad /
    55 Keypad *
    56 Keypad -
    57 Keypad +
    58 Keypad ENTER
    59 Keypad 1 and End
    5A Keypad 2 and Down Arrow
    5B Keypad 3 and PageDn
    5C Keypad 4 and Left Arrow
    5D Keypad 5
    5E Keypad 6 and Right Arrow
    5F Keypad 7 and Home
    60 Keypad 8 and Up Arrow
    61 Keypad 9 and PageUp
    62 Keypad 0 and Insert
    63 Keypad . and Delete
    64 Non-US \\ and |
    65 Application
    66 Power
    67 Keypad =
    74 Execute
    75 Help
    76 Menu
    77 Select
    78 Stop
    79 Again
    7A Undo
    7B Cut
    7C Copy
    7D Paste
    7E Find
    7F Mute
    80 Volume Up
    81 Volume Down
    82 Locking Caps Lock
    83 Locking Num Lock
    84 Locking Scroll Lock
    85 Keypad Comma
    86 Keypad Equal Sign
    99 Alternate Erase
    9A SysReq/Attention
    9B Cancel
    9C Clear
    9D Prior
    9E Return
    9F Separator
    A0 Out
    A1 Oper
    A2 Clear/Again
    A3 CrSel/Props
    A4 ExSel
    B0 Keypad 00
    B1 Keypad 000
    B2 Thousands Separator
    B3 Decimal Separator
    B4 Currency Unit
    B5 Currency Sub-unit
    B6 Keypad (
    B7 Keypad )
    B8 Keypad {
    B9 Keypad }
    BA Keypad Tab
    BB Keypad Backspace
    BC Keypad A
    BD Keypad B
    BE Keypad C
    BF Keypad D
    C0 Keypad E
    C1 Keypad F
    C2 Keypad XOR
    C3 Keypad ^
    C4 Keypad %
    C5 Keypad <
    C6 Keypad >
    C7 Keypad &
    C8 Keypad &&
    C9 Keypad |
    CA Keypad ||
    CB Keypad :
    CC Keypad #
    CD Keypad Space
    CE Keypad @
    CF Keypad !
    D0 Keypad Memory Store
    D1 Keypad Memory Recall
    D2 Keypad Memory Clear
    D3 Keypad Memory Add
    D4 Keypad Memory Subtract
    D5 Keypad Memory Multiply
    D6 Keypad Memory Divide
    D7 Keypad +/-
    D8 Keypad Clear
    D9 Keypad Clear Entry
    DA Keypad Binary
    DB Keypad Octal
    DC Keypad Decimal
    DD Keypad Hexadecimal
    E0 LeftControl
    E1 LeftShift
    E2 LeftAlt
    E3 Left GUI
    E4 RightControl
    E5 RightShift
    E6 RightAlt
    E7 Right GUI
""")
_KEYBOARD.update({0x04 + i: f"{c} and {c.upper()}" for i, c in enumerate("abcdefghijklmnopqrstuvwxyz")})
_KEYBOARD.update({0x1E + i: f"{d} and {s}" for i, (d, s) in enumerate(zip("1234567890", "!@#$%^&*()", strict=True))})
_KEYBOARD.update({0x3A + i: f"F{i + 1}" for i in range(12)})
_KEYBOARD.update({0x68 + i: f"F{i + 13}" for i in range(12)})
_KEYBOARD.update({0x87 + i: f"International{i + 1}" for i in range(9)})
_KEYBOARD.update({0x90 + i: f"LANG{i + 1}" for i in range(9)})

_LED = _table("""
    00 Undefined
    01 Num Lock
    02 Caps Lock
    03 Scroll Lock
    04 Compose
    05 Kana
    06 Power
    07 Shift
    08 Do Not Disturb
    09 Mute
    0A Tone Enable
    0B High Cut Filter
    0C Low Cut Filter
    0D Equalizer Enable
    0E Sound Field On
    0F Surround On
    10 Repeat
    11 Stereo
    12 Sampling Rate Detect
    13 Spinning
    14 CAV
    15 CLV
    16 Recording Format Detect
    17 Off-Hook
    18 Ring
    19 Message Waiting
    1A Data Mode
    1B Battery Operation
    1C Battery OK
    1D Battery Low
    1E Speaker
    1F Head Set
    20 Hold
    21 Microphone
    22 Coverage
    23 Night Mode
    24 Send Calls
    25 Call Pickup
    26 Conference
    27 Stand-by
    28 Camera On
    29 Camera Off
    2A On-Line
    2B Off-Line
    2C Busy
    2D Ready
    2E Paper-Out
    2F Paper-Jam
    30 Remote
    31 Forward
    32 Reverse
    33 Stop
    34 Rewind
    35 Fast Forward
    36 Play
    37 Pause
    38 Record
    39 Error
    3A Usage Selected Indicator
    3B Usage In Use Indicator
    3C Usage Multi Mode Indicator
    3D Indicator On
    3E Indicator Flash
    3F Indicator Slow Blink
    40 Indicator Fast Blink
    41 Indicator Off
    42 Flash On Time
    43 Slow Blink On Time
    44 Slow Blink Off Time
    45 Fast Blink On Time
    46 Fast Blink Off Time
    47 Usage Indicator Color
    48 Indicator Red
    49 Indicator Green
    4A Indicator Amber
    4B Generic Indicator
    4C System Suspend
    4D External Power Connected
    4E Indicator Blue
    4F Indicator Orange
    50 Good Status
    51 Warning Status
    52 RGB LED
    53 Red LED Channel
    54 Blue LED Channel
    55 Green LED Channel
    56 LED Intensity
    57 System Microphone Mute
""")

_CONSUMER = _table("""
    00 Undefined
    01 Consumer Control
    02 Numeric Key Pad
    03 Programmable Buttons
    04 Microphone
    05 Headphone
    06 Graphic Equalizer
    20 +10
    21 +100
    22 AM/PM
    30 Power
    31 Reset
    32 Sleep
    33 Sleep After
    34 Sleep Mode
    35 Illumination
    36 Function Buttons
    40 Menu
    41 Menu Pick
    42 Menu Up
    43 Menu Down
    44 Menu Left
    45 Menu Right
    46 Menu Escape
    47 Menu Value Increase
    48 Menu Value Decrease
    60 Data On Screen
    61 Closed Caption
    62 Closed Caption Select
    63 VCR/TV
    64 Broadcast Mode
    65 Snapshot
    66 Still
    6F Display Brightness Increment
    70 Display Brightness Decrement
    72 Display Backlight Toggle
    73 Display Set Brightness to Minimum
    74 Display Set Brightness to Maximum
    75 Display Set Auto Brightness
    80 Selection
    81 Assign Selection
    82 Mode Step
    83 Recall Last
    84 Enter Channel
    85 Order Movie
    86 Channel
    87 Media Selection
    88 Media Select Computer
    89 Media Select TV
    8A Media Select WWW
    8B Media Select DVD
    8C Media Select Telephone
    8D Media Select Program Guide
    8E Media Select Video Phone
    8F Media Select Games
    90 Media Select Messages
    91 Media Select CD
    92 Media Select VCR
    93 Media Select Tuner
    94 Quit
    95 Help
    96 Media Select Tape
    97 Media Select Cable
    98 Media Select Satellite
    99 Media Select Security
    9A Media Select Home
    9B Media Select Call
    9C Channel Increment
    9D Channel Decrement
    9E Media Select SAP
    A0 VCR Plus
    A1 Once
    A2 Daily
    A3 Weekly
    A4 Monthly
    B0 Play
    B1 Pause
    B2 Record
    B3 Fast Forward
    B4 Rewind
    B5 Scan Next Track
    B6 Scan Previous Track
    B7 Stop
    B8 Eject
    B9 Random Play
    BA Select Disc
    BB Enter Disc
    BC Repeat
    BD Tracking
    BE Track Normal
    BF Slow Tracking
    C0 Frame Forward
    C1 Frame Back
    C2 Mark
    C3 Clear Mark
    C4 Repeat From Mark
    C5 Return To Mark
    C6 Search Mark Forward
    C7 Search Mark Backwards
    C8 Counter Reset
    C9 Show Counter
    CA Tracking Increment
    CB Tracking Decrement
    CC Stop/Eject
    CD Play/Pause
    CE Play/Skip
    CF Voice Command
    E0 Volume
    E1 Balance
    E2 Mute
    E3 Bass
    E4 Treble
    E5 Bass Boost
    E6 Surround Mode
    E7 Loudness
    E8 MPX
    E9 Volume Increment
    EA Volume Decrement
    180 Application Launch Buttons
    181 AL Launch Button Configuration Tool
    182 AL Programmable Button Configuration
    183 AL Consumer Control Configuration
    184 AL Word Processor
    185 AL Text Editor
    186 AL Spreadsheet
    187 AL Graphics Editor
    188 AL Presentation App
    189 AL Database App
    18A AL Email Reader
    18B AL Newsreader
    18C AL Voicemail
    18D AL Contacts/Address Book
    18E AL Calendar/Schedule
    18F AL Task/Project Manager
    190 AL Log/Journal/Timecard
    191 AL Checkbook/Finance
    192 AL Calculator
    193 AL A/V Capture/Playback
    194 AL Local Machine Browser
    195 AL LAN/WAN Browser
    196 AL Internet Browser
    19C AL Logoff
    19E AL Terminal Lock/Screensaver
    19F AL Control Panel
    1A6 AL Integrated Help Center
    1A7 AL Documents
    1AB AL Spell Check
    1AE AL Keyboard Layout
    1B1 AL Screen Saver
    1B4 AL File Browser
    1B6 AL Image Browser
    1B7 AL Audio Browser
    1B8 AL Movie Browser
    200 Generic GUI Application Controls
    201 AC New
    202 AC Open
    203 AC Close
    204 AC Exit
    205 AC Maximize
    206 AC Minimize
    207 AC Save
    208 AC Print
    209 AC Properties
    21A AC Undo
    21B AC Copy
    21C AC Cut
    21D AC Paste
    21E AC Select All
    21F AC Find
    220 AC Find and Replace
    221 AC Search
    222 AC Go To
    223 AC Home
    224 AC Back
    225 AC Forward
    226 AC Stop
    227 AC Refresh
    228 AC Previous Link
    229 AC Next Link
    22A AC Bookmarks
    22B AC History
    22C AC Subscriptions
    22D AC Zoom In
    22E AC Zoom Out
    22F AC Zoom
    230 AC Full Screen View
    231 AC Normal View
    232 AC View Toggle
    233 AC Scroll Up
    234 AC Scroll Down
    235 AC Scroll
    236 AC Pan Left
    237 AC Pan Right
    238 AC Pan
    279 AC Redo/Repeat
    289 AC Reply
    28B AC Forward Msg
    28C AC Send
""")

_DIGITIZERS = _table("""
    00 Undefined
    01 Digitizer
    02 Pen
    03 Light Pen
    04 Touch Screen
    05 Touch Pad
    06 Whiteboard
    07 Coordinate Measuring Machine
    08 3D Digitizer
    09 Stereo Plotter
    0A Articulated Arm
    0B Armature
    0C Multiple Point Digitizer
    0D Free Space Wand
    0E Device Configuration
    0F Capacitive Heat Map Digitizer
    20 Stylus
    21 Puck
    22 Finger
    23 Device settings
    24 Character Gesture
    30 Tip Pressure
    31 Barrel Pressure
    32 In Range
    33 Touch
    34 Untouch
    35 Tap
    36 Quality
    37 Data Valid
    38 Transducer Index
    39 Tablet Function Keys
    3A Program Change Keys
    3B Battery Strength
    3C Invert
    3D X Tilt
    3E Y Tilt
    3F Azimuth
    40 Altitude
    41 Twist
    42 Tip Switch
    43 Secondary Tip Switch
    44 Barrel Switch
    45 Eraser
    46 Tablet Pick
    47 Touch Valid
    48 Width
    49 Height
    51 Contact Identifier
    52 Device Mode
    53 Device Identifier
    54 Contact Count
    55 Contact Count Maximum
    56 Scan Time
    57 Surface Switch
    58 Button Switch
    59 Pad Type
    5A Secondary Barrel Switch
    5B Transducer Serial Number
    5C Preferred Color
    5D Preferred Color is Locked
    5E Preferred Line Width
    5F Preferred Line Width is Locked
    60 Latency Mode
    61 Gesture Character Quality
    62 Character Gesture Data Length
    63 Character Gesture Data
    64 Gesture Character Encoding
    65 UTF8 Character Gesture Encoding
    66 UTF16 Little Endian Character Gesture Encoding
    67 UTF16 Big Endian Character Gesture Encoding
    68 UTF32 Little Endian Character Gesture Encoding
    69 UTF32 Big Endian Character Gesture Encoding
    6A Capacitive Heat Map Protocol Vendor ID
    6B Capacitive Heat Map Protocol Version
    6C Capacitive Heat Map Frame Data
    6D Gesture Character Enable
    6E Transducer Serial Number Part 2
    6F No Preferred Color
    70 Preferred Line Style
    71 Preferred Line Style is Locked
    72 Ink
    73 Pencil
    74 Highlighter
    75 Chisel Marker
    76 Brush
    77 No Preference
    80 Digitizer Diagnostic
    81 Digitizer Error
    82 Err Normal Status
    83 Err Transducers Exceeded
    84 Err Full Trans Features Unavailable
    85 Err Charge Low
    90 Transducer Software Info
    91 Transducer Vendor Id
    92 Transducer Product Id
    93 Device Supported Protocols
    94 Transducer Supported Protocols
    95 No Protocol
    96 Wacom AES Protocol
    97 USI Protocol
    98 Microsoft Pen Protocol
    A0 Supported Report Rates
    A1 Report Rate
    A2 Transducer Connected
    A3 Switch Disabled
    A4 Switch Unimplemented
    A5 Transducer Switches
    A6 Transducer Index Selector
    B0 Button Press Threshold
""")

USAGE_NAMES: dict[int, dict[int, str]] = {
    0x01: _GENERIC_DESKTOP, 0x02: _SIMULATION, 0x07: _KEYBOARD, 0x08: _LED, 0x0C: _CONSUMER, 0x0D: _DIGITIZERS,
}
"""Usage names by page, then usage ID (Button and Ordinal are named by number, see :func:`usage_name`)."""


def page_name(page: int) -> str:
    """The name of a usage page (``"Vendor-defined 0xFF00"``, ``"Reserved 0x0013"`` where the HUT has none)."""
    page &= 0xFFFF
    if page in PAGE_NAMES:
        return PAGE_NAMES[page]
    if page in VENDOR_PAGES:
        return f"Vendor-defined 0x{page:04X}"
    return f"Reserved 0x{page:04X}"


def usage_name(usage: int) -> str:
    """The name of a 32-bit usage ``page << 16 | id``: ``"X"``, ``"Button 3"``, ``"Generic Desktop 0x00FF"``."""
    page, uid = usage >> 16 & 0xFFFF, usage & 0xFFFF
    if page == 0x09:
        return f"Button {uid}" if uid else "No Button Pressed"
    if page == 0x0A:
        return f"Instance {uid}" if uid else "Undefined"
    name = USAGE_NAMES.get(page, {}).get(uid)
    return name if name is not None else f"{page_name(page)} 0x{uid:04X}"
