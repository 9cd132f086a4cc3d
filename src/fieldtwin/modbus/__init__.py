"""Sans-IO Modbus: PDU codec, CRC, RTU and MBAP framing, slave state machine (DESIGN rule 6).

``RtuLine`` (a multi-drop RTU line) and ``TcpSession`` (one Modbus TCP connection)
are the two cores: ``receive(data, now)``, ``poll(now) -> [Transmission]``,
``next_deadline()``.  ``fieldtwin.runtime.modbus_server`` binds them to transports.
"""

from fieldtwin.modbus.line import RtuLine, Wiring
from fieldtwin.modbus.session import TcpSession
from fieldtwin.modbus.slave import SlaveSet, Transmission
from fieldtwin.modbus.timing import RtuTiming, exchange_time_us, request_exchange_time_us

__all__ = [
    "RtuLine",
    "RtuTiming",
    "SlaveSet",
    "TcpSession",
    "Transmission",
    "Wiring",
    "exchange_time_us",
    "request_exchange_time_us",
]
