"""Plain discrete input and output modules of the TSX Series 7 (issue 13 item 3).

No manual of this round describes them; the example applications name them:
the TSX DET 805 input module at 14 and two TSX DST 1635 output modules at 16
and 17 (AEM 5.1), the TSX DET 3212 inputs at 2 and TSX DST 2472 outputs at 3
(DEM 5.3-4).  They are modelled minimally (docs/manual-notes.md, "PLC programs"):
inputs Ixy,0..Ixy,F follow their levels, outputs Oxy,0..Oxy,F are what the PLC
wrote; no register words, no Text Block, no Run/Stop.
"""

from fieldtwin.tsx.discrete.module import DiscreteInputs, DiscreteOutputs, make_types

MODULE_TYPES = make_types()

__all__ = ["MODULE_TYPES", "DiscreteInputs", "DiscreteOutputs"]
