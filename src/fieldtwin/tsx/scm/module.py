"""The TSX SCM 20xy / 21xy / 22xy module: two serial channels on the TSX bus.

Register interface (SCM 5.2): IWxy,0 module status, IWxy,1 channel status,
IWxy,2..4 the full-duplex buffer of a 21xy channel 1, OWxy,0,2 message-system
reset, OWxy,1 exchange resets and PWF acknowledgement.  Discrete bits (5.1):
Oxy,0..7 and Ixy,8..F, four per channel adaptor.  Requests (3.3, 4, 6.3):
write/read configuration, transmission/reception 0..7, module reset,
identification, application name, fault bits.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

from fieldtwin.charformat import CharFormat
from fieldtwin.clock import S
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.module import (
    ST_BLOCKING_FAULT,
    ST_GENERAL_FAULT,
    ST_RUN,
    FaultCategory,
    IntelligentModule,
    ModuleContext,
    ModuleState,
)
from fieldtwin.tsx.scm import config as cfgmod
from fieldtwin.tsx.scm import requests as reqmod
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.channel import AppFault, Channel
from fieldtwin.tsx.scm.endpoints import MemoryPeer, Port
from fieldtwin.tsx.scm.fullduplex import FullDuplexChannel
from fieldtwin.tsx.scm.halfduplex import HalfDuplexChannel
from fieldtwin.tsx.scm.line import Line
from fieldtwin.tsx.scm.variants import CODES_47_20, Adaptor, Family, Variant
from fieldtwin.tsx.scm.wiring import Wiring
from fieldtwin.tsx.textblock import (
    ERR_CANCELLED,
    ERR_MODULE_FAULT,
    ERR_PARAMETER,
    MODULE_SYSTEM,
    V_ERROR,
    V_OK_WRITE,
    Answer,
    Exchange,
    Request,
)
from fieldtwin.words import set_bit

REQ_WRITE_CONFIG = 0x40
REQ_READ_CONFIG = 0x41
REQ_MODULE_RESET = 0x44
V_READ_CONFIG = 0x71
WRITE_KEY = 0x81  # the full-duplex write exchange of channel 1 (a second Text Block)
BATTERY_US = 21 * 24 * 3600 * S  # SCM 3.1: "at least 3 weeks"

# SCM 6.3 3rd word: bit offsets within a channel's byte
_FAULT_OFFSET = {
    AppFault.WRONG_ECHO: 0,
    AppFault.NO_ECHO: 1,
    AppFault.READ_TIMEOUT: 2,
    AppFault.WRITE_TIMEOUT: 3,
    AppFault.WR_TIMEOUT: 4,
    AppFault.PARITY: 5,
}
PWF_OFFSET = 7
# fault names -> (fault string bit, hardware?) (SCM 6.1, 6.3)
HARDWARE_FAULTS = {
    "eprom_checksum": 0,
    "ram": 1,
    "logic": 2,
    "loopback_ch0": 16,
    "loopback_ch1": 24,
    "dtr_cd_ch1": 25,
    "rts_cts_ch1": 26,
}


class ScmModule(IntelligentModule):
    """One module reference of appendix 7.3 (subclassed per reference in ``__init__``)."""

    variant: ClassVar[Variant]
    software_codes = CODES_47_20
    self_test_us = 1 * S  # not given by the manual (manual-notes)
    fault_string_bytes = 6  # SCM 6.3: 6 bytes, three words
    has_run_stop = False  # AMB-SCM-26: IWxy,0,C is an activity flag
    led_names = ("OK", "F")  # SCM 1.2: two indicator lights, green OK and red F
    discrete_outputs = 8  # SCM 5.1: Oxy,0..7
    battery_us = BATTERY_US

    def __init__(
        self,
        ctx: ModuleContext,
        rack: int,
        slot: int,
        *,
        declared_code: int | None = None,
        adaptors: Sequence[str] | None = None,
    ) -> None:
        super().__init__(ctx, rack, slot, declared_code=declared_code)
        self.adaptors = self._adaptors(adaptors)
        self.lines = [Line(self.call_at), Line(self.call_at)]
        self.signals = [Signals(a) for a in self.adaptors]
        self.configs: list[cfgmod.ChannelConfig | None] = [None, None]
        self.channels: list[Channel] = [self._channel(i, None) for i in (0, 1)]
        self.wiring = Wiring(self)
        self.pwf = False
        self.cpuf = False  # SCM 7.1 IWxy,1,7: never raised by this twin
        self._powered_before = False
        self._resetting = False
        self._off_at: int | None = None
        self._interrupted: set[int] = set()

    def _adaptors(self, names: Sequence[str] | None) -> tuple[Adaptor, Adaptor]:
        if names is None:
            return self.variant.adaptors
        if len(names) != 2:
            raise ConfigError(f"adaptors: give one per channel, got {list(names)}")
        return Adaptor.parse(names[0], "adaptors[0]"), Adaptor.parse(names[1], "adaptors[1]")

    def _channel(self, index: int, config: cfgmod.ChannelConfig | None) -> Channel:
        line, signals = self.lines[index], self.signals[index]
        signals.dtr_auto = None
        if config is None:
            return Channel(self, index, line, signals, None)
        if config.full_duplex:
            return FullDuplexChannel(self, index, line, signals, config)
        return HalfDuplexChannel(self, index, line, signals, config)

    # --- the wiring (a component: endpoints and adaptor signals) -----------------

    @property
    def ports(self) -> list[Port | None]:
        return self.wiring.ports

    def attach(self, channel: int, endpoint: str) -> MemoryPeer | str:
        """Wire a channel: "memory" returns a MemoryPeer; "pty" the path a peer opens;
        "tcp://127.0.0.1:0" the listening address; "serial:///dev/..." the device."""
        return self.wiring.attach(channel, endpoint)

    def attach_memory(self, channel: int) -> MemoryPeer:
        peer = self.wiring.attach(channel, "memory")
        assert isinstance(peer, MemoryPeer)
        return peer

    def detach(self, channel: int) -> None:
        self.wiring.detach(channel)

    def set_signal(self, channel: int, name: str, level: int) -> None:
        """An adaptor input signal (CTS, CD, DSR, RI) as the wiring drives it (SCM 5.1)."""
        self.wiring.set_signal(channel, name, level)

    def set_loop(self, channel: int, loop: str) -> None:
        """How an SCA2 current loop is wired: "point-to-point" or "multipoint" (SCM 5.1 PSR)."""
        self.wiring.set_loop(channel, loop)

    def peer_format(self, channel: int) -> CharFormat:
        return self.wiring.line(channel).fmt

    # --- status -----------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """Always False: the SCM has no Run/Stop mode (SCM 5.2; AMB-SCM-26, IWxy,0,C is
        an activity flag, ``active``)."""
        return False

    @property
    def active(self) -> bool:
        """IWxy,0,C: a request is being executed by one of the channels (SCM 5.2)."""
        return bool(self.iw[0] >> ST_RUN & 1)

    def status(self) -> dict[str, str]:
        """The base lines without a Run/Stop mode the module does not have (SCM 1.2, 5.2)."""
        lines = super().status()
        lines.pop("mode", None)
        return lines

    # --- host of the channels -----------------------------------------------------

    def app_fault(self, channel: int, fault: AppFault) -> None:
        bit = self._fault_bit(channel, fault)
        if bit is not None:  # an event: memorised until the fault bits are read (6.4)
            self.set_fault(bit, True)
            self.set_fault(bit, False)

    def _fd21(self, channel: int) -> bool:
        config = self.configs[channel]
        return self.variant.family is Family.SCM21 and config is not None and config.full_duplex

    def _fault_bit(self, channel: int, fault: AppFault) -> int | None:
        offset = _FAULT_OFFSET.get(fault)
        if fault is AppFault.FORMAT:
            offset = 6 if self._fd21(channel) else 5  # SCM 6.3 (21: E); else parity bit
        elif fault is AppFault.OVERLOAD:
            offset = 7 if self._fd21(channel) else None
        return None if offset is None else 32 + 8 * channel + offset

    def changed(self) -> None:
        """Recompute IWxy,1..4 and the discrete inputs, then IWxy,0."""
        if self.state is ModuleState.OFF:
            return
        self.iw[1] = self._channel_word()
        fd = self.channels[1]
        if isinstance(fd, FullDuplexChannel):
            self.iw[2], self.iw[3], self.iw[4] = int(fd.overflow), fd.last_char, len(fd.buffer)
        else:
            self.iw[2] = self.iw[3] = self.iw[4] = 0
        self.i_bits = (self.signals[0].input_nibble() << 8) | (self.signals[1].input_nibble() << 12)
        self.awaiting_configuration = not any(self.configs)
        self.refresh_status()

    def _channel_word(self) -> int:
        # SCM 5.2 IWxy,1 (and the 21 full-duplex bits 9/A)
        word = 0
        for index, channel in enumerate(self.channels):
            base = 8 * index
            if isinstance(channel, FullDuplexChannel):
                word = set_bit(word, base + 1, channel.receiving)
                word = set_bit(word, base + 2, channel.transmitting)
            else:
                word = set_bit(word, base + 1, channel.busy)
                word = set_bit(word, base + 2, channel.busy and channel.transmitting)
            word = set_bit(word, base + 3, channel.configured)
            word |= self.adaptors[index].code << (base + 4)
        word = set_bit(word, 7, self.cpuf)
        return set_bit(word, 15, self.pwf)

    def standard_status(self) -> int:
        word = super().standard_status()
        if self.state is ModuleState.OFF:
            return word
        busy = self.state is ModuleState.OPERATIONAL and any(c.busy for c in self.channels)
        word = set_bit(word, ST_RUN, busy)  # AMB-SCM-26: a request is being executed
        blocked = bool(word >> ST_BLOCKING_FAULT & 1)
        return word | (1 << ST_GENERAL_FAULT) if blocked else word  # 5.2: OR of 5..8

    def fault_category_of(self, bit: int) -> FaultCategory:
        if bit < 16:
            return FaultCategory.BLOCKING
        return FaultCategory.MODULE if bit < 32 else FaultCategory.APPLICATION

    # --- power (SCM 3.1, 6.2, 7.1) --------------------------------------------------

    def on_power_on(self, now: int) -> None:
        if self._off_at is not None and now - self._off_at > self.battery_us:
            self.configs = [None, None]  # the battery ran out
            self.app_name = b""
        self.channels = [self._channel(i, None) for i in (0, 1)]
        self.changed()

    def on_self_test_done(self, now: int) -> None:
        self.channels = [self._channel(i, self.configs[i]) for i in (0, 1)]
        for channel in self.channels:
            channel.start(now)
        if self._powered_before and not self._resetting:
            self.pwf = True  # SCM 6.2: IWxy,1,F on power return
            for index in sorted(self._interrupted):
                if not self._fd21(index):
                    self.set_fault(32 + 8 * index + PWF_OFFSET, True)
                    self.set_fault(32 + 8 * index + PWF_OFFSET, False)
        self._interrupted.clear()
        self._powered_before = True
        self._resetting = False
        self.changed()

    def on_power_off(self, now: int) -> None:
        self._off_at = now
        self._interrupted = {i for i, c in enumerate(self.channels) if c.busy}
        for channel in self.channels:
            channel.power_off()

    # --- outputs (SCM 5.1, 5.2) ------------------------------------------------------

    def on_outputs(self, old_ow: list[int], old_o: int, now: int) -> None:
        for index in (0, 1):
            self.signals[index].outputs = (self.o_bits >> (4 * index)) & 0xF
            self.channels[index].signals_changed(now)
        rising = self.ow[1] & ~old_ow[1]
        fd = self.channels[1]
        if rising & (1 << 1):
            self._reset_channel(0, now)
        if isinstance(fd, FullDuplexChannel):
            if rising & (1 << 9):
                self._reset_channel(1, now, write=False)
            if rising & (1 << 0xA):
                self._reset_channel(1, now, read=False)
            if rising & (1 << 8):
                fd.overflow = False
            if rising & (1 << 0xB):
                fd.clear_buffer()
        elif rising & (1 << 9):
            self._reset_channel(1, now)  # AMB-SCM-7
        if rising & (1 << 0xF):
            self.pwf = False  # PWF acknowledgement
        self.changed()

    def _reset_channel(self, index: int, now: int, write: bool = True, read: bool = True) -> None:
        for exchange in self.channels[index].abort(now, write, read):
            exchange.complete(Answer.fault(ERR_CANCELLED), now)

    def reset_exchanges(self, now: int, channel: int | None = None) -> None:
        if channel is None:  # OWxy,0,2: the whole message system
            for index in (0, 1):
                self._reset_channel(index, now)
                self.channels[index].message_reset(now)
        elif channel in (0, 1):
            if isinstance(self.channels[channel], FullDuplexChannel):
                return  # which side? the program uses OWxy,1,9/A (manual-notes)
            self._reset_channel(channel, now)
        super().reset_exchanges(now, channel)
        self.changed()

    def cancel_exchange(self, exchange: Exchange, now: int) -> None:
        """A Text Block reset: on a full-duplex channel, only that side (read or write)."""
        index = exchange.request.channel
        if index in (0, 1) and isinstance(self.channels[index], FullDuplexChannel):
            write = self._exchanges.get(WRITE_KEY) is exchange
            for job in self.channels[index].abort(now, write, not write):
                job.complete(Answer.fault(ERR_CANCELLED), now)
            if not exchange.done:  # abort() ended it if it was that side's
                exchange.complete(Answer.fault(ERR_CANCELLED), now)
            self.changed()
            return
        super().cancel_exchange(exchange, now)

    # --- the message interface -----------------------------------------------------

    def submit(self, request: Request, now: int, on_done: Any) -> Exchange:
        if request.channel not in (0, 1) or not self._is_fd_write(request):
            return super().submit(request, now, on_done)
        exchange = Exchange(request, now, on_done)  # a second Text Block on channel 1
        busy = self._exchanges.get(WRITE_KEY)
        if self.state is not ModuleState.OPERATIONAL or not self.code_ok:
            exchange.complete(Answer.fault(ERR_MODULE_FAULT), now)
        elif busy is not None and not busy.done:
            exchange.complete(Answer.fault(ERR_PARAMETER), now)
        else:
            self._exchanges[WRITE_KEY] = exchange
            self.handle_request(exchange, now)
        return exchange

    def _is_fd_write(self, request: Request) -> bool:
        return isinstance(self.channels[request.channel], FullDuplexChannel) and (
            reqmod.is_fd_write(request.code, request.data)
        )

    def overridden_requests(self) -> frozenset[int]:
        return frozenset()

    def handle_request(self, exchange: Exchange, now: int) -> None:
        request = exchange.request
        code, channel = request.code, request.channel
        if channel == MODULE_SYSTEM:
            if code == REQ_MODULE_RESET:
                self._module_reset(exchange, now)
            elif code == REQ_READ_CONFIG:
                exchange.complete(self._read_config(0), now)  # AMB-SCM-19
            else:
                exchange.complete(Answer(v=V_ERROR), now)
        elif code == REQ_WRITE_CONFIG:
            exchange.complete(self._write_config(channel, request.data, now), now)
        elif code == REQ_READ_CONFIG:
            exchange.complete(self._read_config(channel), now)
        elif code <= reqmod.COMBINED:
            self._channel_request(exchange, now)
        else:
            exchange.complete(Answer(v=V_ERROR), now)
        self.changed()

    def _channel_request(self, exchange: Exchange, now: int) -> None:
        request = exchange.request
        channel = self.channels[request.channel]
        fd = isinstance(channel, FullDuplexChannel)
        code = request.code
        if code == reqmod.COMBINED and not self.variant.has_request_7:
            exchange.complete(Answer(v=V_ERROR), now)  # SCM 4.3: 21xy only
            return
        if fd and code != reqmod.COMBINED:
            exchange.complete(Answer(v=V_ERROR), now)  # SCM 4.4: request 7 only
            return
        try:
            job = reqmod.parse(code, request.data)
        except cfgmod.Refused:
            exchange.complete(Answer(v=V_ERROR), now)
            return
        if (not fd and channel.busy) or (fd and job.reads and channel.receiving):
            exchange.complete(Answer.fault(ERR_PARAMETER), now)
            return
        if fd and job.writes and channel.transmitting:
            exchange.complete(Answer.fault(ERR_PARAMETER), now)
            return
        channel.request(exchange, job, now)

    def _write_config(self, index: int, data: bytes, now: int) -> Answer:
        other = self.configs[1 - index]
        for exchange in self.channels[index].abort(now):
            exchange.complete(Answer.fault(ERR_CANCELLED), now)
        self.channels[index].power_off()
        fd_allowed = index == 1 and self.variant.full_duplex_ch1
        try:
            config = cfgmod.decode(data, index, fd_allowed)
            if other is not None and cfgmod.speed_conflict(config.baud, other.baud):
                raise cfgmod.Refused("speed restriction with the other channel")  # AMB-SCM-4
        except cfgmod.Refused:
            config = None  # SCM 3.3: the channel is not configured, the previous one lost
        self.apply_config(index, config, now)
        return Answer(v=V_OK_WRITE if config is not None else V_ERROR)

    def apply_config(self, index: int, config: cfgmod.ChannelConfig | None, now: int) -> None:
        self.configs[index] = config
        self.channels[index] = self._channel(index, config)
        if self.state is ModuleState.OPERATIONAL:
            self.channels[index].start(now)
        self.wiring.follow_configuration(index)
        self.changed()

    def _read_config(self, index: int) -> Answer:
        config = self.configs[index]
        if config is None:
            return Answer(v=V_ERROR)
        return Answer(v=V_READ_CONFIG, data=config.table_bytes())

    def _module_reset(self, exchange: Exchange, now: int) -> None:
        # SCM 6.3: erase both configurations and the faults, restart as at power-up
        exchange.complete(Answer(v=V_OK_WRITE), now)
        self.reset_exchanges(now)
        self.configs = [None, None]
        self.pwf = False
        self._resetting = True  # until the self-test ends: no PWF for a reset
        self.power_off(now)
        self.power_on(now)

    # --- faults ---------------------------------------------------------------------

    def set_self_test_fault(self, bit: int, present: bool) -> None:
        """A fault the self-test finds (fault bit ``bit`` of HARDWARE_FAULTS, SCM 6.1, 6.3)."""
        if bit not in HARDWARE_FAULTS.values():
            allowed = ", ".join(map(str, HARDWARE_FAULTS.values()))
            raise ConfigError(f"SCM self-test fault bit {bit} not allowed (allowed: {allowed})")
        self.hardware_fault(bit, present)
        self.changed()

    def set_parity_errors(self, channel: int, on: bool) -> None:
        """Every character channel ``channel`` receives has a parity error (kept by the UART)."""
        self.wiring.line(channel).inject_parity = on

    def set_format_errors(self, channel: int, on: bool) -> None:
        """Every character channel ``channel`` receives has a format error (kept by the UART)."""
        self.wiring.line(channel).inject_format = on
