"""fieldtwin: executable twins of legacy field I/O hardware.

TSX Series 7 intelligent modules (AEM 811, DEM 2412/2413, SCM 20/21/22) on a
simulated PLC bus, and Leroy TES remote I/O terminals as Modbus slaves.
"""

from fieldtwin.errors import ConfigError, FieldtwinError, ProtocolError, TransportError

__all__ = ["ConfigError", "FieldtwinError", "ProtocolError", "TransportError"]
__version__ = "0.1.0"
