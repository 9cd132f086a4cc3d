"""TSX DEM 2412 / 2413: 24-input time-stamping (sequence of events) modules."""

from fieldtwin.tsx.dem24.models import Dem24, Dem2412, Dem2413

MODULE_TYPES = {"TSX DEM 2412": Dem2412, "TSX DEM 2413": Dem2413}

__all__ = ["MODULE_TYPES", "Dem24", "Dem2412", "Dem2413"]
