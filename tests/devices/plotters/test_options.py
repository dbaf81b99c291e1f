"""The plotter classes' URL options as specs: one table per class, the base's in every family, the sim: split."""

from __future__ import annotations

import pytest

from pixelpen.devices.plotters import base, progress, resume, state
from pixelpen.devices.plotters.axidraw import AxiDrawPlotter
from pixelpen.devices.plotters.base import PlotterDisplay
from pixelpen.devices.plotters.grbl import GrblPlotter
from pixelpen.devices.plotters.hpgl import HP7440A, HP7475A, HP7550A
from pixelpen.errors import URLError
from pixelpen.options import describe
from pixelpen.urls import parse_url

FAMILIES = [HP7475A, HP7550A, HP7440A, GrblPlotter, AxiDrawPlotter]
BASE = ("paper", "baud", "flow", "timeout", "profile", "state")


@pytest.mark.parametrize("cls", FAMILIES, ids=lambda c: c.__name__)
def test_every_family_declares_the_base_options_first_and_each_name_once(cls):
    names = [spec.name for spec in cls.OPTIONS]
    assert tuple(names[: len(BASE)]) == BASE == tuple(s.name for s in PlotterDisplay.OPTIONS)
    assert len(names) == len(set(names))
    assert all(spec.help for spec in cls.OPTIONS)


@pytest.mark.parametrize("cls", FAMILIES, ids=lambda c: c.__name__)
def test_the_help_table_pixelpen_devices_prints_comes_from_the_specs(cls):
    rows = dict(describe(cls.OPTIONS))
    assert list(rows) == [spec.name for spec in cls.OPTIONS]
    assert not hasattr(cls, "url_options")  # the older help table is not kept beside the specs


def test_family_options_and_their_defaults():
    assert {s.name: s.default for s in HP7475A.OPTIONS[len(BASE):]} == {
        "handshake": "escb", "reserve": 128, "sync_strokes": 16, "sync_bytes": 512, "velocity": None, "ps": None,
        "stall": 60.0, "verify": "instruction"}
    assert [s.name for s in GrblPlotter.OPTIONS[len(BASE):]] == [
        "stream", "pen", "pen_up", "pen_down", "dwell", "feed", "rx_buffer", "unlock"]
    assert [s.name for s in AxiDrawPlotter.OPTIONS[len(BASE):]] == ["model", "moves", "pen_up", "pen_down"]


def test_values_are_read_by_the_shared_converters():
    d = HP7475A.from_url(parse_url("hp7475a:/dev/null?handshake=XONXOFF&flow=xonxoff&reserve=0&timeout=2.5&baud=4800"))
    assert (d.handshake, d.reserve, d.timeout, d.baudrate, d.flow) == ("xonxoff", 0, 2.5, 4800, "xonxoff")
    assert AxiDrawPlotter.from_url(parse_url("axidraw:/dev/null?model=SE-A3")).profile.name == \
        AxiDrawPlotter.from_url(parse_url("axidraw:/dev/null?model=se_a3")).profile.name


@pytest.mark.parametrize("query, message", [
    ("baud=fast", "option baud='fast' is not valid"),
    ("timeout=-1", "option timeout='-1' is not valid"),
    ("flow=dtr", "option flow='dtr' is not valid"),
    ("papr=a4", "unknown option.*papr.*did you mean 'paper'"),
])
def test_base_options_are_checked_for_every_family(query, message):
    for cls, scheme in ((HP7475A, "hp7475a"), (GrblPlotter, "grbl"), (AxiDrawPlotter, "axidraw")):
        with pytest.raises(URLError, match=message):
            cls.from_url(parse_url(f"{scheme}:/dev/null?{query}"))


def test_a_sim_url_keeps_paper_for_both_and_gives_the_transport_baud_and_flow():
    d = HP7475A.from_url(parse_url("sim:hp7475a?paper=a3&baud=2400&flow=xonxoff&handshake=xonxoff&speed=fast"))
    sim = parse_url(d.port)
    assert d.paper.name == "a3" and d.baudrate != 2400
    assert (sim.target, dict(sim.options)) == ("//hp7475a", {"paper": "a3", "baud": "2400", "flow": "xonxoff",
                                                             "speed": "fast"})


def test_the_moved_names_still_import_from_base():
    assert base.DeviceWhere is resume.DeviceWhere and base.locate is resume.locate
    assert base.ResumePoint is resume.ResumePoint
    assert base.PlotState is state.PlotState and base.fingerprint is state.fingerprint
    assert base.PlotProgress is progress.PlotProgress
    assert all(hasattr(base, name) for name in base.__all__)
