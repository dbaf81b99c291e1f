"""SDL GameControllerDB mappings: real database lines, SDL's GUID layout, SDL's lookup and its arithmetic."""

from __future__ import annotations

import contextlib
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pixelpen.devices.hid.gamecontrollerdb import (
    MAX_LINE,
    Binding,
    MappingDatabase,
    SdlGuid,
    Source,
    crc16,
    parse_guid,
    parse_mapping,
    sdl_guid,
)
from pixelpen.devices.hid.joystick import JoystickState
from pixelpen.drivers.identity import DeviceId
from pixelpen.errors import ParseError

# Lines copied literally from SDL_GameControllerDB's gamecontrollerdb.txt (mdqinc/SDL_GameControllerDB, 2026).
XBOX_360 = ("030000005e0400008e02000004010000,Microsoft Xbox 360,a:b0,b:b1,back:b6,dpdown:h0.4,dpleft:h0.8,"
            "dpright:h0.2,dpup:h0.1,guide:b8,leftshoulder:b4,leftstick:b9,lefttrigger:a2,leftx:a0,lefty:a1,"
            "rightshoulder:b5,rightstick:b10,righttrigger:a5,rightx:a3,righty:a4,start:b7,x:b2,y:b3,"
            "platform:Linux,")
PS4_8100 = ("030000004c050000c405000000810000,PS4 Controller,a:b0,b:b1,back:b8,dpdown:h0.4,dpleft:h0.8,"
            "dpright:h0.2,dpup:h0.1,guide:b10,leftshoulder:b4,leftstick:b11,lefttrigger:a2,leftx:a0,lefty:a1,"
            "rightshoulder:b5,rightstick:b12,righttrigger:a5,rightx:a3,righty:a4,start:b9,x:b3,y:b2,"
            "platform:Linux,")
PS4_0111 = ("030000004c050000c405000011010000,PS4 Controller,a:b1,b:b2,back:b8,dpdown:h0.4,dpleft:h0.8,"
            "dpright:h0.2,dpup:h0.1,guide:b12,leftshoulder:b4,leftstick:b10,lefttrigger:a3,leftx:a0,lefty:a1,"
            "rightshoulder:b5,rightstick:b11,righttrigger:a4,rightx:a2,righty:a5,start:b9,touchpad:b13,x:b0,"
            "y:b3,platform:Linux,")
NES30 = ("03000000008000000210000011010000,8BitDo NES30,a:b1,b:b2,back:b8,dpdown:+a1,dpleft:-a0,dpright:+a0,"
         "dpup:-a1,leftshoulder:b4,lefttrigger:b6,rightshoulder:b5,righttrigger:b7,start:b9,x:b0,y:b3,"
         "platform:Linux,")
GAMECUBE = ("03000000260900008888000000010000,Cyber Gadget GameCube Controller,a:b0,b:b1,dpdown:h0.4,dpleft:h0.8,"
            "dpright:h0.2,dpup:h0.1,lefttrigger:a4,leftx:a0,lefty:a1,rightshoulder:b6,righttrigger:a5,rightx:a2,"
            "righty:a3~,start:b7,x:b2,y:b3,platform:Linux,")
JOYCON_L = ("030000007e0500000620000000000000,Joy-Con (L),+leftx:h0.2,+lefty:h0.4,-leftx:h0.8,-lefty:h0.1,a:b0,"
            "b:b1,back:b13,leftshoulder:b4,leftstick:b10,rightshoulder:b5,start:b8,x:b2,y:b3,platform:Windows,")
GS_GAMEPAD = ("0500000047532047616d657061640000,GS Gamepad,a:b0,b:b1,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,"
              "dpup:h0.1,guide:b8,leftshoulder:b4,leftstick:b10,lefttrigger:b6,leftx:a0,lefty:a1,rightshoulder:b5,"
              "rightstick:b11,righttrigger:b7,rightx:a2,righty:a3,start:b9,x:b2,y:b3,platform:Linux,")
