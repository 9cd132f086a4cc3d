"""Leroy Automation TES remote I/O terminals."""
