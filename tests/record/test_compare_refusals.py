"""A refusal is compared by what went wrong, not by the list of what is allowed."""

from __future__ import annotations

from fieldtwin.runtime.compare import compare


def _refused(text: str, t_us: int = 5) -> list[object]:
    return ["result", t_us, "console", {"error": text}]


def test_a_longer_allowed_list_is_the_same_refusal() -> None:
    recorded = [_refused("unknown command 'no' (allowed: read, write)")]
    replayed = [_refused("unknown command 'no' (allowed: read, write, scenario)")]
    assert compare(recorded, replayed) is None


def test_another_reason_or_instant_or_result_is_a_difference() -> None:
    recorded = [_refused("unknown command 'no' (allowed: read)")]
    assert compare(recorded, [_refused("unknown command 'na' (allowed: read)")]) is not None
    assert compare(recorded, [_refused("unknown command 'no' (allowed: read)", 6)]) is not None
    answered: list[object] = ["result", 5, "console", ["ok"]]
    assert compare(recorded, [answered]) is not None
    assert compare([answered], recorded) is not None
