"""The UART model (SCM 3.2 formats and timing) and the plant-file keys of an SCM."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.charformat import CharFormat, Parity
from fieldtwin.devices.scm.status import lines as status_lines
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.tsx.scm.line import ALLOWED_FRAMES, decode_stream

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "scm.toml"
# the eight formats of SCM 3.2, at 9600 baud
FORMATS = [CharFormat(9600, int(f[0]), Parity(f[1]), int(f[2])) for f in sorted(ALLOWED_FRAMES)]


@given(st.binary(min_size=1, max_size=40), st.sampled_from(FORMATS))
def test_same_format_reads_back_exactly(data: bytes, fmt: CharFormat) -> None:
    chars = decode_stream(data, fmt, fmt)
    assert bytes(c.value for c in chars) == bytes(b & fmt.mask for b in data)
    assert not any(c.parity_error or c.format_error for c in chars)
    assert chars[-1].offset_us == round(len(data) * fmt.bits * 1e6 / 9600)


@given(st.binary(min_size=1, max_size=20), st.sampled_from(FORMATS), st.sampled_from(FORMATS))
def test_any_pair_of_formats_decodes_without_crashing(
    data: bytes, sender: CharFormat, receiver: CharFormat
) -> None:
    chars = decode_stream(data, sender, receiver)
    assert all(0 <= c.value <= receiver.mask for c in chars)


def test_7e1_sender_to_8n1_receiver_gets_the_parity_bit_as_bit_7() -> None:
    chars = decode_stream(b"A", CharFormat(9600, 7, Parity.EVEN, 1), CharFormat(9600, 8))
    assert [c.value for c in chars] == [0x41]  # 'A' has an even number of 1s: parity bit 0
    chars = decode_stream(b"C", CharFormat(9600, 7, Parity.EVEN, 1), CharFormat(9600, 8))
    assert [c.value for c in chars] == [0xC3]


def test_character_times() -> None:
    assert CharFormat(9600, 8, Parity.NONE, 2).char_time_us == 1146  # 11 bits
    assert CharFormat(75, 7, Parity.EVEN, 1).char_time_us == 133_333  # 10 bits


def test_example_plant_wires_a_pty_and_configures_channel_0() -> None:
    plant = load_plant(EXAMPLE)
    assert plant.plc is not None
    mod = plant.plc.module(0, 7)
    assert (
        mod.ports[0].path.startswith("/dev/")
        and mod.ports[0].path in status_lines(mod)["channel 0"]
    )
    assert mod.configs[0].baud == 9600 and mod.configs[1].full_duplex  # kept through self-test
    mod.detach(0)
    plant.plc.advance(1.1)  # unpaced again once the pty is gone
    assert plant.plc.read("IW7,1,3") == 1 and plant.plc.read("IW7,1,B") == 1


def test_plant_errors_name_the_field(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[[module]]\ntype = "TSX SCM 2011"\nslot = 3\n'
        "channels = [{ channel = 0, config = [\"H'0702'\", \"H'9600'\", 0, 0, 0, 0, 0, 0] }]\n"
    )
    with pytest.raises(ConfigError, match=r"module\[0\]\.channels\[0\]\.config"):
        load_plant(bad)
    bad.write_text('[[module]]\ntype = "TSX SCM 2011"\nslot = 3\nwires = 1\n')
    with pytest.raises(ConfigError, match="wires"):
        load_plant(bad)
    bad.write_text('[[module]]\ntype = "TSX SCM 2011"\nslot = 3\nfaults = ["loopback_ch0"]\n')
    plc = load_plant(bad).plc
    assert plc is not None
    plc.advance(1.1)
    assert plc.read("IW3,0,6") == 1
