"""A channel configured in half-duplex character strings (SCM 4.1-4.3, 6.2 flow-charts).

At a given time the channel either transmits or receives: requests 0/1/2
transmit, 3/4 receive, 5/6 (and 7 on a 21xy) transmit then receive.  The
transmission echo (3.2) waits after each character for its echo, tries it
again 3 more times, then ends the request with a fault.
"""

from __future__ import annotations

import enum

from fieldtwin.clock import Handle
from fieldtwin.fsm import Machine, Table
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.channel import BS, SP, AppFault, Channel, Host
from fieldtwin.tsx.scm.config import ECHO_RETRIES, ChannelConfig
from fieldtwin.tsx.scm.line import Line
from fieldtwin.tsx.scm.requests import Job, JobKind
from fieldtwin.tsx.textblock import V_ERROR, Answer, Exchange


class HdState(enum.Enum):
    IDLE = "idle"
    TRANSMITTING = "transmitting"
    RECEIVING = "receiving"


class HdInput(enum.Enum):
    WRITE = "transmission request"
    READ = "reception request"
    WRITE_READ = "transmission/reception request"
    WRITE_DONE = "last character sent"
    TURN_AROUND = "last character sent, reception follows"
    READ_DONE = "reception ended"
    TIMEOUT = "time-out"
    ECHO_FAILED = "echo failed after 3 tries"
    ABORT = "reset"


class HalfDuplexChannel(Channel):
    """One channel in half-duplex character-string mode; its table is ``HALF_DUPLEX``."""

    def __init__(
        self,
        host: Host,
        index: int,
        line: Line,
        signals: Signals,
        config: ChannelConfig | None,
    ) -> None:
        super().__init__(host, index, line, signals, config)
        self.machine: Machine[HdState, HdInput, HalfDuplexChannel] = Machine(
            HALF_DUPLEX, HdState.IDLE, self
        )
        self.job: Job | None = None
        self.exchange: Exchange | None = None
        self.received = bytearray()  # SCM 4.2: the characters of the reception request
        self.reception_report = 0  # SCM 4.5: 0 count, 1/2 end character
        self.to_send = b""  # SCM 4.1: what the transmission sends (ETC, auto-LF applied)
        self.transmission_report = 0
        self.position = 0  # characters of to_send already sent (and echoed back)
        self.tries = 0  # SCM 3.2 transmission echo: failed tries of the present character
        self.awaiting_echo = 0
        self.echo_fault = AppFault.NO_ECHO
        self._timer: Handle | None = None
        self._echo_timer: Handle | None = None

    @property
    def state(self) -> HdState:
        return self.machine.state

    def fire(self, event: HdInput, now: int) -> None:
        self.machine.fire(event, now)
        self.host.changed()

    @property
    def receiving(self) -> bool:
        return self.state is HdState.RECEIVING

    @property
    def transmitting(self) -> bool:
        return self.state is HdState.TRANSMITTING

    def describe(self) -> str:
        assert self.config is not None
        return f"half-duplex {self.config.fmt}, {self.state.value}"

    # --- requests -----------------------------------------------------------

    def request(self, exchange: Exchange, job: Job, now: int) -> None:
        self.job, self.exchange = job, exchange
        self.received = bytearray()
        self.reception_report = 0
        kinds = {JobKind.WRITE: _I.WRITE, JobKind.READ: _I.READ, JobKind.WRITE_READ: _I.WRITE_READ}
        self.fire(kinds[job.kind], now)

    def abort(self, now: int, write: bool = True, read: bool = True) -> list[Exchange]:
        exchange = self.exchange if self.state is not HdState.IDLE else None
        self.fire(HdInput.ABORT, now)
        return [exchange] if exchange is not None and not exchange.done else []

    def _complete(self, answer: Answer, now: int) -> None:
        if self.exchange is not None and not self.exchange.done:  # request 2 ended early
            self.exchange.complete(answer, now)

    def _cancel_timers(self) -> None:
        for handle in (self._timer, self._echo_timer):
            if handle is not None:
                handle.cancel()
        self._timer = self._echo_timer = None

    def _start_timer(self, at: int) -> None:
        assert self.job is not None
        if self.job.timeout_us is not None and self._timer is None:
            self._timer = self.host.call_at(at + self.job.timeout_us, self._on_timeout)

    def _on_timeout(self, now: int) -> None:
        self._timer = None
        self.fire(HdInput.TIMEOUT, now)

    # --- transmission (SCM 4.1) ---------------------------------------------

    def _begin_write(self, now: int) -> None:
        assert self.job is not None and self.config is not None
        self.to_send, self.transmission_report = self.outgoing(self.job.chars)
        self.position = 0
        self.tries = 0
        if not self.job.report:
            self._complete(Answer(v=0), now)  # request 2: TXTi,D at once (AMB-SCM-10)
        if not self.to_send:
            self.host.call_at(now, self._written)
        elif self.config.tx_echo:
            self.line.send(self.to_send[:1], now)
        else:
            self.line.send(self.to_send, now)

    def on_sent(self, value: int, tag: str, now: int) -> None:
        if self.state is not HdState.TRANSMITTING or self.config is None:
            return  # an echo of a reception
        # SCM 4.1: the time-out counts from the first character actually sent
        self._start_timer(now - self.line.char_us)
        if self.config.tx_echo:
            self.awaiting_echo = value
            self._echo_timer = self.host.call_at(now + self.config.echo_timeout_us, self._no_echo)
            return
        self.position += 1
        if self.position == len(self.to_send):
            self._written(now)

    def _written(self, now: int) -> None:
        assert self.job is not None
        self.fire(HdInput.TURN_AROUND if self.job.reads else HdInput.WRITE_DONE, now)

    def _end_write(self, now: int) -> None:
        self._cancel_timers()
        self._complete(Answer(v=self.transmission_report), now)

    # --- transmission echo (SCM 3.2) -----------------------------------------

    def _echo_received(self, value: int, now: int) -> None:
        if self._echo_timer is not None:
            self._echo_timer.cancel()
            self._echo_timer = None
        if value != self.awaiting_echo:
            self._echo_try_failed(AppFault.WRONG_ECHO, now)
            return
        self.position += 1
        self.tries = 0
        if self.position == len(self.to_send):
            self._written(now)
        else:
            self.line.send(self.to_send[self.position : self.position + 1], now)

    def _no_echo(self, now: int) -> None:
        self._echo_timer = None
        self._echo_try_failed(AppFault.NO_ECHO, now)

    def _echo_try_failed(self, fault: AppFault, now: int) -> None:
        # AMB-SCM-9: 1 transmission + 3 more tries, then the fault and the request ends
        self.tries += 1
        if self.tries > ECHO_RETRIES:
            self.echo_fault = fault
            self.fire(HdInput.ECHO_FAILED, now)
            return
        self.line.send(self.to_send[self.position : self.position + 1], now)

    def _echo_failed(self, now: int) -> None:
        self._cancel_timers()
        self.host.app_fault(self.index, self.echo_fault)
        self._complete(Answer(v=V_ERROR), now)

    # --- reception (SCM 4.2) ---------------------------------------------------

    def _begin_read(self, now: int) -> None:
        self._start_timer(now)  # request 3 from now; 5/6/7 already running

    def on_char(self, value: int, now: int) -> None:
        if self.state is HdState.TRANSMITTING and self.config is not None:
            if self.config.tx_echo and self._echo_timer is not None:
                self._echo_received(value, now)
            return
        if self.state is HdState.RECEIVING:
            self._received(value, now)
        # idle: a half-duplex channel only receives while executing a request

    def _received(self, value: int, now: int) -> None:
        assert self.config is not None and self.job is not None
        cfg = self.config
        if cfg.back_space and cfg.rx_echo and value == BS:
            # SCM 3.2: not stored, the previous character is deleted, BS SP BS sent
            if self.received:
                self.received.pop()
                self.echo(bytes([BS, SP, BS]), now)
            return
        if cfg.rx_echo:
            self.echo(self.with_auto_lf(bytes([value])), now)
        which = cfg.erc.match(value)
        if which:
            if cfg.erc.included(which):
                self.received.append(value)
            self.reception_report = which
            self.fire(HdInput.READ_DONE, now)
            return
        self.received.append(value)
        if len(self.received) >= self.job.count:
            self.fire(HdInput.READ_DONE, now)

    def _reply_data(self) -> bytes:
        assert self.exchange is not None
        # SCM 4.2: characters beyond the reception table's capacity are lost
        return bytes(self.received[: self.exchange.request.capacity])

    def _end_read(self, now: int) -> None:
        self._cancel_timers()
        self._complete(Answer(v=self.reception_report, data=self._reply_data()), now)

    # --- endings -----------------------------------------------------------------

    def _time_out(self, now: int) -> None:
        assert self.job is not None
        self._cancel_timers()
        fault = {
            JobKind.WRITE: AppFault.WRITE_TIMEOUT,
            JobKind.READ: AppFault.READ_TIMEOUT,
            JobKind.WRITE_READ: AppFault.WR_TIMEOUT,
        }[self.job.kind]
        self.line.clear_tx()
        self.host.app_fault(self.index, fault)
        data = self._reply_data() if self.job.reads else b""
        self._complete(Answer(v=V_ERROR, data=data), now)

    def _stop(self, now: int) -> None:
        self._cancel_timers()
        self.line.clear_tx()

    def power_off(self) -> None:
        self._cancel_timers()
        self.machine.state = HdState.IDLE  # SCM 6.2 power break: the request is abandoned
        super().power_off()


