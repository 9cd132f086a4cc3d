"""The real-time runner: paces the simulated clock and pumps transports."""
