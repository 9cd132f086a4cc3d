"""The lane writes an answer of plain values once and remembers it: the key it remembers
it by fixes the JSON (a bool, an int and a float that are equal do not share a body;
a float or a container is never remembered), and a remembered answer is the body the
route writes."""

from __future__ import annotations

import httpx

from fieldtwin.control.lane import _plain
from tests.control.test_lane import WAIT_S, served


def test_the_key_fixes_the_json() -> None:
    base = {"device": "tes1", "input": "3"}
    keys = [_plain({**base, "value": v}) for v in (True, 1, "1", False, 0, "on")]
    assert None not in keys
    assert len(set(keys)) == len(keys)  # True == 1 and False == 0, yet not the same key
    assert _plain({**base, "value": True}) == keys[0]
    assert _plain({"value": True, **base}) != keys[0]  # another order, another body
    for unkeyed in (1.0, -0.0, 0.0, None, [1], {"kind": "sine"}):
        assert _plain({**base, "value": unkeyed}) is None
    assert _plain([("value", True)]) is None


def test_a_remembered_answer_is_the_routes_body() -> None:
    with served(True, None) as lane, served(False, None) as stack:
        headers = {"content-type": "application/json"}
        with httpx.Client(timeout=WAIT_S) as http:
            for value in (True, 1, "on", False, 0, "off", True, 1, 1.0, -0.0, 0.0, 0):
                path = "/devices/tes1/inputs/3"
                body = {"value": value}
                mine = http.put(lane.url + path, json=body, headers=headers)
                theirs = http.put(stack.url + path, json=body, headers=headers)
                assert (mine.status_code, mine.content) == (theirs.status_code, theirs.content)
        app = lane.server.app
        written = [way.written for way in app._ways.values() if way.written]
        assert written and all(len(kept) >= 2 for kept in written)  # the lane remembered
