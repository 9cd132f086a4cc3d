"""Instructions per unit of work: a measure that does not wobble with the machine's load.

Time ratios on a shared machine swing by 20-40 % with what else runs; the number of
instructions a fixed workload executes hardly moves.  A benchmark's ``--counts``
runs its own fixed workload (``--workload N``, in a fresh process) twice, at two
sizes, under a counter, and prints the difference per unit of work (a simulated
second, an edge, a request): start-up, imports and the plant's construction cancel
out.

The counter: ``perf stat -e instructions:u`` where the kernel lets this process read
the hardware counters; else valgrind's callgrind (every instruction of the process,
about 50 times slower); the output says which.  Neither installed:
``apt-get install linux-perf valgrind`` (Debian).  A workload prints its units of
work as its last line, ``units <n>``.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from functools import cache
from pathlib import Path

TIMEOUT_S = 1800  # one counted workload (callgrind is slow)


@dataclass(frozen=True, slots=True)
class Counted:
    instructions: int
    units: float


@dataclass(frozen=True, slots=True)
class PerUnit:
    instructions: float  # per unit of work
    unit: str
    tool: str  # "perf" or "callgrind"
    small: Counted
    large: Counted

    def __str__(self) -> str:
        return (
            f"{self.instructions:,.0f} instructions per {self.unit} ({self.tool}; "
            f"{self.large.units:,.0f} against {self.small.units:,.0f} {self.unit}s of work)"
        )


@cache
def tool() -> str:
    """``perf`` if it counts instructions here, else ``callgrind``."""
    perf = shutil.which("perf")
    if perf is not None:
        probe = subprocess.run(
            [perf, "stat", "-x,", "-e", "instructions:u", "true"],
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )
        if probe.returncode == 0 and _perf_count(probe.stderr) is not None:
            return "perf"
    if shutil.which("valgrind") is not None:
        return "callgrind"
    raise SystemExit(
        "--counts: neither perf with hardware counters nor valgrind is available "
        "(Debian: apt-get install linux-perf valgrind)"
    )


def _perf_count(stderr: str) -> int | None:
    for line in stderr.splitlines():
        fields = line.split(",")
        if len(fields) > 2 and fields[2].startswith("instructions") and fields[0].isdigit():
            return int(fields[0])
    return None


def count(argv: list[str]) -> Counted:
    """The instructions ``argv`` executes (user space) and the units it printed."""
    if tool() == "perf":
        command = ["perf", "stat", "--no-inherit", "-x,", "-e", "instructions:u", "--", *argv]
    else:
        command = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *argv]
    done = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT_S, check=False)
    if done.returncode != 0:
        raise SystemExit(f"--counts: {' '.join(argv)} failed:\n{done.stdout}{done.stderr}")
    if tool() == "perf":
        instructions = _perf_count(done.stderr)
    else:
        match = re.search(r"Collected : (\d+)", done.stderr)
        instructions = int(match.group(1)) if match else None
    lines = done.stdout.strip().splitlines()
    if instructions is None or not lines or not lines[-1].startswith("units "):
        raise SystemExit(f"--counts: no count in the output of {' '.join(argv)}:\n{done.stderr}")
    return Counted(instructions, float(lines[-1].split()[1]))


def per_unit(script: str | Path, small: int, large: int, unit: str, *extra: str) -> PerUnit:
    """Run ``script --workload small`` and ``--workload large`` under the counter; the
    instructions of the difference per unit of the difference."""
    base = [sys.executable, str(script), *extra, "--workload"]
    a, b = count([*base, str(small)]), count([*base, str(large)])
    if b.units <= a.units:
        raise SystemExit(f"--counts: the larger workload did no more work ({a} / {b})")
    return PerUnit((b.instructions - a.instructions) / (b.units - a.units), unit, tool(), a, b)