PS5_ACCESS = ("0300004b4c0500005f0e000011010000,PS5 Access Controller,a:b1,b:b2,back:b8,dpdown:h0.4,dpleft:h0.8,"
              "dpright:h0.2,dpup:h0.1,guide:b12,leftshoulder:b4,leftstick:b10,lefttrigger:a3,leftx:a0,lefty:a1,"
              "misc1:b14,rightshoulder:b5,rightstick:b11,righttrigger:a4,rightx:a2,righty:a5,start:b9,"
              "touchpad:b13,x:b0,y:b3,platform:Linux,")
XINPUT = ("xinput,XInput Controller,a:b0,b:b1,back:b6,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,dpup:h0.1,guide:b8,"
          "leftshoulder:b4,leftstick:b9,lefttrigger:a2,leftx:a0,lefty:a1,rightshoulder:b5,rightstick:b10,"
          "righttrigger:a5,rightx:a3,righty:a4,start:b7,x:b2,y:b3,platform:Linux,")


def state(axes=(), buttons=(), hats=()) -> JoystickState:
    return JoystickState(tuple(axes), tuple(buttons), tuple(hats))


# -- parsing --------------------------------------------------------------------------------------------

def test_xbox_360_line_parses_into_its_bindings():
    m = parse_mapping(XBOX_360)
    assert (m.guid, m.name, m.platform, m.crc) == ("030000005e0400008e02000004010000", "Microsoft Xbox 360",
                                                   "Linux", None)
    bound = {b.target: b.source for b in m.bindings}
    assert bound["a"] == Source("button", 0)
    assert bound["leftx"] == Source("axis", 0)
    assert bound["righttrigger"] == Source("axis", 5)
    assert bound["dpup"] == Source("hat", 0, mask=1)
    assert bound["dpleft"] == Source("hat", 0, mask=8)
    assert len(m.bindings) == 21


def test_half_axis_sources_and_inverted_axes():
    nes = {b.target: b.source for b in parse_mapping(NES30).bindings}
    assert nes["dpdown"] == Source("axis", 1, "+") and nes["dpleft"] == Source("axis", 0, "-")
    cube = {b.target: b.source for b in parse_mapping(GAMECUBE).bindings}
    assert cube["righty"] == Source("axis", 3, inverted=True)
    # SDL_PrivateParseGamepadElement: "~" swaps the input range
    assert cube["righty"].axis_range == (32767, -32768)
    assert nes["dpleft"].axis_range == (0, -32768)


def test_half_axis_targets():
    joycon = parse_mapping(JOYCON_L)
    halves = {(b.half, b.target): b.source for b in joycon.bindings if b.half}
    assert halves == {("+", "leftx"): Source("hat", 0, mask=2), ("+", "lefty"): Source("hat", 0, mask=4),
                      ("-", "leftx"): Source("hat", 0, mask=8), ("-", "lefty"): Source("hat", 0, mask=1)}
    assert joycon.platform == "Windows"


def test_target_names_ignore_case_as_sdl_strcasecmp():
    m = parse_mapping("030000005e0400008e02000004010000,Pad,A:b0,LeftX:a0,+LEFTY:a1,platform:Linux,")
    assert [str(b) for b in m.bindings] == ["a:b0", "leftx:a0", "+lefty:a1"]


def test_special_guid_and_text_round_trip():
    m = parse_mapping(XINPUT)
    assert m.guid == "xinput" and m.guid_info is None
    assert parse_mapping(str(parse_mapping(XBOX_360))) == parse_mapping(XBOX_360)


def test_extra_fields_crc_hint_sdk():
    m = parse_mapping("030000005e0400008e02000004010000,Pad,a:b0,crc:1a2b,hint:!SDL_GAMECONTROLLER_USE_"
                      "BUTTON_LABELS:=1,sdk>=:21,sdk<=:33,platform:Android,")
    assert m.crc == 0x1A2B and (m.sdk_min, m.sdk_max) == (21, 33)
    assert m.hints[0].negated and m.hints[0].name == "SDL_GAMECONTROLLER_USE_BUTTON_LABELS" and m.hints[0].value == "1"


def test_a_crc_inside_the_guid_becomes_the_mapping_crc():
    # bytes 2-3 of this real GUID are 00 4b: SDL moves that CRC to the crc: field (little endian 0x4b00)
    assert parse_mapping(PS5_ACCESS).crc == 0x4B00


