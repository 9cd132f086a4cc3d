"""Plant-side events for the event stream: object and LED changes (DESIGN rule 13).

The observer looks, it never touches: on each of the runner's ticks (not a
clock event, so the simulation's schedule is the same observed or not) and
only while somebody subscribes, it peeks every device's objects and LEDs
through the Device face and publishes what changed since the last look:
``object`` events (``{"object": "IW5,0", "value": 4104, "was": 4096}``) and
``led`` events (``{"led": "ERR", "state": "on", "was": "off"}``).  An object a
plant-file tag names carries it (``"tag": "tank1.level"``: the tag beside the object,
looked up once when the object's peek is bound).  Between two
ticks a value that changes and changes back is not seen: the stream shows the
plant at the tick's resolution (docs/control.md, "Events").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from fieldtwin.devices.face import Device, device_id, peeker
from fieldtwin.errors import FieldtwinError
from fieldtwin.plant.tags import Tags
from fieldtwin.runtime.events import EventBus

MAX_OBJECTS = 4096  # objects one device is looked at for (a TES map is far smaller)


class Observer:
    """Publishes object and LED changes of ``devices`` on ``bus``."""

    def __init__(self, devices: Sequence[Device], bus: EventBus, tags: Tags | None = None) -> None:
        self.devices = list(devices)
        self.bus = bus
        self.tags = tags if tags is not None else Tags()
        self._objects: dict[tuple[str, str], int] = {}
        self._leds: dict[tuple[str, str], str] = {}
        self._watching = False  # a first look after a subscriber came publishes nothing
        # id(device) -> (name, its peek bound once, its tag) of each object, looked up once
        self._peeks: dict[int, list[tuple[str, Callable[[], int], str | None]]] = {}

    def sample(self, now: int) -> None:
        if not self.bus.active:
            self._watching = False
            return
        first = not self._watching
        self._watching = True
        for device in self.devices:
            address = str(device.address)
            self._look_leds(device, address, now, first)
            self._look_objects(device, address, now, first)

    def _look_leds(self, device: Device, address: str, now: int, first: bool) -> None:
        for name, state in device.status().leds:
            key = (address, name)
            was = self._leds.get(key)
            self._leds[key] = state
            if not first and was is not None and was != state:
                self.bus.publish(now, "led", address, {"led": name, "state": state, "was": was})

    def _look_objects(self, device: Device, address: str, now: int, first: bool) -> None:
        peeks = self._peeks.get(id(device))
        if peeks is None:  # a TES lists "H'003' name": the address is enough
            objects = device.objects()
            names = [entry.address for entry in objects.names()[:MAX_OBJECTS]]
            ident = device_id(device, self.devices)
            peeks = [(name, peeker(objects, name), self._tag(ident, name)) for name in names]
            self._peeks[id(device)] = peeks  # names parsed and tags looked up once
        for name, peek, tag in peeks:
            try:
                value = peek()
            except FieldtwinError:
                continue  # a module out of its slot, a word its model lacks
            key = (address, name)
            was = self._objects.get(key)
            self._objects[key] = value
            if not first and was is not None and was != value:
                data: dict[str, object] = {"object": name, "value": value, "was": was}
                if tag is not None:
                    data["tag"] = tag
                self.bus.publish(now, "object", address, data)

    def _tag(self, ident: str, name: str) -> str | None:
        """The tag naming the object ``name`` of the device ``ident`` (a PL7 object, or a
        device's register as its objects list it), if any."""
        found = self.tags.of_object(name)
        if found is None:
            found = self.tags.of_device(ident, "register", name)
        return found.name if found is not None else None


__all__ = ["Observer"]
