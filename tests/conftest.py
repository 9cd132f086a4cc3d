"""Project-wide test settings."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator

import pytest
from hypothesis import HealthCheck, settings

# Deterministic property tests: fixed seeds, no wall-clock deadline (the machine may
# be loaded; timing is never what a property test checks), no example database.
settings.register_profile(
    "fieldtwin",
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.load_profile("fieldtwin")

# pytester: tests/plugin runs fieldtwin's pytest plugin in fresh projects.
pytest_plugins = ["pytester", "tests.markers"]


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """``make test-fast`` (FIELDTWIN_FAST_EXAMPLES=N): each property test runs at most
    N examples, so the inner loop stays short; the full run keeps every count."""
    cap = os.environ.get("FIELDTWIN_FAST_EXAMPLES")
    if not cap:
        return
    for item in items:
        test = getattr(item, "obj", None)
        own = getattr(test, "_hypothesis_internal_use_settings", None)
        if test is not None and own is not None and own.max_examples > int(cap):
            # fewer examples make the health check's first sample look filtered
            quiet = [*own.suppress_health_check, HealthCheck.filter_too_much]
            test._hypothesis_internal_use_settings = settings(
                own, max_examples=int(cap), suppress_health_check=quiet
            )


@pytest.fixture
def signal_handlers() -> Iterator[None]:
    """The process's SIGTERM/SIGINT/SIGALRM handlers and its timer as they were, after
    the test (fieldtwin run's stop handlers install themselves)."""
    saved = {n: signal.getsignal(n) for n in (signal.SIGTERM, signal.SIGINT, signal.SIGALRM)}
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        for number, handler in saved.items():
            signal.signal(number, handler)
