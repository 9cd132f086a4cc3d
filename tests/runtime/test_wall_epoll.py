"""SystemWall's own epoll set says what selectors says (docs/decisions.md, "The runner's
cycle"): the same readable and writable descriptors after the same watches, data,
hang-ups and forgets, on random histories."""

from __future__ import annotations

import contextlib
import random
import select
import socket

import pytest

from fieldtwin.runtime.wall import SystemWall

pytestmark = pytest.mark.skipif(not hasattr(select, "epoll"), reason="epoll is Linux's")

PAIRS = 4
STEPS = 60


def _ready(wall: SystemWall, by_fd: dict[int, int]) -> tuple[list[int], list[int]]:
    """What ``wait(0)`` says, by the pair's index (the two walls watch different fds)."""
    readable, writable = wall.wait(0)
    return sorted(by_fd[fd] for fd in readable), sorted(by_fd[fd] for fd in writable)


@pytest.mark.parametrize("seed", range(8))
def test_epoll_says_what_selectors_say(seed: int) -> None:
    rng = random.Random(seed)
    walls = {"epoll": SystemWall(), "selectors": SystemWall(epoll=False)}
    assert walls["epoll"]._epoll is not None and walls["selectors"]._epoll is None
    pairs = {name: [socket.socketpair() for _ in range(PAIRS)] for name in walls}
    for name in walls:
        for ours, _ in pairs[name]:
            ours.setblocking(False)
    by_fd = {name: {ours.fileno(): i for i, (ours, _) in enumerate(pairs[name])} for name in walls}
    closed: set[int] = set()
    try:
        for _ in range(STEPS):
            i = rng.randrange(PAIRS)
            action = rng.choice(["read", "write", "both", "forget", "send", "drain", "hangup"])
            for name, wall in walls.items():
                ours, theirs = pairs[name][i]
                if action in ("read", "write", "both") and i not in closed:
                    wall.watch(ours.fileno(), read=action != "write", write=action != "read")
                elif action == "forget":
                    wall.forget(ours.fileno())
                elif action == "send" and i not in closed:
                    theirs.send(b"x" * rng.randint(1, 50))
                elif action == "drain" and i not in closed:
                    with contextlib.suppress(BlockingIOError):
                        ours.recv(4096)
                elif action == "hangup" and i not in closed:
                    theirs.close()
            if action == "hangup":
                closed.add(i)
            got = {name: _ready(wall, by_fd[name]) for name, wall in walls.items()}
            assert got["epoll"] == got["selectors"], (seed, action, i)
            assert walls["epoll"].watched == walls["selectors"].watched
    finally:
        for name, wall in walls.items():
            for ours, theirs in pairs[name]:
                wall.forget(ours.fileno())
                ours.close()
                theirs.close()
            wall.close()


def test_forgetting_a_closed_descriptor_is_harmless() -> None:
    for wall in (SystemWall(), SystemWall(epoll=False)):
        a, b = socket.socketpair()
        wall.watch(a.fileno())
        fd = a.fileno()
        a.close()
        wall.forget(fd)  # closed before it was forgotten: no error, nothing watched
        assert wall.watched == 0
        assert wall.wait(0) == ((), ())
        b.close()
        wall.close()


def test_a_timeout_is_kept_without_descriptors_ready() -> None:
    wall = SystemWall()
    a, b = socket.socketpair()
    try:
        wall.watch(a.fileno())
        assert wall.wait(0.001) == ([], [])
        b.send(b"!")
        assert wall.wait(None) == ([a.fileno()], [])
    finally:
        wall.forget(a.fileno())
        a.close()
        b.close()
        wall.close()
