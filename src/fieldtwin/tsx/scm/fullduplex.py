"""Channel 1 of a TSX SCM 21xy in full-duplex character strings (SCM 3.2, 4.4, 5.2).

From the configuration on, every character received is stored in a 254-byte
buffer (IWxy,4 counts them, IWxy,3 shows the last, IWxy,2,0 the overflow); a
read request (7 with L = 4) takes a message from it: n characters, up to an
end character, or what came before a silence.  Write requests (7 with 0
characters to receive) run at the same time on the transmitter; they interrupt
the reception echo, which restarts afterwards by the echo type.
"""

from __future__ import annotations

import enum
from collections.abc import Callable

from fieldtwin.clock import Handle
from fieldtwin.fsm import Machine, Table
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.channel import BS, SP, XOFF, XON, AppFault, Channel, Host
from fieldtwin.tsx.scm.config import ChannelConfig
from fieldtwin.tsx.scm.line import Line
from fieldtwin.tsx.scm.requests import Job, JobKind
from fieldtwin.tsx.textblock import V_ERROR, Answer, Exchange

BUFFER_BYTES = 254  # SCM 4.4; AMB-SCM-15: the 255th character overflows
REPORT_SILENCE = 3  # SCM 4.5


class Side(enum.Enum):
    IDLE = "idle"
    BUSY = "busy"


class FdInput(enum.Enum):
    START = "request"
    DONE = "request executed"
    TIMEOUT = "time-out"
    ABORT = "reset"


class Direction(enum.Enum):
    """The two sides of a full-duplex channel, each with its own machine (SCM 4.4)."""

    WRITE = "write"
    READ = "read"


_W, _R = Direction.WRITE, Direction.READ


