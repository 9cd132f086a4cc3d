"""Running the real `fieldtwin run --record` in a subprocess, and replaying what it wrote."""

from __future__ import annotations

import os
import re
import select
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_PLANT = ROOT / "src" / "fieldtwin" / "plants" / "default.toml"
ANNOUNCE_S = 30.0  # the longest the run may take to announce its endpoints


@dataclass
class Run:
    proc: subprocess.Popen[str]
    tcp: list[int] = field(default_factory=list)  # modbus-tcp ports
    rtu_ptys: list[str] = field(default_factory=list)  # modbus-rtu lines on a pty
    scm_ptys: list[str] = field(default_factory=list)  # SCM channels on a pty
    control: str | None = None
    lines: list[str] = field(default_factory=list)

    def stop(self) -> str:
        """SIGTERM, then the rest of its output (bounded)."""
        self.proc.terminate()
        try:
            out, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate(timeout=5)
        assert self.proc.returncode == 0, f"{out}\n{err}"
        return "\n".join(self.lines) + "\n" + out + err


def fieldtwin(*argv: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def start(plant: Path, record: Path, *extra: str, control: bool = False) -> Run:
    argv = ["run", str(plant), "--no-live", "--record", str(record), *extra]
    argv += ["--control-port", "0"] if control else ["--no-control"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    run = Run(proc)
    assert proc.stdout is not None
    fd = proc.stdout.fileno()  # read raw: a text file's buffer would hide lines from select
    deadline = time.monotonic() + ANNOUNCE_S
    pending = b""
    while time.monotonic() < deadline:
        if not select.select([fd], [], [], 0.5)[0]:
            continue
        chunk = os.read(fd, 65536)
        if not chunk:
            break
        pending += chunk
        *complete, pending = pending.split(b"\n")
        for raw in complete:
            line = raw.decode("utf-8", "replace")
            run.lines.append(line)
            if m := re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+)", line):
                run.tcp.append(int(m.group(1)))
            elif m := re.match(r"listening: modbus-rtu pty (\S+)", line):
                run.rtu_ptys.append(m.group(1))
            elif m := re.match(r"listening: TSX SCM .* pty (\S+)", line):
                run.scm_ptys.append(m.group(1))
            elif m := re.match(r"control: (\S+)", line):
                run.control = m.group(1)
            if (line.startswith("running ") and not control) or run.control is not None:
                return run
    proc.kill()
    out, err = proc.communicate(timeout=5)
    raise AssertionError(f"the run did not start:\n{''.join(run.lines)}{out}\n{err}")


def free_port_plant(source: Path, target: Path) -> Path:
    """The plant file with its fixed TCP ports made 0 (any free port)."""
    text = re.sub(r"tcp://127\.0\.0\.1:\d+", "tcp://127.0.0.1:0", source.read_text("utf-8"))
    target.write_text(text, "utf-8")
    return target
