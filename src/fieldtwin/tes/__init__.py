"""Leroy Automation TES remote I/O terminals (Modbus RTU slaves) and their TESIS workbench."""

from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import MODELS

__all__ = ["MODELS", "Tes"]
