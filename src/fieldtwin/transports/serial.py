"""A serial device through pyserial (a USB adapter, a real COM port, a pty slave).

pyserial opens and configures the port (baud, data bits, parity, stop bits)
with ``timeout=0``, so reads never block.  Writes go through ``os.write`` on
the port's descriptor where it has one: pyserial 3.5's ``write`` with
``write_timeout=0`` spins forever when the kernel buffer is full (it retries
EAGAIN in a loop), which would freeze the simulation.

pyserial is imported when a port is opened, not with this module: on POSIX it loads
termios and fcntl, which a TCP-only plant never needs (README, "POSIX").
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

from fieldtwin.charformat import Parity
from fieldtwin.errors import TransportError
from fieldtwin.transports.base import READ_CHUNK, FdTransport, LineSettings, line_settings

if TYPE_CHECKING:
    import serial as pyserial

# pyserial's PARITY_*, SEVENBITS/EIGHTBITS and STOPBITS_* values
_PARITY = {Parity.NONE: "N", Parity.EVEN: "E", Parity.ODD: "O"}
_BYTESIZE = {7: 7, 8: 8}
_STOPBITS = {1: 1, 2: 2}


class SerialTransport(FdTransport):
    """A pyserial port, non-blocking both ways."""

    def __init__(self, device: str, settings: LineSettings) -> None:
        super().__init__(f"serial://{device}")
        self.device = device
        self.settings = settings
        import serial as pyserial  # here: see the module's docstring

        try:
            self._port = pyserial.Serial(
                device,
                baudrate=settings.baud,
                bytesize=_BYTESIZE[settings.data_bits],
                parity=_PARITY[settings.parity],
                stopbits=_STOPBITS[settings.stop_bits],
                timeout=0,
                write_timeout=0,
            )
        except (pyserial.SerialException, OSError, ValueError) as exc:
            raise TransportError(f"cannot open serial device {device!r}: {exc}") from exc
        self._fd: int | None = self._port_fd()
        # a pty opened as a serial device carries no baud rate (issue 15 item 2)
        self.carries_baud = self._fd is None or not _is_pty(self._fd)

    @property
    def port(self) -> pyserial.Serial:
        """The pyserial port itself (for modem lines, RS-485 settings, ...)."""
        return self._port

    def _port_fd(self) -> int | None:
        import serial as pyserial

        try:
            return int(self._port.fileno())
        except (AttributeError, OSError, pyserial.SerialException):
            return None  # a port without a descriptor: fall back to pyserial's write

    def _write(self, data: bytes) -> int:
        if self._fd is not None:
            return os.write(self._fd, data)
        import serial as pyserial

        try:
            return int(self._port.write(data) or 0)
        except pyserial.SerialTimeoutException:
            return 0

    def receive(self) -> bytes:
        """What has arrived on the line; b"" if nothing; TransportError if the device went away."""
        self._check_open("receive")
        self.flush()
        import serial as pyserial

        try:
            return bytes(self._port.read(READ_CHUNK))
        except (pyserial.SerialException, OSError) as exc:
            self._broken(f"read failed: {exc}")
            raise  # pragma: no cover - _broken always raises

    def fileno(self) -> int | None:
        return None if self.closed else self._fd

    def _release(self) -> None:
        self._port.close()


# Linux: Unix 98 pty slaves have major numbers 136..143 (Documentation/admin-guide/devices.txt)
_PTY_MAJORS = range(136, 144)


def _is_pty(fd: int) -> bool:
    try:
        return os.major(os.fstat(fd).st_rdev) in _PTY_MAJORS
    except OSError:
        return False


def open_serial(device: str, settings: LineSettings | None = None) -> SerialTransport:
    """Open ``device`` (e.g. /dev/ttyUSB0, or a pty's peer_path) with ``settings``."""
    return SerialTransport(device, settings or line_settings())
