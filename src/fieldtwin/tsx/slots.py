"""The PLC models and a slot's images (what the PLC and its program memory share).

Both ``fieldtwin.tsx.plc`` (the PLC) and ``fieldtwin.tsx.plcmemory`` (the PL7
program's view of it) use these, so neither imports the other for them.
"""

from __future__ import annotations

from dataclasses import dataclass

from fieldtwin.tsx.bus import BusImage
from fieldtwin.tsx.module import IntelligentModule


@dataclass(frozen=True, slots=True)
class PlcModel:
    name: str
    register_every: int  # register words refreshed every N cycles (AEM 2.4-3)
    table_max: int  # Text Block table length in bytes (SCM 4.1: 30 on a 47-20)
    report_name: str  # TXTi,R on a TSX 47-20, TXTi,V elsewhere (SCM 3.3)
    racks: int
    intelligent_slots: int  # slots of a rack that take intelligent modules
    basic_rack_max: int = 8  # intelligent modules in the basic rack (AEM 6.1-1)


MODELS = {
    "TSX 47-20": PlcModel("TSX 47-20", 2, 30, "R", 1, 4),
    # AEM 6.1-1: a single-rack basic configuration takes 5 intelligent modules at most
    "TSX 47-30": PlcModel("TSX 47-30", 1, 254, "V", 8, 8, 5),
    "TSX 67": PlcModel("TSX 67", 1, 254, "V", 8, 8),
    "TSX 87": PlcModel("TSX 87", 1, 254, "V", 8, 8),
}

ABSENT = BusImage((1 << 8,) + (0,) * 7, 0, True)  # what an empty slot reads


class Slot:
    """A slot's images.  The program reads and writes them in place (plcmemory cells):
    ``words`` and ``inputs`` follow ``image`` (IWxy,0..7; Ixy,i and Ixy,S), ``outputs``
    holds the output bits Oxy,i."""

    __slots__ = ("_image", "inputs", "module", "outputs", "ow", "present", "words")

    def __init__(self, module: IntelligentModule) -> None:
        self.module = module
        self.present = True
        self.ow = [0] * 8
        self.outputs = [0]  # [Oxy,0..F as a mask]
        self.words = [0] * 8  # image.iw as a list
        self.inputs = [0, 1]  # [image.i_bits, image.fault]
        self._image = BusImage((0,) * 8, 0, True)

    @property
    def image(self) -> BusImage:
        return self._image

    @image.setter
    def image(self, image: BusImage) -> None:
        self._image = image
        self.words[:] = image.iw
        self.inputs[0] = image.i_bits
        self.inputs[1] = int(image.fault)

    @property
    def o_bits(self) -> int:
        return self.outputs[0]

    @o_bits.setter
    def o_bits(self, value: int) -> None:
        self.outputs[0] = value


__all__ = ["ABSENT", "MODELS", "PlcModel", "Slot"]
