"""DEM 5.3-4 end to end: the assembly-line program (PRE, CHART with XM0, POST) on the twin."""

from __future__ import annotations

from pathlib import Path

from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.discrete import DiscreteInputs, DiscreteOutputs
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.plcmemory import TxtDeclaration
from tests.tsx.dem24.helpers import ASSEMBLY

ROOT = Path(__file__).resolve().parents[3]
ASSEMBLY_PROGRAM = ROOT / "examples" / "dem24_assembly.pl7"


def assembly_plc() -> tuple[Plc, Dem24, DiscreteInputs]:
    plc = Plc("TSX 87")
    dem = plc.insert("TSX DEM 2412", 0, 4)
    det = plc.insert("TSX DET 3212", 0, 2)
    dst = plc.insert("TSX DST 2472", 0, 3)
    assert isinstance(dem, Dem24) and isinstance(det, DiscreteInputs)
    assert isinstance(dst, DiscreteOutputs)
    dst.wire(4, dem.set_sync_input)  # O3,4: the synchronization pulse (L11)
    plc.cw[0:9] = ASSEMBLY
    # DEM 5.3-1: TXT0 CW0 (9), TXT1 reception W0 (117) transmission W117 (2),
    # TXT2 W200 (4), TXT3 W190 (6)
    plc.declare_text_block(0, TxtDeclaration(send=("CW", 0)))
    plc.declare_text_block(1, TxtDeclaration(send=("W", 117), recv=("W", 0)))
    plc.declare_text_block(2, TxtDeclaration(send=("W", 200), send_words=4))
    plc.declare_text_block(3, TxtDeclaration(recv=("W", 190)))
    plc.set_calendar(1994, 7, 15, 18, 5, 33)
    plc.load_program(ASSEMBLY_PROGRAM)
    return plc, dem, det


def press(plc: Plc, det: DiscreteInputs, point: int) -> None:
    det.set_input(point, True)
    plc.advance(0.1)
    det.set_input(point, False)
    plc.advance(0.1)


def stored(plc: Plc) -> list[bytes]:
    count = plc.read("W186") // 15
    words = [plc.read(f"W{1000 + k}") for k in range(15 * count)]
    data = b"".join(w.to_bytes(2, "little") for w in words)
    return [data[30 * k : 30 * k + 30] for k in range(count)]


def test_the_chart_initialises_the_module_then_steps_through_its_phases() -> None:
    plc, dem, det = assembly_plc()
    program = plc.program
    assert program is not None
    assert program.active_steps() == []  # the first CHART activates the initial step
    plc.advance(0.05)
    assert program.active_steps() == ["XM0,0"]  # IN left at once: the module is not in Run
    plc.advance(12.0)
    # XM0: configured (TXT0), to Run, time sent (TXT2), stack purged, then step 0
    assert program.active_steps() == ["0"] and plc.read("X0") == 1
    assert plc.read("IW4,0,C") == 1 and plc.read("IW4,2,D") == 0
    assert dem.timebase.pending is not None  # the time waits for the next pulse
    assert plc.read("OW4,2") == 0 and plc.read("OW4,1,1") == 0
    for point, step, ow2, ow3 in ((0, "1", 0xFF, 0), (1, "2", 0xFFFF, 0), (2, "3", 0xF000, 0xF)):
        press(plc, det, point)
        assert program.active_steps() == [step] and plc.read(f"X{step}") == 1
        assert (plc.read("OW4,2"), plc.read("OW4,3")) == (ow2, ow3)
    det.set_input(4, True)  # T: 3>4 on I2,3.I2,4
    press(plc, det, 3)
    assert program.active_steps() == ["4"] and plc.read("OW4,3") == 0xF
    det.set_input(4, False)
    det.set_input(0, True)  # T: 4>0, held for one master task (else T: 0>1 follows)
    plc.advance(0.01)
    det.set_input(0, False)
    plc.advance(0.05)
    assert program.active_steps() == ["0"] and plc.read("OW4,2") == 0


def test_the_program_sets_the_time_and_stores_the_messages_of_the_stack() -> None:
    plc, dem, det = assembly_plc()
    plc.advance(35.0)  # the first SY7 pulse on O3,4 at 30 s: the period reference
    press(plc, det, 0xB)  # L12: RE(I2,B), the time from SW51..SW56 sent by TXT2
    assert plc.read("W200") == 0x5E07 and plc.read("W201") == 0x0F12  # 94/07, 15 18h
    plc.advance(60.0)  # the pulse at 90 s adopts it
    assert dem.timebase.ready
    before = plc.read("W186")
    press(plc, det, 0)  # step 1: inputs 0..7 logged
    for channel in range(3):
        dem.set_input(channel, True)
        plc.advance(1.0)
        dem.set_input(channel, False)
        plc.advance(1.0)
    plc.advance(1.0)
    assert plc.read("IW4,5") == 0  # read out of the stack by L32 / TXT1
    messages = stored(plc)[before // 15 :]
    assert len(messages) == 6  # on and off of channels 0, 1, 2 (SR0 into W1000(W186))
    first = messages[0]
    assert first[:6] == b"150794" and first[6:10] == b"1807"  # day month year hour min
    # channel number and state (SR0: W180, W181)
    assert [(m[20:22], m[22:24]) for m in messages] == [
        (b"00", b"on"),
        (b"00", b"of"),
        (b"01", b"on"),
        (b"01", b"of"),
        (b"02", b"on"),
        (b"02", b"of"),
    ]
