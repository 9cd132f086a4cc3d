"""What a plant has opened: its binder groups, in order, and its recorder.

A built plant opens nothing (fieldtwin.plant.building).  Its ports are opened
by the runtime's binder, group by group (``SERIAL_LINE`` for the console,
``MODBUS`` or ``ALL`` for a run); each group opened is noted (a recording
replays the binds in that order), and the recorder, when there is one, is told.
``close()`` closes what was opened in the order it was opened (the ports
before the recorder that writes their traffic).  A session
(fieldtwin.session) holds one ``Ports`` per plant.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from fieldtwin.devices.face import Device
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.binder import Binding, bind
from fieldtwin.runtime.events import EventBus
from fieldtwin.transports.backends import REAL, Backends

if TYPE_CHECKING:
    from fieldtwin.runtime.record import Recorder
    from fieldtwin.runtime.runner import Runner


class Ports:
    """The binder groups a plant opened, its recorder, and how to close them."""

    def __init__(self) -> None:
        self.bindings: list[Binding] = []
        self.bound: list[tuple[str, ...]] = []  # the binder groups opened, in order
        self.recorder: Recorder | None = None

    def bind(
        self,
        devices: Sequence[Device],
        runner: Runner | None,
        groups: tuple[str, ...],
        events: EventBus,
        backends: Backends = REAL,
    ) -> Binding:
        """Open ``groups`` of the devices' ports (through ``backends``); returns the
        binding (its lines)."""
        self.note_bound(groups)
        binding = bind(devices, runner, groups=groups, events=events, backends=backends)
        self.bindings.append(binding)
        return binding

    def note_bound(self, groups: tuple[str, ...]) -> None:
        """The binder is about to open ``groups`` (a recording replays that)."""
        self.bound.append(groups)
        if self.recorder is not None:
            self.recorder.bound(groups)

    def adopt(self, binding: Binding) -> None:
        """A binding opened elsewhere (a replay's), closed with the others."""
        self.bindings.append(binding)

    def add(self, close: Callable[[], None]) -> None:
        """Something to close with the ports, after those opened before it."""
        binding = Binding()
        binding.add([], close)
        self.bindings.append(binding)

    def set_recorder(self, recorder: Recorder) -> None:
        """The one recorder of the plant, told of the groups already opened."""
        if self.recorder is not None:
            raise ConfigError(f"this plant is already recording into {self.recorder.path}")
        for groups in self.bound:
            recorder.bound(groups)
        self.recorder = recorder

    def close(self) -> None:
        bindings, self.bindings = self.bindings, []
        self.recorder = None
        for binding in bindings:
            binding.close()
