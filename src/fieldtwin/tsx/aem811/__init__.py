"""The TSX AEM 811 analog input module (manual: tsx-aem-811-analog-input.txt)."""

from __future__ import annotations

from fieldtwin.tsx.aem811.module import Aem811

MODULE_TYPES = {"TSX AEM 811": Aem811}

__all__ = ["MODULE_TYPES", "Aem811"]
