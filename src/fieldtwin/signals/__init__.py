"""Input signals of simulated devices: a value at each simulated time and the next change.

Analog signals give a float in the unit the device expects (volts, milliamps...);
discrete signals give a bool.  Random ones are seeded and answer the same for the
same time whatever order they are asked in.  See docs/signals.md.
"""

from fieldtwin.signals.analog import (
    Constant,
    Noise,
    PiecewiseLinear,
    Ramp,
    Sine,
    Square,
    Step,
    Sum,
)
from fieldtwin.signals.base import AnalogSignal, DiscreteSignal
from fieldtwin.signals.discrete import DiscreteConstant, Edges, PulseTrain, RandomEdges
from fieldtwin.signals.spec import (
    ANALOG_KINDS,
    DISCRETE_KINDS,
    KINDS,
    Signal,
    analog_from_spec,
    discrete_from_spec,
    is_discrete,
    signal_from_spec,
)

__all__ = [
    "ANALOG_KINDS",
    "DISCRETE_KINDS",
    "KINDS",
    "AnalogSignal",
    "Constant",
    "DiscreteConstant",
    "DiscreteSignal",
    "Edges",
    "Noise",
    "PiecewiseLinear",
    "PulseTrain",
    "Ramp",
    "RandomEdges",
    "Signal",
    "Sine",
    "Square",
    "Step",
    "Sum",
    "analog_from_spec",
    "discrete_from_spec",
    "is_discrete",
    "signal_from_spec",
]
