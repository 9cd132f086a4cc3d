"""The Python client of a running plant's control API (fieldtwin.control.client)."""

from fieldtwin.control.client import Client, ConsoleResult, ControlError, EventStream

__all__ = ["Client", "ConsoleResult", "ControlError", "EventStream"]
