"""Sans-IO Modbus: PDU codec, CRC, RTU and MBAP framing, slave state machine (DESIGN rule 6)."""
