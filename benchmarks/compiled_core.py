"""Would a compiled core pay?  The Modbus request path counted in pure Python and with
its hottest modules compiled by mypyc (issue 25 item 5; docs/decisions.md, "A compiled
core: not now").

The script copies ``src/`` to a temporary directory, compiles there, with mypyc, the
modules a TES read goes through (``HOT``: the TCP session and the TES's access,
digital, execute and state modules), and counts, in both trees, the instructions of
one request in a TCP session alone (no sockets: ``TcpSession.receive`` and ``poll``
with a TES 32EST, slave 1) for the requests a SCADA makes: FC03 of words 0..9 (status,
memorized and filtered inputs), FC03 and FC16 of ten words at 37.  Nothing in the
project is compiled or changed; the copy is removed at the end.

    .venv/bin/python benchmarks/compiled_core.py [--modules extra/module.py ...]

Needs a C compiler and the Python headers (mypyc comes with mypy, a dev dependency)
and valgrind (or perf with hardware counters: benchmarks/counts.py).  About two
minutes: most of it is the compilation.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from counts import PerUnit, per_unit

SRC = Path(__file__).resolve().parent.parent / "src"
HOT = (
    "fieldtwin/modbus/session.py",
    "fieldtwin/tes/access.py",
    "fieldtwin/tes/digital.py",
    "fieldtwin/tes/execute.py",
    "fieldtwin/tes/state.py",
)
REQUESTS = {  # what is counted: an MBAP frame, slave 1
    "FC03 0..9": "00010000000601030000000a",
    "FC03 37..46": "00010000000601030025000a",
    "FC16 37..46": "00010000001b01100025000a14" + "0001" * 10,
}
SMALL, LARGE = 500, 1500  # requests per counted run


def workload(requests: int, frame_hex: str, compiled: bool) -> None:
    from fieldtwin.clock import SimClock
    from fieldtwin.modbus.session import TcpSession
    from fieldtwin.tes import Tes

    clock = SimClock()
    session = TcpSession([Tes("32EST", 1, clock=clock)])
    frame = bytes.fromhex(frame_hex)
    for _ in range(requests):
        session.receive(frame, clock.now)
        session.poll(clock.now)
    import fieldtwin.modbus.session as where

    if str(where.__file__).endswith(".so") != compiled:  # counted the other tree: say so
        raise SystemExit(
            f"expected the {'compiled' if compiled else 'pure'} core: {where.__file__}"
        )
    print(f"units {requests}")


def compile_copy(tmp: Path, modules: list[str]) -> Path:
    tree = tmp / "src"
    shutil.copytree(SRC, tree, ignore=shutil.ignore_patterns("__pycache__", "*.so"))
    mypyc = Path(sys.executable).with_name("mypyc")
    done = subprocess.run(
        [str(mypyc), *modules], cwd=tree, capture_output=True, text=True, timeout=1800
    )
    if done.returncode != 0:
        raise SystemExit(f"mypyc failed:\n{done.stdout[-3000:]}{done.stderr[-3000:]}")
    return tree


def counted(tree: Path | None, frame_hex: str) -> PerUnit:
    env = os.environ.pop("PYTHONPATH", None)
    try:
        if tree is not None:
            os.environ["PYTHONPATH"] = str(tree)
        compiled = "yes" if tree is not None else "no"
        return per_unit(
            __file__, SMALL, LARGE, "request", "--frame", frame_hex, "--compiled", compiled
        )
    finally:
        os.environ.pop("PYTHONPATH", None)
        if env is not None:
            os.environ["PYTHONPATH"] = env


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--modules", nargs="*", default=[], help="more modules to compile")
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--frame", help=argparse.SUPPRESS)
    parser.add_argument("--compiled", choices=("yes", "no"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.workload is not None:
        workload(args.workload, args.frame, args.compiled == "yes")
        return
    modules = [*HOT, *args.modules]
    with tempfile.TemporaryDirectory(prefix="fieldtwin-mypyc-") as tmp:
        print(f"compiling {len(modules)} modules with mypyc ...", flush=True)
        tree = compile_copy(Path(tmp), modules)
        print(f"{'request':<14}{'pure Python':>14}{'compiled':>14}{'change':>9}")
        for name, frame in REQUESTS.items():
            pure, native = counted(None, frame), counted(tree, frame)
            change = native.instructions / pure.instructions - 1
            print(
                f"{name:<14}{pure.instructions:>14,.0f}{native.instructions:>14,.0f}"
                f"{change:>+9.1%}",
                flush=True,
            )
        print(f"instructions per request in a TCP session alone ({pure.tool})")


if __name__ == "__main__":
    main()
