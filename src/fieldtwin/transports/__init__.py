"""Thin adapters over the OS: memory pairs, ptys, serial ports, TCP (DESIGN rule 5)."""
