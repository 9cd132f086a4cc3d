"""The live view renders every part of a plant (rich, recorded off-screen); run's options."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console as RichConsole

from fieldtwin.cli import main
from fieldtwin.live import plain_status, render
from fieldtwin.plant import load_plant
from tests.cli.test_cli import default_plant_copy


def test_live_view_and_plain_status_show_modules_tes_and_endpoints(tmp_path: Path) -> None:
    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    assert plant.plc is not None
    plant.plc.advance(12.0)
    screen = RichConsole(record=True, width=160, file=io.StringIO())
    screen.print(render(plant, ["listening: modbus-tcp tcp://127.0.0.1:5020 slaves 1,2"]))
    text = screen.export_text()
    for expected in (
        "t = 12.0 s",
        "TSX 87 RUN",
        "TSX AEM 811",
        "TSX DEM 2412",
        "TSX SCM 2111",
        "TES 32EST",
        "TES 8EA",
        "listening: modbus-tcp",
        "Ctrl-C to stop",
    ):
        assert expected in text, expected
    lines = plain_status(plant)
    assert lines[0] == "t = 12.000 s"
    assert any(line.startswith("slot 5 TSX AEM 811: Run") for line in lines)
    assert any(line.startswith("TES 2 TES 8EA: on  status H'") for line in lines)
    plant.close()


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "--duration", "nan"],
        ["run", "--duration", "-1"],
        ["run", "--status-every", "inf"],
        ["run", "--speed", "nan"],
        ["run", "--speed", "inf"],
    ],
)
def test_run_rejects_non_finite_times(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    # `--duration nan` escaped as a ValueError traceback from round()
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    assert argv[-1] in capsys.readouterr().err


def _screen(plant: object, width: int) -> list[str]:
    screen = RichConsole(record=True, width=width, file=io.StringIO(), color_system=None)
    screen.print(render(plant, ["listening: modbus-tcp tcp://127.0.0.1:5020 slaves 1,2"]))  # type: ignore[arg-type]
    return screen.export_text().splitlines()


@pytest.mark.parametrize("width", [80, 100, 200])
def test_live_view_reads_well_at_80_100_and_200_columns(tmp_path: Path, width: int) -> None:
    # issue 10 item 15: below ~130 columns the module column went, LEDs blanked, words were cut
    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    assert plant.plc is not None
    plant.plc.advance(12.0)
    lines = _screen(plant, width)
    text = "\n".join(lines)
    assert all(len(line) <= width for line in lines)
    assert "…" not in text  # nothing cut
    rows = {
        "TSX DEM 2412": ("4", "Run", "1008"),
        "TSX AEM 811": ("5", "Run", "1008"),
        "TSX SCM 2111": ("7", "operational", "0008"),
    }
    for kind, (slot, mode, iw0) in rows.items():
        (row,) = [line for line in lines if f" {kind} " in line]
        words = row.replace("│", " ").split()
        assert words[0] == slot and mode in words and iw0 in words, row
        lit, dark = (1, 1) if kind == "TSX SCM 2111" else (1, 2)  # SCM 1.2: OK and F only
        if width < 130:
            assert "●OK" in row and "○F" in row, row
            assert ("○ERR" in row) == (kind != "TSX SCM 2111"), row
        else:
            assert row.count("●") == lit and row.count("○") == dark, row
    for slave, model in (("1", "TES 32EST"), ("2", "TES 8EA")):
        (row,) = [line for line in lines if model in line]
        assert "tcp://127.0.0.1:" in row and f" {slave} " in row and "●Pwr" in row, row
    assert "listening: modbus-tcp" in text and lines[-1].strip() == "Ctrl-C to stop"
    if width == 80:
        assert len(lines) <= 24  # the default plant fits an 80 x 24 terminal
    plant.close()


@pytest.mark.parametrize(("width", "height"), [(80, 24), (100, 30), (200, 50), (60, 12)])
def test_the_footer_names_the_control_and_dashboard_urls_at_every_size(
    tmp_path: Path, width: int, height: int
) -> None:
    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    urls = ["control: http://127.0.0.1:8521", "dashboard: http://127.0.0.1:8521/"]
    screen = RichConsole(record=True, width=width, height=height, file=io.StringIO())
    screen.print(
        render(plant, ["listening: modbus-tcp tcp://127.0.0.1:5020 slaves 1,2"], urls=urls)
    )
    text = screen.export_text()
    lines = text.splitlines()
    assert len(lines) <= height - 1, len(lines)  # fits: nothing of it scrolls away
    tail = " ".join(lines[-3:])
    for url in ("http://127.0.0.1:8521", "http://127.0.0.1:8521/"):
        assert url in tail.replace(" ", "") or url in tail, (width, tail)
    assert "Ctrl-C to stop" in text
