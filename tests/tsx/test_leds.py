"""``.leds`` on every module: the front panel's own LED names, "on"/"off"/"blink"."""

from __future__ import annotations

import pytest

from fieldtwin.tsx.plc import Plc

# AEM 4.4-1 "Indicator lights": F, OK, ERR; DEM 4.3 "Indicator lamps": F, OK, ERR;
# SCM 1.2 "Two indicator lights": a green "OK" and a red "F"
PANELS = {
    "TSX AEM 811": ("OK", "ERR", "F"),
    "TSX DEM 2412": ("OK", "ERR", "F"),
    "TSX DEM 2413": ("OK", "ERR", "F"),
    "TSX SCM 2111": ("OK", "F"),
}


@pytest.mark.parametrize(("kind", "names"), list(PANELS.items()))
def test_leds_name_only_the_front_panel_s_lights(kind: str, names: tuple[str, ...]) -> None:
    plc = Plc(scan_ms=10)
    mod = plc.insert(kind, rack=0, slot=5)
    assert tuple(mod.leds) == names
    assert set(mod.leds.values()) <= {"on", "off", "blink"}
    plc.advance(12.0)  # past every initial self-test
    assert mod.leds["OK"] == "on" and mod.leds["F"] == "off"
    plc.remove(0, 5)
    assert mod.leds == dict.fromkeys(names, "off")


def test_status_shows_the_same_leds_and_no_mode_the_module_has_not() -> None:
    plc = Plc(scan_ms=10)
    aem = plc.insert("TSX AEM 811", rack=0, slot=5)
    scm = plc.insert("TSX SCM 2111", rack=0, slot=6)
    plc.advance(12.0)
    assert aem.status()["leds"] == "OK=on ERR=off F=off" and aem.status()["mode"] == "Stop"
    assert scm.status()["leds"] == "OK=on F=off"
    assert "mode" not in scm.status()  # SCM: IWxy,0,C is an activity flag, no Run/Stop
