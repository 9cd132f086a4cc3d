"""With --control-host a token is required on every request; exposure names the listener."""

from __future__ import annotations

from pathlib import Path

import httpx
import pytest

from fieldtwin.client import Client, ControlError
from fieldtwin.control.launch import exposure_warnings
from tests.control.plantproc import default_plant_copy, fieldtwin_run


def test_a_given_control_host_requires_the_printed_token(tmp_path: Path) -> None:
    with fieldtwin_run(default_plant_copy(tmp_path), "--control-host", "127.0.0.1") as plant:
        assert plant.token is not None and len(plant.token) >= 20
        assert any(
            line.endswith(f"--attach {plant.url} --token {plant.token}") for line in plant.lines
        )
        for path in ("/plant", "/openapi.json", "/devices/tes1"):
            refused = httpx.get(plant.url + path, timeout=10)
            assert refused.status_code == 401
            assert refused.json()["field"] == "token"
        wrong = httpx.get(plant.url + "/plant", headers={"Authorization": "Bearer x"}, timeout=10)
        assert wrong.status_code == 401
        with pytest.raises(ControlError) as info:
            Client(plant.url).plant()
        assert info.value.status == 401
        with pytest.raises(ControlError):
            next(Client(plant.url).events(timeout_s=5))
        with Client(plant.url, token=plant.token) as api:
            assert api.plant()["title"] == "fieldtwin default plant"
            stream = api.events(["clock"], timeout_s=10)
            api.pause()
            api.resume()
            assert next(stream)["what"] == "paused"
            stream.close()


def test_a_given_token_is_the_one_required(tmp_path: Path) -> None:
    with fieldtwin_run(default_plant_copy(tmp_path), "--control-token", "s3cret-token") as plant:
        assert plant.token == "s3cret-token"
        assert httpx.get(plant.url + "/plant", timeout=10).status_code == 401
        assert Client(plant.url, token="s3cret-token").plant()["devices"]


def test_the_warning_names_the_control_listener_reachable_from_other_machines() -> None:
    assert exposure_warnings("127.0.0.1", "http://127.0.0.1:8520") == []
    assert exposure_warnings("::1", "http://[::1]:8520") == []
    (warning,) = exposure_warnings("0.0.0.0", "http://0.0.0.0:8520")
    assert "control API http://0.0.0.0:8520 is reachable from other machines" in warning
    assert "bound to every interface" in warning and "token" in warning