class FullDuplexChannel(Channel):
    """Channel 1 of a 21xy configured with function 1; its tables are ``FD_WRITE``/``FD_READ``."""

    def __init__(
        self,
        host: Host,
        index: int,
        line: Line,
        signals: Signals,
        config: ChannelConfig | None,
    ) -> None:
        super().__init__(host, index, line, signals, config)
        self.buffer = bytearray()
        self.ends: list[tuple[int, int]] = []  # (end position in the buffer, report)
        self.overflow = False
        self.last_char = 0
        self.echoed = 0  # buffer characters already echoed
        self.xoff_sent = False
        self.machines: dict[Direction, Machine[Side, FdInput, FullDuplexChannel]] = {
            _W: Machine(FD_WRITE, Side.IDLE, self),
            _R: Machine(FD_READ, Side.IDLE, self),
        }
        self.jobs: dict[Direction, Job | None] = {_W: None, _R: None}
        self.exchanges: dict[Direction, Exchange | None] = {_W: None, _R: None}
        self.timers: dict[Direction, Handle | None] = {_W: None, _R: None}
        self.to_send = b""  # the write's characters (ETC, auto-LF applied)
        self.write_report = 0
        self.position = 0  # characters of to_send already sent
        self.read_report = 0
        self.read_data = b""
        self._silence: Handle | None = None

    def side(self, direction: Direction) -> Side:
        return self.machines[direction].state

    def start(self, now: int) -> None:
        assert self.config is not None
        self.signals.dtr_auto = 0 if self.config.dtr_auto else None

    def describe(self) -> str:
        assert self.config is not None
        return (
            f"full-duplex {self.config.fmt}, write {self.side(_W).value},"
            f" read {self.side(_R).value}, buffer {len(self.buffer)}"
        )

    @property
    def receiving(self) -> bool:
        return self.side(_R) is Side.BUSY

    @property
    def transmitting(self) -> bool:
        return self.side(_W) is Side.BUSY

    def fire(self, side: Direction, event: FdInput, now: int) -> None:
        self.machines[side].fire(event, now)
        self.host.changed()

    # --- requests -----------------------------------------------------------------

    def request(self, exchange: Exchange, job: Job, now: int) -> None:
        if job.writes:
            self.jobs[_W] = job
            self.exchanges[_W] = exchange if job.kind is JobKind.WRITE else None
            self.fire(_W, FdInput.START, now)
        if job.reads:
            self.jobs[_R] = job
            self.exchanges[_R] = exchange
            self.fire(_R, FdInput.START, now)

    def abort(self, now: int, write: bool = True, read: bool = True) -> list[Exchange]:
        cancelled = []
        for side, wanted in ((_W, write), (_R, read)):
            exchange = self.exchanges[side]
            if wanted and self.side(side) is Side.BUSY:
                if exchange is not None:
                    cancelled.append(exchange)
                self.fire(side, FdInput.ABORT, now)
        return cancelled

    def _timer(self, side: Direction, at: int) -> None:
        job = self.jobs[side]
        if job is not None and job.timeout_us is not None and self.timers[side] is None:
            self.timers[side] = self.host.call_at(at + job.timeout_us, self._timeout_of(side))

    def _timeout_of(self, side: Direction) -> Callable[[int], None]:
        def fired(now: int) -> None:
            self.timers[side] = None
            self.fire(side, FdInput.TIMEOUT, now)

        return fired

    def _cancel(self, side: Direction) -> None:
        handle = self.timers[side]
        if handle is not None:
            handle.cancel()
        self.timers[side] = None

    def _complete(self, side: Direction, answer: Answer, now: int) -> None:
        exchange = self.exchanges[side]
        self.exchanges[side] = None
        if exchange is not None:
            exchange.complete(answer, now)

    # --- the write side ----------------------------------------------------------

    def _begin_write(self, now: int) -> None:
        job = self.jobs[_W]
        assert job is not None
        self.to_send, self.write_report = self.outgoing(job.chars)
        self.position = 0
        # SCM 3.2 Echo type: a write interrupts the reception echo
        self.echoed = max(0, self.echoed - self.line.clear_tx("echo"))
        if self.to_send:
            self.line.send(self.to_send, now, tag="write")
        else:
            self.host.call_at(now, lambda t: self.fire(_W, FdInput.DONE, t))

    def on_sent(self, value: int, tag: str, now: int) -> None:
        if tag != "write" or self.side(_W) is not Side.BUSY:
            return
        self._timer(_W, now - self.line.char_us)  # from the first character sent
        self.position += 1
        if self.position == len(self.to_send):
            self.fire(_W, FdInput.DONE, now)

    def _end_write(self, now: int) -> None:
        self._cancel(_W)
        self._complete(_W, Answer(v=self.write_report), now)
        self._restart_echo(now)

    def _time_out_write(self, now: int) -> None:
        job = self.jobs[_W]
        self.line.clear_tx("write")
        fault = AppFault.WRITE_TIMEOUT if job and job.kind is JobKind.WRITE else AppFault.WR_TIMEOUT
        self.host.app_fault(self.index, fault)
        self._complete(_W, Answer(v=V_ERROR), now)
        self._restart_echo(now)

    def _stop_write(self, now: int) -> None:
        self._cancel(_W)
        self.line.clear_tx("write")
        self.exchanges[_W] = None
        self._restart_echo(now)

    def _restart_echo(self, now: int) -> None:
        assert self.config is not None
        if not self.config.rx_echo:
            return
        start = 0 if self.config.echo_type == 1 else self.echoed  # SCM 3.2 Echo type 1 / 0
        self._echo(bytes(self.buffer[start:]), now)
        self.echoed = len(self.buffer)

    def _echo(self, chars: bytes, now: int) -> None:
        if chars:
            self.echo(self.with_auto_lf(chars), now, tag="echo")

    # --- the buffer (SCM 4.4, 5.2 IWxy,2..4) --------------------------------------

    def on_char(self, value: int, now: int) -> None:
        assert self.config is not None
        cfg = self.config
        self.last_char = value  # SCM 5.2 IWxy,3: even when the buffer is full
        writing = self.side(_W) is Side.BUSY
        if cfg.back_space and cfg.rx_echo and value == BS:
            self._back_space(now, writing)
            return
        which = cfg.erc.match(value)
        if (not which or cfg.erc.included(which)) and not self._store(value):
            return
        if which:
            self._end_message(which)
        if cfg.rx_echo and not writing:
            self._echo(bytes([value]), now)
            self.echoed = len(self.buffer)
        self._arm_silence(now)
        self._serve(now)

    def _end_message(self, report: int) -> None:
        # an end character right after another ends no new message: a read takes the
        # first one and drops the empty one after it, so it is not kept (bounded ends)
        if not self.ends or self.ends[-1][0] != len(self.buffer):
            self.ends.append((len(self.buffer), report))

    def overrun(self, now: int) -> None:
        # SCM 6.3 (TSX SCM 21) 3rd word bit F "overload fault in reception" (manual-notes)
        self.host.app_fault(self.index, AppFault.OVERLOAD)

    def _store(self, value: int) -> bool:
        if len(self.buffer) >= BUFFER_BYTES:
            self.overflow = True  # SCM 5.2 IWxy,2,0: the character is lost
            self.host.app_fault(self.index, AppFault.OVERLOAD)
            return False
        self.buffer.append(value)
        return True

    def _back_space(self, now: int, writing: bool) -> None:
        # SCM 3.2 / 5.2 note: BS deletes the previous character, IWxy,4 decrements
        floor = self.ends[-1][0] if self.ends else 0
        if len(self.buffer) <= floor:
            return
        self.buffer.pop()
        self.echoed = min(self.echoed, len(self.buffer))
        if not writing:
            self.echo(bytes([BS, SP, BS]), now, tag="echo")

    def _arm_silence(self, now: int) -> None:
        assert self.config is not None
        if self._silence is not None:
            self._silence.cancel()
        if self.config.silence_chars:
            at = now + self.config.silence_chars * self.line.char_us
            self._silence = self.host.call_at(at, self._silence_reached)

    def _silence_reached(self, now: int) -> None:
        # SCM 3.2 "SILENCE BETWEEN CHARACTERS": end of message, report 3
        self._silence = None
        floor = self.ends[-1][0] if self.ends else 0
        if len(self.buffer) > floor:
            self.ends.append((len(self.buffer), REPORT_SILENCE))
            self._serve(now)
        self.host.changed()

    def take(self, count: int) -> bytes:
        data = bytes(self.buffer[:count])
        del self.buffer[:count]
        self.ends = [(p - count, r) for p, r in self.ends if p - count > 0]
        self.echoed = max(0, self.echoed - count)
        return data

    def clear_buffer(self) -> None:
        """OWxy,1,B, message-system reset: the buffer, IWxy,2,0 and IWxy,4 to 0."""
        self.take(len(self.buffer))
        self.ends.clear()
        self.overflow = False

    # --- the read side -----------------------------------------------------------

    def _begin_read(self, now: int) -> None:
        assert self.config is not None
        if self.xoff_sent:  # SCM 3.2 XON-XOFF (R): the next read sends XON
            self.xoff_sent = False
            self.line.send(bytes([XON]), now, tag="flow", first=True)
        if self.config.dtr_auto:
            self.signals.dtr_auto = 0
        self._timer(_R, now)
        self._serve(now)

    def _serve(self, now: int) -> None:
        job = self.jobs[_R]
        if self.side(_R) is not Side.BUSY or job is None:
            return
        if self.ends and self.ends[0][0] <= job.count:
            position, self.read_report = self.ends[0]
            self.ends.pop(0)
            self.read_data = self.take(position)
        elif len(self.buffer) >= job.count:
            self.read_report = 0
            self.read_data = self.take(job.count)
        else:
            return
        self.fire(_R, FdInput.DONE, now)

    def _end_read(self, now: int) -> None:
        assert self.config is not None
        self._cancel(_R)
        if self.read_report == 0:
            self._count_reached(now)
        self.overflow = False  # SCM 5.2: IWxy,2 and IWxy,3 reset when a request is processed
        self.last_char = 0
        exchange = self.exchanges[_R]
        capacity = exchange.request.capacity if exchange is not None else 0
        self._complete(_R, Answer(v=self.read_report, data=self.read_data[:capacity]), now)

    def _count_reached(self, now: int) -> None:
        assert self.config is not None
        if self.config.xon_xoff_rx:
            self.xoff_sent = True
            self.line.send(bytes([XOFF]), now, tag="flow", first=True)
        elif self.config.dtr_auto:
            self.signals.dtr_auto = 1  # AMB-SCM-22: modem not ready until the next read

    def _time_out_read(self, now: int) -> None:
        job = self.jobs[_R]
        fault = AppFault.READ_TIMEOUT if job and job.kind is JobKind.READ else AppFault.WR_TIMEOUT
        self.host.app_fault(self.index, fault)
        self._complete(_R, Answer(v=V_ERROR), now)  # the characters stay in the buffer

    def _stop_read(self, now: int) -> None:
        self._cancel(_R)
        self.exchanges[_R] = None

    def message_reset(self, now: int) -> None:
        self.clear_buffer()
        self.last_char = 0

    def power_off(self) -> None:
        for side in Direction:
            self._cancel(side)
        if self._silence is not None:
            self._silence.cancel()
        super().power_off()


