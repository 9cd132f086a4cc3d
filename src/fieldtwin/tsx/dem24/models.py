"""The DEM 2412 and DEM 2413 (DEM 6.1, 7.2): thresholds and codes of one module class."""

from __future__ import annotations

from fieldtwin.tsx.dem24.inputs import TYPE1_24V, TYPE1_48V
from fieldtwin.tsx.dem24.module import Dem24


class Dem2412(Dem24):
    """24 x 24 V DC inputs, code 777 (DEM 6.1, 6.2)."""

    type_name = "TSX DEM 2412"
    thresholds = TYPE1_24V
    hardware_codes = frozenset({777})
    software_codes = frozenset({777})
    version_text = "TSX DEM 2412 V1.0"


class Dem2413(Dem24):
    """24 x 48 V DC inputs, code 778 (DEM 6.1, 6.2)."""

    type_name = "TSX DEM 2413"
    thresholds = TYPE1_48V
    hardware_codes = frozenset({778})
    software_codes = frozenset({778})
    version_text = "TSX DEM 2413 V1.0"


__all__ = ["Dem24", "Dem2412", "Dem2413"]
