"""Modbus server glue: the sans-IO cores of ``fieldtwin.modbus`` on real transports.

``serve_tcp`` (Modbus TCP, any number of connections), ``serve_rtu`` (an RTU
line on a pty, a serial port or a memory transport) and ``serve_rtu_over_tcp``
(RTU frames inside TCP connections) attach the cores to a ``Runner``.  Each
core says when it next needs the clock (``next_deadline``); one clock event per
core wakes it then, and replies are sent the instant they are due.

A TCP endpoint at its connection limit hangs up its longest-idle connection
for a new master (fieldtwin.transports.tcp); a pump tells the listener whether
its connection is in the middle of a request (one that is is never hung up)
and the server reports the first such eviction once.

``ModbusServer.tap(bus, endpoint)`` publishes every frame in and out on the
plant's event bus (fieldtwin.runtime.wiretap): on the simulation's thread one raw
record per chunk, decoded on the observers' side; a pump checks ``bus.watched``
first, so an unobserved server pays one attribute read per chunk.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol

from fieldtwin.clock import MS, Handle
from fieldtwin.errors import TransportError
from fieldtwin.modbus.line import RtuLine, Wiring
from fieldtwin.modbus.model import Link, SlaveDevice
from fieldtwin.modbus.rtu import COLLISION, MAX_FRAME
from fieldtwin.modbus.session import TcpSession
from fieldtwin.modbus.slave import SlaveSet, Transmission
from fieldtwin.modbus.timing import RtuTiming, WireTiming
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.uart import REASON_SETTINGS, Uart
from fieldtwin.runtime.wiretap import Stream, Wiretap
from fieldtwin.transports.base import LineSettings, Listener, Transport
from fieldtwin.transports.pty import PtyTransport
from fieldtwin.transports.tcp import TcpTransport, listener_url

# Real transports deliver bytes with operating-system jitter and no line timing:
# a frame complete by length and CRC is taken at once (eager), and inside a
# frame a silence up to this (wall) time is not a break (see docs/modbus.md).
REAL_LINE_FLOOR_US = 2 * MS
# RTU over TCP carries no line timing at all: frames are cut by length and CRC
# (eager), this silence only flushes bytes that never made a frame.
TCP_STREAM_FLOOR_US = 50 * MS


class Core(Protocol):
    """What the glue needs from a sans-IO core (RtuLine, TcpSession)."""

    def receive(self, data: bytes, now: int) -> None: ...
    def poll(self, now: int) -> list[Transmission]: ...
    def next_deadline(self) -> int | None: ...


class _Pump:
    """One core bound to one transport on the runner's clock."""

    def __init__(
        self,
        runner: Runner,
        transport: Transport,
        core: Core,
        server: ModbusServer | None = None,
        precise: bool = False,
    ) -> None:
        self.runner = runner
        self.transport = transport
        self.core = core
        # a wire-timed line: while it has a deadline (a reply due), the runner's waits
        # end on time to a fraction of a ms; not otherwise (precise waits cost naps)
        self._wired = precise
        self._precise = False
        self._timer: Handle | None = None
        self._server = server  # its open pumps: this one leaves them on close
        self._stream: Stream | None = None  # the wiretap's decoder, made when first observed
        self.uart: Uart | None = None  # a pty line: what the device's UART makes of the master
        self._close_told = False  # the pcap was told how this TCP connection ended
        if server is not None:
            server.pumps[id(self)] = self
        self._session = isinstance(core, TcpSession)  # a session closes on a bad stream
        self._line = isinstance(core, RtuLine)  # a line may collide (half duplex)
        if isinstance(transport, TcpTransport):  # its listener may hang up an idle one
            transport.in_progress = self.in_progress
        runner.attach(transport, self.on_data, self.on_close)
        if isinstance(transport, TcpTransport):
            stream = self._observed()
            if stream is not None:  # the pcap's three-way handshake, when it happened
                stream.seen_connection(runner.clock.now, "open", "master")

    def in_progress(self) -> bool:
        """A request is in progress: a reply (or a frame's end) is still due."""
        return self.core.next_deadline() is not None

    def _observed(self) -> Stream | None:
        server = self._server
        if server is None or server.wiretap is None or not server.wiretap.bus.watched:
            return None
        if self._stream is None:
            self._stream = server.wiretap.stream(_conn_name(self.transport))
        return self._stream

    def on_data(self, data: bytes, now: int) -> None:
        if self.uart is not None and self.uart.admit(data, now) is None:
            stream = self._observed()
            if stream is not None:
                stream.seen_rejected(data, now, REASON_SETTINGS, self.uart.describe())
            self._flush(now)
            return
        core = self.core
        if self._line and isinstance(core, RtuLine) and core.collides(now):
            core.collide(data, now)  # half duplex: the master talked over a reply
            stream = self._observed()
            if stream is not None:
                note = "collision: the master sent while a reply was due; the reply is lost"
                stream.seen_rejected(data, now, COLLISION, note, "crc_errors")
            self._flush(now)
            return
        server = self._server  # _observed() inline: one check when nobody has a wiretap
        stream = None if server is None or server.wiretap is None else self._observed()
        if stream is not None:
            stream.seen_in(data, now)  # before the core: the TES's state as the request meets it
        self.core.receive(data, now)
        self._flush(now)

    def on_close(self, now: int) -> None:
        self._closing("fin", "master")
        self.close()

    def _closing(self, state: str, by: str) -> None:
        """Tell the pcap how a TCP connection ended (once: ``close`` follows)."""
        if isinstance(self.transport, TcpTransport) and not self._close_told:
            self._close_told = True
            stream = self._observed()
            if stream is not None:
                stream.seen_connection(self.runner.clock.now, state, by)

    def _want_precise(self, on: bool) -> None:
        if on is not self._precise:
            self._precise = on
            self.runner.want_precise_waits(on)

    def close(self) -> None:
        self._closing("fin", "twin")  # dropped, evicted, or the session ended: the twin's FIN
        self._want_precise(False)
        if self._server is not None:
            self._server.pumps.pop(id(self), None)
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.runner.detach(self.transport)
        if not self.transport.closed:
            self.transport.close()

    def _wake(self, now: int) -> None:
        self._timer = None
        self._flush(now)

    def _flush(self, now: int) -> None:
        server = self._server
        stream = None if server is None or server.wiretap is None else self._observed()
        core = self.core
        try:
            if stream is not None:
                stream.seen_poll(now)
            for transmission in core.poll(now):
                self.transport.send(transmission.data)
                if stream is not None:
                    stream.seen_out(transmission.data, now)
        except TransportError:
            self._closing("rst", "master")  # the master's end is gone: reset
            self.close()
            return
        if self._session and core.close_reason is not None:  # type: ignore[attr-defined]
            self.close()
            return
        deadline = core.next_deadline()
        if deadline is None and self._timer is None and not self._precise:
            return  # nothing due and nothing armed: what ``_rearm`` would leave
        self._rearm(deadline)

    def _rearm(self, deadline: int | None) -> None:
        if self._wired:
            self._want_precise(deadline is not None)
        timer = self._timer
        if timer is not None and timer.active and timer.time == deadline:
            return
        if timer is not None:
            timer.cancel()
        self._timer = None if deadline is None else self.runner.clock.schedule(deadline, self._wake)


