"""The DEM's discrete and register interface (DEM 2.4-2, 2.4-3): bit positions and words.

Pure functions of what the module knows; the module writes their results into its
bus image after every change (nothing is computed per PLC scan).
"""

from __future__ import annotations

from fieldtwin.tsx.dem24.stack import NEARLY_FULL

# Discrete input bits Ixy,i (DEM 2.4-2 reconstructed, AMB-DEM-01)
I_READY, I_NOT_EMPTY, I_NEARLY_FULL, I_SATURATED, I_SYNC_FAULT, I_PULSE = 0, 1, 2, 3, 4, 7

# OWxy,1 command bits (DEM 2.4-3, 4.2-1, AMB-DEM-03)
OW1_STOP, OW1_PURGE, OW1_OVERALL = 0, 1, 2

# IWxy,2 bits (DEM 2.4-3); bits 1..5 are the configuration diagnostics (3.4-3)
IW2_NO_LOGGING, IW2_READY, IW2_SUPPLY, IW2_DEFAULT = 0, 7, 8, 0xD


def status_word(diag_word: int, logging: bool, ready: bool, supply: bool, default: bool) -> int:
    """IWxy,2: no logging, diagnostics, ready to log, external supply fault, default."""
    return (
        diag_word
        | (int(not logging) << IW2_NO_LOGGING)
        | (int(ready) << IW2_READY)
        | (int(supply) << IW2_SUPPLY)
        | (int(default) << IW2_DEFAULT)
    )


def input_bits(ready: bool, count: int, full: bool, sync_fault: bool, pulse_image: bool) -> int:
    """Ixy,0..7: ready, stack not empty / 70 % / saturated, sync fault, pulse image."""
    # bools shift as 0 and 1 (no int() call: once per logged edge and per read)
    return (
        (ready << I_READY)
        | ((count > 0) << I_NOT_EMPTY)
        | ((count >= NEARLY_FULL) << I_NEARLY_FULL)
        | (full << I_SATURATED)
        | (sync_fault << I_SYNC_FAULT)
        | (pulse_image << I_PULSE)
    )
