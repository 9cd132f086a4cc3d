"""A module completes each exchange once (a second completion raises ProtocolError):
the paths that used to complete twice, and were silently ignored, now end once."""

from __future__ import annotations

from tests.tsx.scm.helpers import m, ready


def test_message_reset_while_a_request_2_still_transmits() -> None:
    # SCM 4.1: request 2 ends at once (no report) and its characters go on; a
    # message-system reset (OWxy,0,2) then stops the line without ending it again
    plc, mod, peer = ready()
    r = plc.exchange(m=m(0), c=0x02, send_bytes=b"X" * 100)
    assert (r.v, r.s, r.e) == (0, 0, False) and plc.read("IW7,1,1") == 1
    plc.write("OW7,0,2", 1)
    plc.advance(0.05)
    plc.write("OW7,0,2", 0)
    plc.advance(0.05)
    assert plc.read("IW7,1,1") == 0  # the channel is idle again
    again = plc.exchange(m=m(0), c=0x02, send_bytes=b"Y")
    assert (again.v, again.e) == (0, False)