def _conn_name(transport: Transport) -> str:
    """The peer of a connection (``127.0.0.1:50412``), or the line's path."""
    name = transport.peer_path or transport.name
    return name.rsplit(" <- ", 1)[-1]


def url_of(scheme: str, listener: Listener) -> str:
    """The endpoint URL a listener is bound to, one that parses back (``tcp://[::]:502``)."""
    return listener_url(scheme, listener.address)


def _slaves_text(slaves: SlaveSet) -> str:
    return ",".join(str(n) for n in slaves.numbers)


def _max_lead(timing: RtuTiming) -> int:
    """A real line carries at most one longest frame beyond what the wall has seen
    (issue 10 item 5): more is a UART overrun (see modbus/rtu.py)."""
    return MAX_FRAME * timing.char_us


def _carries_baud(transport: Transport) -> bool:
    """A UART that sends at the baud rate itself (not a pty, whatever its path)."""
    return bool(getattr(transport, "carries_baud", False))


def _scaled(runner: Runner, floor_us: int) -> int:
    """A wall-time floor in simulated microseconds at the runner's speed."""
    return int(floor_us * (runner.speed or 1.0))


class ModbusServer:
    """What the ``serve_*`` functions return: ``describe()`` and ``close()``."""

    def __init__(
        self,
        runner: Runner,
        kind: str,
        where: str,
        slaves: SlaveSet,
        line: str = "",
        listener: Listener | None = None,
        timing: RtuTiming | None = None,
    ) -> None:
        self.runner = runner
        self.kind = kind
        self.where = where
        self.slaves = slaves
        self._line = line
        self._listener = listener
        # open transports served, by id: a pump leaves on close, so churn never grows it
        self.pumps: dict[int, _Pump] = {}
        self.closed = False
        self.wiretap: Wiretap | None = None
        self._timing = timing  # the RTU framing a wiretap copies (None: MBAP)
        self._holding = False  # holds the runner's pace (a real RTU line)
        self._evictions_told = False

    @property
    def evicted(self) -> int:
        """Idle connections hung up at the connection limit to let a new master in."""
        return int(getattr(self._listener, "evicted", 0))

    def connected(self) -> None:
        """A connection was accepted: say once that the limit is making room."""
        if not self._evictions_told and self.evicted:
            self._evictions_told = True
            limit = getattr(self._listener, "max_connections", "?")
            self.runner.report(
                f"{self.where}: {limit} connections open (the limit): each new one takes"
                " the place of the longest-idle one, which is closed (said once)"
            )

    def tap(self, bus: EventBus, endpoint: str) -> None:
        """Publish every frame in and out on ``bus``, naming ``endpoint`` (as the plant does)."""
        transport = {"modbus-tcp": "tcp", "modbus-rtu-over-tcp": "rtu+tcp"}.get(self.kind, "rtu")
        self.wiretap = Wiretap(bus, endpoint, transport, self.slaves, self._timing, self.where)

    def describe(self) -> str:
        """One line: ``listening: modbus-tcp tcp://127.0.0.1:5020 slaves 1,2``."""
        text = f"listening: {self.kind} {self.where} slaves {_slaves_text(self.slaves)}"
        return f"{text} ({self._line})" if self._line else text

    @property
    def connections(self) -> int:
        """Open transports served (TCP connections, or the one RTU line)."""
        return sum(not pump.transport.closed for pump in self.pumps.values())

    def drop_connections(self) -> int:
        """Close every connection served now (a TCP endpoint; the listener stays open)."""
        if self._listener is None:
            return 0
        pumps = list(self.pumps.values())
        for pump in pumps:
            pump.close()
        return len(pumps)

    def hold_pace(self) -> None:
        """Keep the runner paced while this server is open (its line may hang up)."""
        if not self._holding:
            self._holding = True
            self.runner.hold_pace(True)

    def close(self) -> None:
        """Stop listening and close every transport this server serves."""
        if self._holding:
            self._holding = False
            self.runner.hold_pace(False)
        self.closed = True
        if self._listener is not None:
            self.runner.detach(self._listener)
            self._listener.close()
        for pump in list(self.pumps.values()):
            pump.close()
        self.pumps.clear()


