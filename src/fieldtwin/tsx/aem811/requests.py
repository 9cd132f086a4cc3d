"""The AEM 811 requests (AEM 4.2-1, 4.3-1, 3.4-2, 4.4-2, 4.4-3).

At H'xy00': 1 read measurements (H'81'), 2/4 write thresholds 0/1 (H'FE',
answered once compared, so at Run if sent while stopped), 3/5 read thresholds
0/1 (H'83'/H'85').  At H'xy63': H'40' write configuration (H'FE', only while
stopped), H'41' read configuration (H'71': all of it, or zone 1 and one channel);
H'0F', H'47', H'49', H'4A' are the base's.  Anything else: H'FD'.
"""

from __future__ import annotations

from typing import Protocol

from fieldtwin.tsx.aem811.config import (
    ModuleConfig,
    Rejection,
    parse_configuration,
    read_configuration,
)
from fieldtwin.tsx.aem811.scaling import hysteresis
from fieldtwin.tsx.aem811.thresholds import THRESHOLD_BYTES, ThresholdDetector
from fieldtwin.tsx.textblock import MODULE_SYSTEM, V_ERROR, V_OK_WRITE, Answer, Exchange
from fieldtwin.words import words_to_bytes


class Aem811(Protocol):
    """What the requests use of the module (fieldtwin.tsx.aem811.module.Aem811)."""

    config: ModuleConfig
    default_configuration: bool
    rejection: Rejection | None
    thresholds: ThresholdDetector

    @property
    def enabled(self) -> int: ...

    awaiting_configuration: bool
    hysteresis_values: list[int]
    pending_thresholds: Exchange | None
    snapshot: list[int]

    @property
    def running(self) -> bool: ...

    def ack_thresholds(self, now: int) -> None: ...

    def refresh_status(self) -> None: ...

    def refresh_words(self) -> None: ...


CHANNELS = 0x00  # TXTi,M = H'xy00'
READ_MEASUREMENTS, WRITE_T0, READ_T0, WRITE_T1, READ_T1 = 1, 2, 3, 4, 5
WRITE_CONFIG, READ_CONFIG = 0x40, 0x41
V_MEASUREMENTS, V_THRESHOLD_0, V_THRESHOLD_1, V_CONFIG = 0x81, 0x83, 0x85, 0x71


def handle(mod: Aem811, exchange: Exchange, now: int) -> None:
    request = exchange.request
    if request.channel == CHANNELS:
        if request.code == READ_MEASUREMENTS:
            exchange.complete(read_measurements(mod), now)
        elif request.code in (WRITE_T0, WRITE_T1):
            write_thresholds(mod, exchange, now)
        elif request.code in (READ_T0, READ_T1):
            level = 0 if request.code == READ_T0 else 1
            v = V_THRESHOLD_0 if level == 0 else V_THRESHOLD_1
            exchange.complete(Answer(v, mod.thresholds.table(level)), now)  # AMB-AEM-25
        else:
            exchange.complete(Answer(V_ERROR), now)
    elif request.channel == MODULE_SYSTEM and request.code == WRITE_CONFIG:
        exchange.complete(write_configuration(mod, request.data), now)
    elif request.channel == MODULE_SYSTEM and request.code == READ_CONFIG:
        words = read_configuration(mod.config, request.data, request.capacity)
        exchange.complete(Answer(V_CONFIG, words_to_bytes(words)), now)  # AEM 4.4-3
    else:
        exchange.complete(Answer(V_ERROR), now)


def read_measurements(mod: Aem811) -> Answer:
    """AEM 4.2-1: the 8 measurements of one cycle, inhibited channels 0."""
    enabled = mod.enabled
    values = [v if enabled >> c & 1 else 0 for c, v in enumerate(mod.snapshot)]
    return Answer(V_MEASUREMENTS, words_to_bytes(v & 0xFFFF for v in values))


def write_thresholds(mod: Aem811, exchange: Exchange, now: int) -> None:
    """AEM 4.3-1: held until the module has compared with the new values."""
    if len(exchange.request.data) != THRESHOLD_BYTES:
        exchange.complete(Answer(V_ERROR), now)
        return
    mod.pending_thresholds = exchange
    if mod.running and mod.enabled == 0:
        mod.ack_thresholds(now)  # no channel to compare: nothing to wait for


def write_configuration(mod: Aem811, data: bytes) -> Answer:
    """AEM 3.4-2 / 3.4-3: accepted only while stopped; a refusal keeps the old one."""
    if mod.running:  # AMB-AEM-23: refused, IWxy,0,B unchanged
        mod.rejection = Rejection("module in Run (stop it with OWxy,0,C = 0 first)")
        return Answer(V_ERROR)
    result = parse_configuration(data, mod.config)
    if isinstance(result, Rejection):
        mod.rejection = result
        mod.awaiting_configuration = True  # AEM 3.4-3: IWxy,0,B, previous config kept
        mod.refresh_status()
        return Answer(V_ERROR)
    mod.config = result
    mod.hysteresis_values = [hysteresis(c) for c in result.channels]
    mod.rejection = None
    mod.default_configuration = False  # AMB-AEM-21: any accepted configuration
    mod.awaiting_configuration = False
    mod.refresh_status()
    mod.refresh_words()
    return Answer(V_OK_WRITE)