_S, _I, _C = HdState, HdInput, HalfDuplexChannel

# SCM 6.2 flow-charts: one half-duplex channel (DESIGN rule 4)
HALF_DUPLEX: Table[HdState, HdInput] = Table(
    "SCM half-duplex channel",
    HdState,
    HdInput,
    {
        (_S.IDLE, _I.WRITE): (_C._begin_write, _S.TRANSMITTING),
        (_S.IDLE, _I.WRITE_READ): (_C._begin_write, _S.TRANSMITTING),
        (_S.IDLE, _I.READ): (_C._begin_read, _S.RECEIVING),
        (_S.IDLE, _I.ABORT): (_C._stop, _S.IDLE),
        (_S.TRANSMITTING, _I.WRITE_DONE): (_C._end_write, _S.IDLE),
        (_S.TRANSMITTING, _I.TURN_AROUND): (_C._begin_read, _S.RECEIVING),
        (_S.TRANSMITTING, _I.TIMEOUT): (_C._time_out, _S.IDLE),
        (_S.TRANSMITTING, _I.ECHO_FAILED): (_C._echo_failed, _S.IDLE),
        (_S.TRANSMITTING, _I.ABORT): (_C._stop, _S.IDLE),
        (_S.RECEIVING, _I.READ_DONE): (_C._end_read, _S.IDLE),
        (_S.RECEIVING, _I.TIMEOUT): (_C._time_out, _S.IDLE),
        (_S.RECEIVING, _I.ABORT): (_C._stop, _S.IDLE),
    },
)
