"""``python -m fieldtwin.control.watch URL [--kind K] [--device D] [--count N]``.

Prints the event stream of a running plant, one JSON object a line (what
``websocat ws://HOST:PORT/events`` would show), until ``--count`` events or
``--idle`` seconds without one.  Once subscribed it says so on standard error
(``subscribed: URL``): what is published after that line reaches it.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from fieldtwin.control.client import Client, ControlError


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fieldtwin.control.watch")
    parser.add_argument("url", help="the control API, e.g. http://127.0.0.1:8520")
    parser.add_argument("--kind", action="append", default=[], help="only this kind")
    parser.add_argument("--device", action="append", default=[], help="only this device")
    parser.add_argument("--count", type=int, default=0, help="stop after N events (0: never)")
    parser.add_argument("--idle", type=float, default=None, help="stop after S s without one")
    parser.add_argument("--token", help="the control token")
    args = parser.parse_args(argv)
    seen = 0
    try:
        with Client(args.url, token=args.token) as client:
            stream = client.events(args.kind, args.device, timeout_s=args.idle)
            print(f"subscribed: {args.url}", file=sys.stderr, flush=True)
            for event in stream:
                print(json.dumps(event), flush=True)
                seen += 1
                if args.count and seen >= args.count:
                    break
    except (ControlError, OSError) as exc:
        print(f"fieldtwin: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
