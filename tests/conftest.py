"""Project-wide test settings."""

from __future__ import annotations

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
