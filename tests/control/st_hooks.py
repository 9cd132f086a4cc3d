"""Schemathesis hooks for tests/control/test_openapi_conformance.py (SCHEMATHESIS_HOOKS).

A request may ask to wait for its mode's end or its console line up to an hour
(``wait_s`` <= 3600, valid and served as asked); the fuzzer would wait for each.
A valid ``wait_s`` above WAIT_S is sent as WAIT_S: still valid, answered sooner.
An invalid one (the fuzzer's negative case) is sent as it was.
"""

from __future__ import annotations

from typing import Any

import schemathesis

WAIT_S = 1.0
MAX_WAIT_S = 3600.0


@schemathesis.hook
def before_call(context: Any, case: Any, kwargs: dict[str, Any]) -> None:
    body = case.body
    if isinstance(body, dict):
        wait = body.get("wait_s")
        number = isinstance(wait, int | float) and not isinstance(wait, bool)
        if number and WAIT_S < wait <= MAX_WAIT_S:
            body["wait_s"] = WAIT_S
