"""The options of a simulated line: one OptionSpec each, read and split off a sim:// URL's options."""

from __future__ import annotations

import pytest

from pixelpen.clock import SimulatedClock
from pixelpen.errors import URLError
from pixelpen.options import OptionSpec, describe
from pixelpen.sim.base import Fault
from pixelpen.sim.transports import port
from pixelpen.sim.transports.options import DEVICE_FAULTS, TRANSPORT_OPTIONS, Faults, split_options


def test_every_transport_option_is_one_spec_with_help_and_the_documented_default():
    assert all(isinstance(spec, OptionSpec) and spec.help for spec in TRANSPORT_OPTIONS)
    defaults = {spec.name: spec.default for spec in TRANSPORT_OPTIONS}
    assert defaults == {
        "baud": None, "flow": "none", "speed": "real", "tx_buffer": 4096, "out": None,
        "drop_after": None, "stall_after": None, "corrupt_at": None,
        "power_loss_after": None, "paper_lever_after": None, "pause_after": None,
    }
    assert {f for f in Faults.__dataclass_fields__} <= set(defaults)
    assert [name for name, _ in describe(TRANSPORT_OPTIONS)] == list(defaults)


def test_device_faults_are_fault_members_and_fire_in_count_order():
    assert set(DEVICE_FAULTS.values()) == {Fault.POWER_LOSS, Fault.PAPER_LEVER, Fault.PAUSE_BUTTON}
    assert Faults(pause_after=5, power_loss_after=2).device_faults() == [(2, Fault.POWER_LOSS), (5, Fault.PAUSE_BUTTON)]
    both = Faults(pause_after=3, paper_lever_after=3).device_faults()
    assert both == [(3, Fault.PAPER_LEVER), (3, Fault.PAUSE_BUTTON)]


def test_the_old_import_place_still_works():
    assert port.split_options is split_options and port.TRANSPORT_OPTIONS is TRANSPORT_OPTIONS


def test_unknown_names_are_left_for_the_simulator_and_bad_values_name_the_url():
    transport, rest = split_options({"papr": "a4", "flow": "xonxoff"}, "sim://echo")
    assert rest == {"papr": "a4"} and transport.flow == "xonxoff"
    with pytest.raises(URLError, match=r"^sim://echo: option tx_buffer='0' is not valid: expected an integer >= 1$"):
        split_options({"tx_buffer": "0"}, "sim://echo")


def test_split_options_separates_transport_and_device_options():
    transport, rest = split_options(
        {"baud": "19200", "flow": "RTSCTS", "speed": "fast", "drop_after": "7", "paper": "a4", "pens": "6"}
    )
    assert (transport.baud, transport.flow, transport.speed) == (19200, "rtscts", "fast")
    assert transport.faults.drop_after == 7
    assert rest == {"paper": "a4", "pens": "6"}
    assert isinstance(transport.make_clock(), SimulatedClock)


@pytest.mark.parametrize(
    "options, word",
    [
        ({"baud": "fast"}, "baud"),
        ({"baud": "0"}, "baud"),
        ({"flow": "dtr"}, "flow"),
        ({"speed": "warp"}, "speed"),
        ({"drop_after": "-1"}, "drop_after"),
        ({"corrupt_at": "x"}, "corrupt_at"),
    ],
)
def test_bad_transport_options_name_the_option(options, word):
    with pytest.raises(URLError, match=word):
        split_options(options, "sim://echo")


@pytest.mark.parametrize("name", ["sheet.jpg", "sheet", "sheet.png.txt"])
def test_out_must_name_a_png_or_svg_file(name):
    with pytest.raises(URLError, match="out="):
        split_options({"out": name}, "sim://grbl")
