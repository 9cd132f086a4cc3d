"""The AEM 811 through the real console: `python -m fieldtwin console PLANT --script FILE`.

A plant with the AEM alone (no real endpoint, so simulated time runs at full speed).
The script configures the module by Text Block, sets inputs and a signal, writes
thresholds, cuts wires with `fault 5 open_0 on` and reads what docs/console.md and
docs/aem811.md say it shows.  Timing: period 24 x 100 ms (continuity test on
channel 1), Run R at about 10.1 s, cycles at R + k x 2.4 s, each read made once a
cycle is complete (R + 3.8, R + 6.2, R + 8.6 s): 0.6 s of margin either side.
Channels 4..7 are inhibited, so IWxy,3..5 always show channels 0..2.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

PLANT = """\
[plc]
model = "TSX 87"
scan_ms = 10

[[module]]
type = "TSX AEM 811"
rack = 0
slot = 5
code = 648
quantize = false
"""

SCRIPT = """\
# AEM 811 through the console
advance 10.05
read IW5,0,3 IW5,2,D
exchange H'0563' H'40' send H'00A0' 24 H'00C0' H'80C0' 10000 0 H'00C1' H'20A1'
read IW5,0,B IW5,2,D
write OW5,1 H'00F0'
write OW5,0,C 1
input 5 0 12mA
input 5 1 2.5V
signal 5 2 step before=1 after=7 at_s=13
exchange H'0500' 2 send 4000 2000 4000 0 0 0 0 0
advance 3.7
read IW5,3 IW5,4 IW5,5 IW5,2 I5,0 I5,1 I5,2 IW5,1
exchange H'0500' 1 recv 16
fault 5 open_0 on
input 5 1 open
advance 2.4
read IW5,3 IW5,4 IW5,5 I5,2 IW5,1 IW5,0,7 IW5,0,4 I5,S
exchange H'0563' H'47' recv 8
status 5
fault 5 open_0 off
input 5 1 2.5V
advance 2.4
read IW5,1 IW5,0,7 IW5,0,4 IW5,3
"""


def console(tmp_path: Path, script: str) -> subprocess.CompletedProcess[str]:
    plant = tmp_path / "aem.toml"
    plant.write_text(PLANT)
    path = tmp_path / "script.txt"
    path.write_text(script)
    command = [sys.executable, "-m", "fieldtwin", "console", str(plant)]
    return subprocess.run(
        [*command, "--speed", "max", "--script", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )


def test_console_drives_the_aem(tmp_path: Path) -> None:
    done = console(tmp_path, SCRIPT)
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stdout.splitlines() if not line.startswith("t = ")]
    assert lines[:11] == [
        "IW5,0,3 = 1",
        "IW5,2,D = 1",  # AEM 3.3: default configuration
        "TXT0,V = H'00FE'  TXT0,S = 0  TXT0,E = 0",  # AEM 3.4-2: accepted in Stop
        "IW5,0,B = 0",
        "IW5,2,D = 0",
        "OW5,1 = H'00F0'",
        "OW5,0,C = 1",
        "input 5 0 = 12mA",
        "input 5 1 = 2.5V",
        "signal 5 2 = step",
        "TXT0,V = H'00FE'  TXT0,S = 0  TXT0,E = 0",  # AEM 4.3-1: once compared
    ]
    # cycle 2: 12 mA on 4/20 mA user 0..10000 -> 5000; 2.5 V and 1 V in mV
    assert lines[11:21] == [
        "IW5,3 = H'1388'",
        "IW5,4 = H'09C4'",
        "IW5,5 = H'03E8'",
        "IW5,2 = H'0000'",  # channels 4..7 inhibited: 0..3 in the registers
        "I5,0 = 1",  # 5000 >= 4000 + 26
        "I5,1 = 1",  # 2500 >= 2000 + 25
        "I5,2 = 0",  # 1000 < 4000 + 50
        "IW5,1 = H'00F0'",  # inhibit bits mirrored, no channel fault
        "TXT0,V = H'0081'  TXT0,S = 16  TXT0,E = 0",  # AEM 4.2-1 read measurements
        "data = H'1388' H'09C4' H'03E8' H'0000' H'0000' H'0000' H'0000' H'0000'",
    ]
    # cycle 3: 4/20 mA line cut -> ELL (-200); open voltage input -> EHL, continuity
    assert lines[22:32] == [
        "fault 5 open_0 on",
        "input 5 1 = open",
        "IW5,3 = H'FF38'",
        "IW5,4 = H'2AF8'",
        "IW5,5 = H'1B58'",  # 7000: the step at 13 s
        "I5,2 = 1",
        "IW5,1 = H'03F0'",  # IWxy,1,8 and 9: channel faults
        "IW5,0,7 = 1",
        "IW5,0,4 = 1",
        "I5,S = 0",  # application faults do not set Ixy,S
    ]
    # fault bit string: bit 32 (channel 0 ELL) and 37 (channel 1 continuity)
    assert lines[32:34] == [
        "TXT0,V = H'0077'  TXT0,S = 8  TXT0,E = 0",
        "data = H'0000' H'0000' H'0021' H'0000'",
    ]
    assert "leds: OK=on ERR=on F=off" in lines and "mode: Run" in lines
    assert "sampling: normal, period 24 x 100 ms" in lines
    channel_lines = [line for line in lines if line.startswith("channel ")]
    assert channel_lines[0].startswith("channel 0: 4/20 mA, user 0..10000; = -200;")
    assert channel_lines[0].endswith("FAULT ELL")
    assert channel_lines[1].startswith("channel 1: 0/10 V, input range, continuity test; = 11000;")
    assert channel_lines[1].endswith("FAULT continuity")
    assert (
        channel_lines[4] == "channel 4: -10/+10 V, input range; inhibited; thresholds 0/0 bits 00"
    )
    # read while present: the memorised bits go when the faults end (AEM 4.4-1)
    assert lines[-6:] == [
        "fault 5 open_0 off",
        "input 5 1 = 2.5V",
        "IW5,1 = H'00F0'",
        "IW5,0,7 = 0",
        "IW5,0,4 = 0",
        "IW5,3 = H'1388'",
    ]


def test_console_mistakes_stop_the_script_naming_the_line(tmp_path: Path) -> None:
    done = console(tmp_path, "advance 10.1\ninput 5 9 1V\n")
    assert done.returncode == 2
    assert "script.txt:2: input 5 9 1V:" in done.stderr
    assert "0..7" in done.stderr
    done = console(tmp_path, "fault 5 smoke on\n")
    assert done.returncode == 2 and "unknown fault 'smoke'" in done.stderr
    assert "open_0" in done.stderr
    done = console(tmp_path, "input 5 0 2.5volts\n")
    assert done.returncode == 2 and "allowed" in done.stderr
