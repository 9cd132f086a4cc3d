"""End to end through the real command: `python -m fieldtwin console PLANT --speed max --script`.

A DEM 2412 in slot 4 of a plant file, with a 30 s pulse clock, the 15 July 1994 time
and T-SYN = 30 s; the script drives inputs and faults and exchanges requests 1, 2 and
H'47' as a PLC program would, and the documented outputs are checked line by line.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

PLANT = """\
[plc]
model = "TSX 87"
scan_ms = 10

[[module]]
type = "TSX DEM 2412"
slot = 4
sync = { period_s = 30 }
time = "1994-07-15T18:05:33"
time_indicator = 1
config = [0, 0, 0, 0, 0, 0, 30, 2, 0]
"""

SCRIPT = """\
write OW4,0,C 1
write OW4,2 H'FFFF'
advance 61
read I4,0 IW4,2,7 IW4,5
input 4 3 on
advance 1234ms
input 4 3 4.5V
advance 10ms
read IW4,6 IW4,5 I4,1
exchange H'0400' 1 send 7 9 recv 234
exchange H'0400' 1 send 8 9 recv 234
fault 4 terminal_block on
advance 50ms
read IW4,0,A IW4,0,C IW4,0,6 I4,S
fault 4 terminal_block off
advance 50ms
read IW4,0,A IW4,0,C
exchange H'0463' H'47' recv 12
exchange H'0400' 1 send 9 9 recv 234
exchange H'0400' 2 send H'5E07' H'0F12' H'0521' H'0002' length 0
exchange H'0400' 2 send H'5E07' H'0F12' H'0630' H'0002'
advance 30
exchange H'0400' 1 send 10 9 recv 234
"""

ZEROS5 = " H'0000' H'0000' H'0000' H'0000' H'0000'"


def message(head: str, word1: str, min_s: str, ms: str, word7: str) -> str:
    """13 words of DEM 4.2-2 for 15 July 1994, 18 h, rack 0 slot 4."""
    return f"{head} {word1} H'5E07' H'0F12' {min_s} {ms} H'0004' {word7}" + ZEROS5


def run(tmp_path: Path) -> list[str]:
    (tmp_path / "plant.toml").write_text(PLANT)
    (tmp_path / "script.txt").write_text(SCRIPT)
    plant, script = str(tmp_path / "plant.toml"), str(tmp_path / "script.txt")
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "console", plant, "--speed", "max", "--script", script],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()


def test_console_script_drives_inputs_faults_and_requests_1_2_47(tmp_path: Path) -> None:
    out = run(tmp_path)
    data = [line for line in out if line.startswith("data = ")]
    reports = [line for line in out if line.startswith("TXT0,")]
    # self-test 10 s; pulses at 30 s (period reference, 2.3-1) and 60 s: the time taken
    # is 18:05:33 rounded up to the 30 s pulse, plus one period: 18:06:30 (4.1-3)
    assert out[3:6] == ["I4,0 = 1", "IW4,2,7 = 1", "IW4,5 = H'0001'"]
    assert out[10:13] == ["IW4,6 = H'0000'", "IW4,5 = H'0003'", "I4,1 = 1"]
    # request 1, exchange 7: overall state (type 1) at 18:06:30.000, channel 3 on at
    # 18:06:31.000, off (4.5 V <= 5 V, type 1) at 18:06:32.234; S = 3 x 26 (4.2-3)
    assert reports[0] == "TXT0,V = H'0081'  TXT0,S = 78  TXT0,E = 0"
    assert data[0] == "data = " + " ".join(
        [
            message("H'0307'", "H'0401'", "H'061E'", "H'0000'", "H'FFFF'"),
            message("H'0307'", "H'0001'", "H'061F'", "H'0000'", "H'0301'"),
            message("H'0307'", "H'0001'", "H'0620'", "H'00EA'", "H'0300'"),
        ]
    )
    # empty stack: S = 2, zero messages and the exchange number (4.2-3)
    assert reports[1] == "TXT0,V = H'0081'  TXT0,S = 2  TXT0,E = 0"
    assert data[1] == "data = H'0008'"
    # terminal block out: IWxy,0,A, STOP (2.5-6), module fault (4.3)
    i = out.index("fault 4 terminal_block on")
    assert out[i + 2 : i + 6] == ["IW4,0,A = 1", "IW4,0,C = 0", "IW4,0,6 = 1", "I4,S = 1"]
    assert out[i + 8 : i + 10] == ["IW4,0,A = 0", "IW4,0,C = 1"]
    # fault string H'47': 12 bytes, bit 16 (terminal block) memorised
    assert reports[2] == "TXT0,V = H'0077'  TXT0,S = 12  TXT0,E = 0"
    assert data[2] == "data = H'0000' H'0001' H'0000' H'0000' H'0000' H'0000'"
    # channel 25 at 1 then 0 (AMB-DEM-19), stamped when the block went and came back
    assert data[3] == "data = " + " ".join(
        [
            message("H'0209'", "H'0001'", "H'0620'", "H'0118'", "H'1901'"),
            message("H'0209'", "H'0001'", "H'0620'", "H'014A'", "H'1900'"),
        ]
    )
    # request 2 with TXTi,L = 0 (the 5.3-4 listing, AMB-DEM-15): no table, refused;
    # with 8 bytes accepted; 18:06:48 (H'0630' is 6 min 48 s) is taken at the 90 s pulse
    # rounded up to 18:07:00, indicator 2, and logged as an overall-state message
    assert reports[4] == "TXT0,V = H'00FD'  TXT0,S = 0  TXT0,E = 0"
    assert reports[5] == "TXT0,V = H'00FE'  TXT0,S = 0  TXT0,E = 0"
    assert data[4] == "data = " + message("H'010A'", "H'0402'", "H'0700'", "H'0000'", "H'FFFF'")