def serve_tcp(
    runner: Runner, listener: Listener, devices: Iterable[SlaveDevice], link: Link = Link.TCP
) -> ModbusServer:
    """Modbus TCP on ``listener``: one session per connection, units = slave numbers."""
    slaves = SlaveSet(devices, link)
    server = ModbusServer(runner, "modbus-tcp", url_of("tcp", listener), slaves, listener=listener)

    def on_connect(transport: Transport, now: int) -> None:
        server.connected()
        _Pump(runner, transport, TcpSession(slaves), server)

    runner.attach_listener(listener, on_connect)
    return server


def serve_rtu(
    runner: Runner,
    transport: Transport,
    devices: Iterable[SlaveDevice],
    link: Link,
    settings: LineSettings,
    wiring: Wiring = Wiring.DOUBLE_PAIR,
    wire_timing: bool = True,
    strict_line: bool = True,
    what: str = "TES",
    half_duplex: bool | None = None,
) -> ModbusServer:
    """A Modbus RTU line on ``transport`` (pty, serial port or memory).

    ``wire_timing`` (real transports): each reply leaves when a real line would
    deliver its last character (``WireTiming``); off, it leaves its answer delay
    after the request's last byte was read (for throughput tests).
    ``strict_line`` (a pty): a master whose termios speed or parity differ from
    ``settings`` gets what a UART would make of it, no answer (runtime/uart.py).
    ``half_duplex`` (default: on for the RS-485 link, a two-wire line; off for RS-232):
    a master that sends while a reply is due collides with it (modbus/line.py).
    """
    timing = RtuTiming.from_format(settings)
    wire = None
    if transport.is_real:
        if wire_timing:
            wire = WireTiming.from_format(settings, carried=_carries_baud(transport))
        floor = _scaled(runner, REAL_LINE_FLOOR_US)
        timing = timing.relaxed(floor, eager=True, max_lead_us=_max_lead(timing))
    if half_duplex is None:
        half_duplex = link is Link.RS485
    line = RtuLine(devices, link, timing, wiring, wire, half_duplex)
    where = f"pty {transport.peer_path}" if transport.peer_path else transport.name
    server = ModbusServer(runner, "modbus-rtu", where, line.slaves, str(settings), timing=timing)
    if transport.is_real:  # the run stays paced if the serial peer goes (issue 15 item 2)
        server.hold_pace()
    pump = _Pump(runner, transport, line, server, precise=wire is not None)
    if isinstance(transport, PtyTransport):  # a pty: the master's termios are visible
        pump.uart = Uart(transport, settings, line.slaves, what, strict_line, runner.report)
    return server