def _nothing(channel: FullDuplexChannel, now: int) -> None:
    """A reset of an idle side: nothing to stop."""


_C, _I, _S = FullDuplexChannel, FdInput, Side

# SCM 4.4: the transmitter and the reader of a full-duplex channel run side by side,
# one machine each (DESIGN rule 4)
FD_WRITE: Table[Side, FdInput] = Table(
    "SCM full-duplex write",
    Side,
    FdInput,
    {
        (_S.IDLE, _I.START): (_C._begin_write, _S.BUSY),
        (_S.IDLE, _I.ABORT): (_nothing, _S.IDLE),
        (_S.BUSY, _I.DONE): (_C._end_write, _S.IDLE),
        (_S.BUSY, _I.TIMEOUT): (_C._time_out_write, _S.IDLE),
        (_S.BUSY, _I.ABORT): (_C._stop_write, _S.IDLE),
    },
)
FD_READ: Table[Side, FdInput] = Table(
    "SCM full-duplex read",
    Side,
    FdInput,
    {
        (_S.IDLE, _I.START): (_C._begin_read, _S.BUSY),
        (_S.IDLE, _I.ABORT): (_nothing, _S.IDLE),
        (_S.BUSY, _I.DONE): (_C._end_read, _S.IDLE),
        (_S.BUSY, _I.TIMEOUT): (_C._time_out_read, _S.IDLE),
        (_S.BUSY, _I.ABORT): (_C._stop_read, _S.IDLE),
    },
)
