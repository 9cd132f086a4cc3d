"""The message interface every intelligent module shares (AEM 2.4-4, 4.4-2; SCM 6.3).

A module holds one :class:`Exchanges` component: the exchanges in progress, one
at a time per channel (00, 01) and per module system (63), and the requests
every module answers alike: H'0F' version, H'47' fault bit string, H'49'/H'4A'
application name.  The component knows its module only through the small
:class:`MessageHost` protocol (state, code check, fault string, the module's own
request handler and cancel hook); it declares none of the module's attributes.
A Text Block request reaches it through the module's ``submit``; the module
answers now or later with ``exchange.complete``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from fieldtwin.tsx.bus import ModuleState
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

# Requests every module shares (AEM 4.4-2, SCM 6.3)
REQ_VERSION = 0x0F
REQ_FAULT_STRING = 0x47
REQ_WRITE_APP_NAME = 0x49
REQ_READ_APP_NAME = 0x4A
V_VERSION = 0x3F
V_FAULT_STRING = 0x77
V_APP_NAME = 0x7A
APP_NAME_MAX = 20
VERSION_LENGTH = 27

OnDone = Callable[[Exchange, int], None]


class MessageHost(Protocol):
    """What the exchanges component needs from the module that holds it."""

    @property
    def state(self) -> ModuleState: ...

    @property
    def code_ok(self) -> bool: ...

    @property
    def version_text(self) -> str: ...

    app_name: bytes

    def read_fault_string(self) -> bytes: ...

    def handle_request(self, exchange: Exchange, now: int) -> None: ...

    def overridden_requests(self) -> frozenset[int]: ...

    def on_exchange_cancelled(self, exchange: Exchange, now: int) -> None: ...


class Exchanges:
    """The exchanges a module holds, by channel key, and the common requests."""

    __slots__ = ("_host", "by_key")

    def __init__(self, host: MessageHost) -> None:
        self._host = host
        self.by_key: dict[int, Exchange] = {}  # channel (00, 01, 63) or a module's own key

    def get(self, key: int) -> Exchange | None:
        return self.by_key.get(key)

    def pending(self, key: int) -> Exchange | None:
        """The exchange held on ``key`` that is not over yet."""
        exchange = self.by_key.get(key)
        return exchange if exchange is not None and not exchange.done else None

    def held(self) -> list[Exchange]:
        """Every exchange not over yet."""
        return [e for e in self.by_key.values() if not e.done]

    def submit(self, request: Request, now: int, on_done: OnDone) -> Exchange:
        """A Text Block validated by the PLC, held on its channel."""
        exchange = Exchange(request, now, on_done)
        host = self._host
        if host.state in (ModuleState.OFF, ModuleState.BLOCKED) or not host.code_ok:
            exchange.complete(Answer.fault(ERR_MODULE_FAULT), now)
            return exchange
        if not self.take(request.channel, exchange, now):
            return exchange
        if host.state is not ModuleState.SELF_TEST:  # else held until the self-test ends
            self.dispatch(exchange, now)
        return exchange

    def take(self, key: int, exchange: Exchange, now: int) -> bool:
        """Hold ``exchange`` on ``key``; one already there ends it with TXTi,S = 5."""
        if self.pending(key) is not None:
            exchange.complete(Answer.fault(ERR_PARAMETER), now)
            return False
        self.by_key[key] = exchange
        return True

    def dispatch(self, exchange: Exchange, now: int) -> None:
        """Answer a common request here, hand any other to the module."""
        host = self._host
        request = exchange.request
        common = self._common(request.code) if request.channel == MODULE_SYSTEM else None
        if common is not None and request.code not in host.overridden_requests():
            exchange.complete(common(request), now)
        else:
            host.handle_request(exchange, now)

    def dispatch_held(self, now: int) -> None:
        """The self-test is over: the exchanges it held are handled now."""
        for exchange in self.held():
            self.dispatch(exchange, now)

    def reset(self, now: int, key: int | None = None) -> None:
        """Cancel exchanges in progress (OWxy,0,2, or a channel reset): TXTi,S = 1."""
        for held_on, exchange in list(self.by_key.items()):
            if (key is None or held_on == key) and not exchange.done:
                self._host.on_exchange_cancelled(exchange, now)
                exchange.complete(Answer.fault(ERR_CANCELLED), now)

    def end_all(self, answer: Answer, now: int) -> None:
        """End every exchange not over yet with ``answer`` (blocking fault, power off)."""
        for exchange in self.held():
            exchange.complete(answer, now)

    def clear(self) -> None:
        self.by_key.clear()

    # --- the common requests ------------------------------------------------

    def _common(self, code: int) -> Callable[[Request], Answer] | None:
        return {
            REQ_VERSION: self._version,
            REQ_FAULT_STRING: self._fault_string,
            REQ_WRITE_APP_NAME: self._write_app_name,
            REQ_READ_APP_NAME: self._read_app_name,
        }.get(code)

    def _version(self, request: Request) -> Answer:
        # AEM 4.4-2, SCM 6.3: 27 characters, V = H'3F'
        text = self._host.version_text.encode("ascii")[:VERSION_LENGTH]
        return Answer(v=V_VERSION, data=text.ljust(VERSION_LENGTH, b" "))

    def _fault_string(self, request: Request) -> Answer:
        return Answer(v=V_FAULT_STRING, data=self._host.read_fault_string())

    def _write_app_name(self, request: Request) -> Answer:
        # AEM 4.4-2, SCM 6.3: 1 to 20 characters, V = H'FE'
        if not 1 <= len(request.data) <= APP_NAME_MAX:
            return Answer(v=V_ERROR)
        self._host.app_name = request.data
        return Answer(v=V_OK_WRITE)

    def _read_app_name(self, request: Request) -> Answer:
        # SCM 6.3: "systematically returns 20 characters"
        return Answer(v=V_APP_NAME, data=self._host.app_name.ljust(APP_NAME_MAX, b" "))


__all__ = ["Exchanges", "MessageHost"]