def serve_rtu_over_tcp(
    runner: Runner,
    listener: Listener,
    devices: Iterable[SlaveDevice],
    settings: LineSettings,
    link: Link = Link.RS485,
    wiring: Wiring = Wiring.DOUBLE_PAIR,
    wire_timing: bool = True,
) -> ModbusServer:
    """RTU frames inside TCP connections (a serial-to-Ethernet gateway in front of a line).

    ``wire_timing``: as for ``serve_rtu`` (the stream carries no baud rate).
    """
    devices = tuple(devices)
    # every connection is one more master on the same line: one set, one line-wide tally
    slaves = SlaveSet(devices, link, shared_counts=True)
    timing = RtuTiming.from_format(settings)
    wire = WireTiming.from_format(settings) if wire_timing else None
    floor = _scaled(runner, TCP_STREAM_FLOOR_US)
    timing = timing.relaxed(floor, eager=True, max_lead_us=_max_lead(timing))
    where = url_of("rtu+tcp", listener)
    server = ModbusServer(
        runner, "modbus-rtu-over-tcp", where, slaves, str(settings), listener, timing
    )

    def on_connect(transport: Transport, now: int) -> None:
        server.connected()
        line = RtuLine(slaves, link, timing, wiring, wire)
        _Pump(runner, transport, line, server, precise=wire is not None)

    runner.attach_listener(listener, on_connect)
    return server
