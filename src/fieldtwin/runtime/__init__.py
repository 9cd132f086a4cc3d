"""The real-time runner: paces the simulated clock and pumps transports."""

from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wall import SystemWall, WallClock

__all__ = ["Runner", "SystemWall", "WallClock"]
