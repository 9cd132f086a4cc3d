"""The default plant's program empties the DEM's message stack as the DEM manual's
own example does (DEM 5.3-4, L31/L32 in %POST, with TXT1): at full speed for 10
simulated minutes after its start-up the stack never saturates and the DEM's ERR LED stays off."""

from __future__ import annotations

from importlib import resources

from fieldtwin.plant import load_plant

STACK = 200  # messages the DEM keeps (DEM 2.3-4)


def test_the_default_plant_keeps_the_dem_stack_low_and_err_off() -> None:
    path = resources.files("fieldtwin").joinpath("plants", "default.toml")
    plant = load_plant(str(path), speed=None)
    try:
        plc = plant.plc
        assert plc is not None
        dem = plant.module_device(0, 4)
        read_at_once: set[int] = set()
        highest = 0
        # ERR is on at power-up until the module is configured and its time set (about
        # 10 s here, H bit of IW4,2): the stack's part starts after that
        plc.advance(15.0)
        for _ in range(600):  # 10 simulated minutes, a look every second
            plc.advance(1.0)
            assert dem.status().led_map["ERR"] == "off", f"ERR on at {plant.clock.now / 1e6} s"
            highest = max(highest, plc.read("IW4,5"))
            read_at_once.add(plc.read("W430"))  # messages the last TXT1 exchange read
        assert plc.fault is None and plc.running
        assert highest < STACK // 4, highest
        assert max(read_at_once) >= 1  # the stack was read, not merely never filled
        assert plc.read("IW4,5") < 10
        # the AEM program beside it still runs: tank levels copied into W1..W3
        assert plc.read("W3") != 0
    finally:
        plant.close()