@pytest.mark.parametrize(("text", "column", "words"), [
    ("0300000,Pad,a:b0,", 1, "field 1 (GUID)"),
    ("030000005e0400008e02000004010000,Pad,a:b0,q:b1,", 43, "unknown gamepad target 'q'"),
    ("030000005e0400008e02000004010000,Pad,a:x0,", 38, "expected a source"),
    ("030000005e0400008e02000004010000,Pad,a:b0,dpup:h0.16,", 43, "hat mask 16"),
    ("030000005e0400008e02000004010000,Pad,+a:b0,", 38, "applies to axes only"),
    ("030000005e0400008e02000004010000,Pad,a:b0,crc:zz,", 43, "4 hex digits"),
    ("030000005e0400008e02000004010000,Pad,a:b0,platform:Linux,platform:Windows,", 58, "platform given twice"),
    ("030000005e0400008e02000004010000,Pad,a:b99999,", 38, "above"),
    ("030000005e0400008e02000004010000,Pad,ab0,", 38, "expected target:source"),
])
def test_errors_name_the_field_and_its_column(text, column, words):
    with pytest.raises(ParseError) as info:
        parse_mapping(text, source="db.txt", line=7)
    assert words in str(info.value)
    assert info.value.column == column and info.value.line == 7 and info.value.source == "db.txt"


