"""The message interface every intelligent module shares (AEM 2.4-4, 4.4-2; SCM 6.3).

A Text Block request reaches the module through :meth:`MessageInterface.submit`;
the module answers now or later with ``exchange.complete``.  One exchange at a
time per channel (00, 01) and per module system (63); the requests every module
answers alike are here: H'0F' version, H'47' fault bit string, H'49'/H'4A'
application name.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

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


class MessageInterface:
    """Mixed into IntelligentModule: the Text Block side of a module."""

    version_text: ClassVar[str]
    state: ModuleState
    app_name: bytes
    _exchanges: dict[int, Exchange]

    @property
    def code_ok(self) -> bool:
        raise NotImplementedError

    def read_fault_string(self) -> bytes:
        raise NotImplementedError

    def handle_request(self, exchange: Exchange, now: int) -> None:
        raise NotImplementedError

    def submit(
        self, request: Request, now: int, on_done: Callable[[Exchange, int], None]
    ) -> Exchange:
        """The PLC validated a Text Block addressed to this module."""
        exchange = Exchange(request, now, on_done)
        key = request.channel
        if self.state in (ModuleState.OFF, ModuleState.BLOCKED) or not self.code_ok:
            exchange.complete(Answer.fault(ERR_MODULE_FAULT), now)
            return exchange
        busy = self._exchanges.get(key)
        if busy is not None and not busy.done:
            exchange.complete(Answer.fault(ERR_PARAMETER), now)
            return exchange
        self._exchanges[key] = exchange
        if self.state is not ModuleState.SELF_TEST:  # else held until the self-test ends
            self._dispatch(exchange, now)
        return exchange

    def _dispatch(self, exchange: Exchange, now: int) -> None:
        request = exchange.request
        common = {
            REQ_VERSION: self._req_version,
            REQ_FAULT_STRING: self._req_fault_string,
            REQ_WRITE_APP_NAME: self._req_write_app_name,
            REQ_READ_APP_NAME: self._req_read_app_name,
        }
        handler = common.get(request.code) if request.channel == MODULE_SYSTEM else None
        if handler is not None and request.code not in self.overridden_requests():
            exchange.complete(handler(request), now)
        else:
            self.handle_request(exchange, now)

    def overridden_requests(self) -> frozenset[int]:
        """Common request codes a subclass answers itself in handle_request."""
        return frozenset()

    def pending_exchange(self, channel: int) -> Exchange | None:
        exchange = self._exchanges.get(channel)
        return exchange if exchange is not None and not exchange.done else None

    def reset_exchanges(self, now: int, channel: int | None = None) -> None:
        """Cancel exchanges in progress (OWxy,0,2, or a channel reset bit)."""
        for key, exchange in list(self._exchanges.items()):
            if (channel is None or key == channel) and not exchange.done:
                self.on_exchange_cancelled(exchange, now)
                exchange.complete(Answer.fault(ERR_CANCELLED), now)

    def cancel_exchange(self, exchange: Exchange, now: int) -> None:
        """A Text Block's reset input cancels this one exchange."""
        self.reset_exchanges(now, exchange.request.channel)

    def on_exchange_cancelled(self, exchange: Exchange, now: int) -> None:
        """An exchange is about to be cancelled: stop what it started."""

    def _req_version(self, request: Request) -> Answer:
        # AEM 4.4-2, SCM 6.3: 27 characters, V = H'3F'
        text = self.version_text.encode("ascii")[:VERSION_LENGTH].ljust(VERSION_LENGTH, b" ")
        return Answer(v=V_VERSION, data=text)

    def _req_fault_string(self, request: Request) -> Answer:
        return Answer(v=V_FAULT_STRING, data=self.read_fault_string())

    def _req_write_app_name(self, request: Request) -> Answer:
        # AEM 4.4-2, SCM 6.3: 1 to 20 characters, V = H'FE'
        if not 1 <= len(request.data) <= APP_NAME_MAX:
            return Answer(v=V_ERROR)
        self.app_name = request.data
        return Answer(v=V_OK_WRITE)

    def _req_read_app_name(self, request: Request) -> Answer:
        # SCM 6.3: "systematically returns 20 characters"
        return Answer(v=V_APP_NAME, data=self.app_name.ljust(APP_NAME_MAX, b" "))
