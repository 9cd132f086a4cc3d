"""Errors by culprit (DESIGN rule 7).

A device's answer to bad input (report H'FD', Modbus exception, status bit) is
data, never one of these exceptions.
"""


class FieldtwinError(Exception):
    """Root of every error fieldtwin raises."""


class ConfigError(FieldtwinError, ValueError):
    """The user's own mistake: a plant file, an object name, an argument."""


class ProtocolError(FieldtwinError):
    """A peer's bytes, or an event a state machine cannot take in its state."""


class TransportError(FieldtwinError):
    """An endpoint is closed, broken or timed out."""