def test_missing_name_and_oversized_lines_are_refused():
    with pytest.raises(ParseError, match="GUID and a name"):
        parse_mapping("030000005e0400008e02000004010000")
    with pytest.raises(ParseError, match="longer than"):
        parse_mapping("030000005e0400008e02000004010000,Pad," + "a:b0," * (MAX_LINE // 5 + 1))


@given(st.text(max_size=120))
def test_arbitrary_text_parses_or_raises_parse_error(text):
    with contextlib.suppress(ParseError):
        parse_mapping(text)


# -- GUIDs ----------------------------------------------------------------------------------------------

def test_crc16_is_crc16_arc():
    # the CRC catalogue's check value of CRC-16/ARC (SDL_crc16): "123456789" -> 0xBB3D
    assert crc16(b"123456789") == 0xBB3D
    assert crc16(b"") == 0


def test_guid_of_a_usb_device_as_sdl_builds_it():
    # SDL_CreateJoystickGUID: LE16 bus 0x0003, CRC 0, LE16 vendor 0x045e, 0, LE16 product 0x028e, 0, LE16 version
    # 0x0104, driver signature 0, data 0 -> the Xbox 360 line's GUID
    xbox = DeviceId("usb", 0x045E, 0x028E, name="Microsoft X-Box 360 pad")
    assert sdl_guid(xbox, version=0x0104, with_crc=False).hex == "030000005e0400008e02000004010000"
    with_crc = sdl_guid(xbox, version=0x0104)
    assert with_crc.crc == crc16(b"Microsoft X-Box 360 pad")
    assert with_crc.to_bytes()[2:4] == with_crc.crc.to_bytes(2, "little")


def test_guid_without_product_id_uses_the_name_form():
    # SDL_CreateJoystickGUID takes the name form unless vendor AND product are known: bus 5 (Bluetooth), CRC,
    # then the name's first 11 bytes NUL-terminated -> the real "GS Gamepad" line's GUID
    pad = DeviceId("bluetooth", 0, 0, name="GS Gamepad")
    assert sdl_guid(pad, with_crc=False).hex == "0500000047532047616d657061640000"
    half_known = DeviceId("bluetooth", 0x1234, 0, name="GS Gamepad")
    assert sdl_guid(half_known, with_crc=False).hex == "0500000047532047616d657061640000"
    long_name = sdl_guid(DeviceId("usb", 0, 0, name="ABCDEFGHIJKLMNOP"), with_crc=False).to_bytes()
    assert long_name[4:] == b"ABCDEFGHIJK\0"
    signed = sdl_guid(DeviceId("usb", 0, 0, name="ABCDEFGHIJKLMNOP"), with_crc=False, driver_signature=ord("h"),
                      driver_data=2).to_bytes()
    assert signed[4:] == b"ABCDEFGHI\0" + b"h\x02"


def test_guid_name_form_keeps_utf8_bytes():
    raw = sdl_guid(DeviceId("usb", 0, 0, name="Manette é"), with_crc=False).to_bytes()
    assert raw[4:] == "Manette é".encode().ljust(12, b"\0")


def test_guid_fields_read_back():
    info = parse_guid("030000004c050000c405000011010000")
    assert (info.bus, info.crc, info.vendor, info.product, info.version) == (3, 0, 0x054C, 0x05C4, 0x0111)
    name_form = parse_guid("0500000047532047616d657061640000")
    assert name_form.name == "GS Gamepad" and name_form.vendor == 0 and name_form.bus == 5
    # a legacy GUID whose first word is not a bus number carries no CRC (SDL_GetJoystickGUIDInfo)
    assert parse_guid("6d6963726f736f66742058626f782033").crc == 0


@given(st.integers(0, 0x1F), st.integers(0, 0xFFFF), st.integers(0, 0xFFFF), st.integers(0, 0xFFFF),
       st.integers(0, 0xFFFF), st.binary(min_size=2, max_size=2))
def test_standard_form_round_trips(bus, crc, vendor, product, version, tail):
    # words: bus, crc, vendor, 0, product, 0, version (little endian), then driver signature and data bytes
    data = struct.pack("<7H", bus, crc, vendor, 0, product, 0, version) + tail
    assert SdlGuid.from_bytes(data).to_bytes() == data


def test_bad_guids_name_the_guid_field():
    for text in ("03000000", "zz" * 16, "0" * 33):
        with pytest.raises(ParseError, match=r"field 1 \(GUID\)"):
            parse_guid(text)


# -- the database ---------------------------------------------------------------------------------------

DB_TEXT = "\n".join(["# Linux", XBOX_360, PS4_8100, PS4_0111, "", NES30, GAMECUBE, GS_GAMEPAD, JOYCON_L,
                     PS5_ACCESS, XINPUT])


def test_database_keeps_only_its_platform():
    linux = MappingDatabase.from_text(DB_TEXT)
    assert len(linux) == 8 and all(m.platform == "Linux" for m in linux)
    assert len(MappingDatabase.from_text(DB_TEXT, platform=None)) == 9


def test_database_errors_name_the_line(tmp_path):
    path = tmp_path / "gamecontrollerdb.txt"
    path.write_text(XBOX_360 + "\n# comment\n030000005e0400008e02000004010000,Pad,a:q1,\n")
    with pytest.raises(ParseError) as info:
        MappingDatabase.read(path)
    assert info.value.line == 3 and info.value.source == str(path)


def test_find_by_exact_guid_then_without_the_version():
    db = MappingDatabase.from_text(DB_TEXT)
    ps4 = DeviceId("usb", 0x054C, 0x05C4, name="Sony Interactive Entertainment Wireless Controller")
    assert db.find(sdl_guid(ps4, version=0x0111)).bindings == parse_mapping(PS4_0111).bindings
    # version 0x0100 is not in the database: SDL retries without the version and takes the first match
    assert db.find(sdl_guid(ps4, version=0x0100)).bindings == parse_mapping(PS4_8100).bindings
    assert db.find("030000004c050000c405000011010000").name == "PS4 Controller"
    assert db.find(sdl_guid(DeviceId("usb", 0x1234, 0x5678))) is None


def test_find_clears_the_device_crc_and_prefers_a_matching_crc_field():
    db = MappingDatabase.from_text(DB_TEXT)
    xbox = DeviceId("usb", 0x045E, 0x028E, name="Microsoft X-Box 360 pad")
    assert db.find(sdl_guid(xbox, version=0x0104)).name == "Microsoft Xbox 360"  # CRC in the GUID, none in the DB
    # the PS5 Access mapping carries CRC 0x4b00: only a device whose name has that CRC gets it
    access = "030000004c0500005f0e000011010000"
    assert db.find(access[:4] + "004b" + access[8:]).name == "PS5 Access Controller"
    assert db.find(access[:4] + "1111" + access[8:]) is None
    db.add(parse_mapping("030000004c0500005f0e000011010000,Generic Access,a:b0,platform:Linux,"))
    assert db.find(access[:4] + "1111" + access[8:]).name == "Generic Access"
    assert db.find(access[:4] + "004b" + access[8:]).name == "PS5 Access Controller"


def test_find_by_name_form_guid():
    db = MappingDatabase.from_text(DB_TEXT)
    assert db.find(sdl_guid(DeviceId("bluetooth", 0, 0, name="GS Gamepad"))).name == "GS Gamepad"


def test_adding_the_same_guid_replaces():
    db = MappingDatabase.from_text(XBOX_360)
    db.add(parse_mapping(XBOX_360.replace("Microsoft Xbox 360", "Renamed")))
    assert len(db) == 1 and db.find("030000005e0400008e02000004010000").name == "Renamed"


def test_oversized_database_file_is_refused(tmp_path, monkeypatch):
    import pixelpen.devices.hid.gamecontrollerdb as gcdb
    monkeypatch.setattr(gcdb, "MAX_DATABASE_BYTES", 100)
    path = tmp_path / "big.txt"
    path.write_text(XBOX_360 * 2)
    with pytest.raises(ParseError, match="larger than 100"):
        MappingDatabase.read(path)


# -- applying a mapping (SDL_gamepad.c HandleJoystickAxis / Button / Hat) -------------------------------------

def test_xbox_mapping_turns_joystick_indices_into_named_outputs():
    m = parse_mapping(XBOX_360)
    # axes: a0 leftx full right, a1 lefty centred, a2 lefttrigger at rest (-1), a5 righttrigger fully pressed
    out = m.apply(state(axes=(1.0, 0.0, -1.0, 0.0, 0.0, 1.0), buttons=(True,) + (False,) * 10, hats=(1 | 2,)))
    assert out.axes["leftx"] == 1.0 and out.axes["lefty"] == 0.0
    # a full-range axis onto a 0..max trigger: (v - min) / (max - min) * 32767
    assert out.axes["lefttrigger"] == 0.0 and out.axes["righttrigger"] == 1.0
    assert out.buttons["a"] and not out.buttons["b"]
    assert out.buttons["dpup"] and out.buttons["dpright"] and not out.buttons["dpdown"]


def test_half_axis_to_buttons_press_beyond_the_middle():
    m = parse_mapping(NES30)
    # +a0 covers 0..32767: threshold 0 + 32767 // 2 = 16383; -a0 covers 0..-32768: threshold -16384
    right = m.apply(state(axes=(16383 / 32767, 0.0)))
    assert right.buttons["dpright"] and not right.buttons["dpleft"]
    assert not m.apply(state(axes=(16382 / 32767, 0.0))).buttons["dpright"]
    left = m.apply(state(axes=(-1.0, -1.0)))
    assert left.buttons["dpleft"] and left.buttons["dpup"] and not left.buttons["dpdown"]


def test_inverted_axis_flips_the_stick():
    m = parse_mapping(GAMECUBE)
    # a3~: input range 32767..-32768 onto -32768..32767: raw +32767 gives -32768 -> -1.0 (clamped)
    assert m.apply(state(axes=(0.0, 0.0, 0.0, 1.0))).axes["righty"] == -1.0
    assert m.apply(state(axes=(0.0, 0.0, 0.0, -1.0))).axes["righty"] == 1.0


def test_hat_to_half_axes():
    m = parse_mapping(JOYCON_L)
    out = m.apply(state(hats=(2,)))
    assert out.axes["leftx"] == 1.0 and out.axes["lefty"] == 0.0
    out = m.apply(state(hats=(8 | 1,)))
    # -leftx's output range is 0..-32768: pressed gives its maximum end, -32768 -> -1.0
    assert out.axes["leftx"] == -1.0 and out.axes["lefty"] == -1.0


def test_button_to_trigger_axis():
    m = parse_mapping(NES30)
    bindings = {b.target: b for b in m.bindings}
    assert bindings["lefttrigger"] == Binding("lefttrigger", Source("button", 6))
    pressed = m.apply(state(axes=(0.0, 0.0), buttons=(False,) * 6 + (True,)))
    assert pressed.axes["lefttrigger"] == 1.0 and pressed.axes["righttrigger"] == 0.0
