"""Decoding Modbus frames for the wiretap: names, fields and what each TES does.

The pure helpers behind fieldtwin.runtime.wiretap (which re-exports them): a
request's or a reply's fields as the trace and the event stream show them
(docs/trace.md), the bits or words a write request writes, and the small tuple of a
TES's state that a request meets (taken on the simulation's thread) with the outcome
it gives (worked out on the observers' side).
"""

from __future__ import annotations

from functools import lru_cache

from fieldtwin.clock import MS
from fieldtwin.modbus.model import (
    Link,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    SlaveDevice,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.pdu import EXCEPTION_FLAG, WRITE_FUNCTIONS, Rejection, decode_request

FUNCTION_NAMES = {
    0x01: "read_coils",
    0x02: "read_discrete_inputs",
    0x03: "read_holding_registers",
    0x04: "read_input_registers",
    0x05: "write_single_coil",
    0x06: "write_single_register",
    0x07: "read_exception_status",
    0x08: "diagnostics",
    0x0F: "write_multiple_coils",
    0x10: "write_multiple_registers",
    # the other public function codes (Modbus Application Protocol V1.1b3, 6.x): the TES
    # answers them with exception 01, and the trace names them as Modbus does (issue 23)
    0x0B: "get_comm_event_counter",
    0x0C: "get_comm_event_log",
    0x11: "report_server_id",
    0x14: "read_file_record",
    0x15: "write_file_record",
    0x16: "mask_write_register",
    0x17: "read_write_multiple_registers",
    0x18: "read_fifo_queue",
    0x2B: "encapsulated_interface_transport",
}

# What a TES does with a request, as the trace says it (docs/trace.md).
ANSWERS = "answers"
NOT_ADDRESSED = "not_addressed"
POWERED_OFF = "powered_off"
NO_ANSWER = "no_answer"
BROADCAST_EXECUTED = "broadcast"
BROADCAST_IGNORED = "broadcast_ignored"  # AMB-TES-29: a broadcast read


def function_name(function: int) -> str:
    code = function & 0x7F
    # a code with no Modbus name: in decimal and hex, never to be read as another
    base = FUNCTION_NAMES.get(code, f"function_{code}_0x{code:02x}")
    return f"{base}_exception" if function & EXCEPTION_FLAG else base


def request_fields(pdu: bytes) -> dict[str, object]:
    """Function, address and count of a request PDU (what the slave core decodes)."""
    if not pdu:
        return {"function": None, "function_name": "empty"}
    out: dict[str, object] = {"function": pdu[0], "function_name": function_name(pdu[0])}
    request = decode_request(pdu)
    if isinstance(request, Rejection):
        out["rejected"] = int(request.code)
        out["reason"] = request.reason
    elif isinstance(request, ReadBits | ReadWords):
        out["address"], out["count"] = request.address, request.count
    elif isinstance(request, WriteBit | WriteWord):
        out["address"], out["count"] = request.address, 1
    elif isinstance(request, WriteBits | WriteWords):
        out["address"], out["count"] = request.address, len(request.values)
    else:
        assert isinstance(request, ReadExceptionStatus)
    return out


def written(pdu: bytes) -> tuple[str, int, list[int]] | None:
    """(bits or words, address, values) a write request PDU writes; None for the others."""
    if not pdu or pdu[0] not in WRITE_FUNCTIONS:
        return None
    request = decode_request(pdu)
    if isinstance(request, WriteBit):
        return "bits", request.address, [int(request.value)]
    if isinstance(request, WriteWord):
        return "words", request.address, [request.value]
    if isinstance(request, WriteBits):
        return "bits", request.address, [int(v) for v in request.values]
    if isinstance(request, WriteWords):
        return "words", request.address, list(request.values)
    return None  # refused: nothing is written


def reply_fields(pdu: bytes) -> dict[str, object]:
    """Function and exception code of a reply PDU."""
    if not pdu:
        return {"function": None, "function_name": "empty"}
    function = pdu[0]
    return dict(
        _reply_items(function, pdu[1] if function & EXCEPTION_FLAG and len(pdu) > 1 else None)
    )


@lru_cache(maxsize=512)
def _reply_items(function: int, exception: int | None) -> tuple[tuple[str, object], ...]:
    """``reply_fields`` of a reply's function code and exception code, remembered."""
    out: dict[str, object] = {"function": function & 0x7F, "function_name": function_name(function)}
    if exception is not None:
        out["exception"] = exception
    return tuple(out.items())


def device_name(device: SlaveDevice) -> str:
    return str(getattr(device, "name", f"slave {device.slave}"))


# What a request meets in one TES: (powered, told not to answer, the line fault an RTU
# line will give this frame, the answer delay in us); None: powered, no fault, no delay.
State = tuple[bool, bool, str | None, int] | None


def state(device: SlaveDevice, link: Link, rtu: bool) -> State:
    """The small tuple of ``device``'s state a request meets now (see ``State``)."""
    powered = getattr(device, "powered", True)
    faults = getattr(device, "line_faults", None)
    no_answer = faults is not None and faults.no_answer
    pending = None
    if rtu and faults is not None:
        fault = faults.pending(link)  # the RTU line will corrupt this frame
        if fault is not None:
            pending = str(fault.value)
    delay = device.answer_delay(link)
    if powered and not no_answer and pending is None and not delay:
        return None
    return (powered, no_answer, pending, delay)


def outcome_of(meets: State) -> str:
    """What a TES in state ``meets`` does with a request addressed to it."""
    if meets is None:
        return ANSWERS
    powered, no_answer, pending, _ = meets
    if not powered:
        return POWERED_OFF
    if no_answer:
        return NO_ANSWER
    if pending is not None:
        return pending
    return ANSWERS


def outcome(device: SlaveDevice, link: Link, rtu: bool) -> str:
    """What ``device`` will do with a request addressed to it, read from its state now."""
    return outcome_of(state(device, link, rtu))


def late_ms(meets: State) -> float:
    return (meets[3] if meets is not None else 0) / MS


@lru_cache(maxsize=4096)
def request_items(pdu: bytes) -> tuple[tuple[str, object], ...]:
    """``request_fields`` of a PDU, remembered (a master polls the same requests)."""
    return tuple(request_fields(pdu).items())


def mbap_bytes(transaction: int, protocol: int, unit: int, pdu: bytes) -> bytes:
    head = transaction.to_bytes(2, "big") + protocol.to_bytes(2, "big")
    return head + (len(pdu) + 1).to_bytes(2, "big") + bytes((unit,)) + pdu


__all__ = [
    "ANSWERS",
    "BROADCAST_EXECUTED",
    "BROADCAST_IGNORED",
    "FUNCTION_NAMES",
    "NOT_ADDRESSED",
    "NO_ANSWER",
    "POWERED_OFF",
    "State",
    "device_name",
    "function_name",
    "late_ms",
    "mbap_bytes",
    "outcome",
    "outcome_of",
    "reply_fields",
    "request_fields",
    "request_items",
    "state",
    "written",
]
