"""The Modbus/TCP and RTU-over-TCP traffic as a pcap file (Wireshark, tshark).

``PcapWriter`` subscribes to the ``modbus`` events of the plant's bus and
writes each frame that travelled over TCP as an Ethernet/IPv4/TCP packet built
with dpkt (docs/decisions.md): per connection, a three-way handshake the first
time it is seen, then sequence and acknowledgement numbers that follow the
bytes each side sent, so that a dissector reassembles the stream.  The frames
are the bytes that crossed the socket (``hex`` of the event); packet times are
the simulated time plus the wall-clock instant the writer started.

Issue 23: a connection's close is written as the close it was (``connection``
events of the server): FIN from the side that closed, answered by a FIN from
the other, or an RST when the master's end vanished.  RTU on a pty or a serial
line has no TCP: each line is written as one synthetic TCP stream carrying its
RTU bytes, from 127.1.1.N to 127.1.0.N port RTU_PORT (N: the line's number in
order of first traffic), which ``tshark -d tcp.port==65020,mbrtu`` decodes as
Modbus RTU.  Bytes an RTU line rejected (``hex`` of a line fault) are written
where they arrived, so the capture has every byte.
Errors: as the trace writer (reported once, the capture stops, the plant runs).
"""

from __future__ import annotations

import ipaddress
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO
from urllib.parse import urlsplit

import dpkt

from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import Event, EventBus, Subscription

TCP_TRANSPORTS = ("tcp", "rtu+tcp")
RTU_LINE = "rtu"  # a pty or a serial line: a synthetic stream (issue 23)
RTU_PORT = 65020  # its server port: `tshark -d tcp.port==65020,mbrtu` (docs/trace.md)
RTU_CLIENT_PORT = 40000
KIND_CONNECTION = "connection"  # fieldtwin.runtime.wiretap's
QUEUE = 10_000
MAX_CONNECTIONS = 4096  # connections whose sequence numbers are remembered (oldest forgotten)
SERVER_MAC = bytes.fromhex("020000000001")  # locally administered addresses
CLIENT_MAC = bytes.fromhex("020000000002")
FALLBACK_SERVER = "127.0.0.1"  # an IPv6 or named host is written as this IPv4 address
FALLBACK_CLIENT = "127.0.0.2"
WINDOW = 65535
ISN_SERVER = 1_000_000  # initial sequence numbers (any fixed value: the trace is reproducible)
ISN_CLIENT = 2_000_000

Report = Callable[[str], None]


def _ipv4(host: str, fallback: str) -> bytes:
    try:
        return ipaddress.IPv4Address(host.strip("[]")).packed
    except ValueError:
        return ipaddress.IPv4Address(fallback).packed


def split_hostport(text: str) -> tuple[str, int]:
    """``127.0.0.1:502`` or ``[::1]:502`` or ``tcp://host:port`` -> (host, port)."""
    parts = urlsplit(text if "://" in text else f"x://{text}")
    return parts.hostname or "", parts.port or 0


@dataclass(slots=True)
class _Connection:
    server: tuple[bytes, int]
    client: tuple[bytes, int]
    server_seq: int = ISN_SERVER + 1
    client_seq: int = ISN_CLIENT + 1


def tcp_packet(
    src: tuple[bytes, int],
    dst: tuple[bytes, int],
    seq: int,
    ack: int,
    flags: int,
    data: bytes,
    to_server: bool = True,
) -> bytes:
    """One Ethernet/IPv4/TCP frame, lengths and checksums computed: the bytes dpkt
    builds (``dpkt_packet``; a test compares them), made with struct at a tenth of
    the cost (the pcap writer builds one per frame)."""
    length = 20 + 20 + len(data)
    key = (src[0], dst[0], length)
    ip = _IP_HEADERS.get(key)
    if ip is None:  # a connection's frames are of a few lengths: their headers kept
        ip = _IP.pack(0x45, 0, length, 0, 0, 64, 6, 0, src[0], dst[0])
        ip = _IP.pack(0x45, 0, length, 0, 0, 64, 6, _checksum(ip), src[0], dst[0])
        if len(_IP_HEADERS) >= 4096:
            _IP_HEADERS.clear()
        _IP_HEADERS[key] = ip
    tcp = _TCP.pack(src[1], dst[1], seq, ack, 0x50, flags, WINDOW, 0, 0)
    pseudo = src[0] + dst[0] + _PSEUDO.pack(6, 20 + len(data))
    tcp = _TCP.pack(
        src[1], dst[1], seq, ack, 0x50, flags, WINDOW, _checksum(pseudo + tcp + data), 0
    )
    # dst MAC, src MAC: from the client to the server, or back
    return (_TO_SERVER if to_server else _TO_CLIENT) + ip + tcp + data


_IP = struct.Struct(">BBHHHBBH4s4s")
_TCP = struct.Struct(">HHIIBBHHH")
_PSEUDO = struct.Struct(">xBH")
_IP_HEADERS: dict[tuple[bytes, bytes, int], bytes] = {}  # (source, destination, length)
_TO_SERVER = SERVER_MAC + CLIENT_MAC + b"\x08\x00"
_TO_CLIENT = CLIENT_MAC + SERVER_MAC + b"\x08\x00"


def _checksum(data: bytes) -> int:
    """The Internet checksum (RFC 1071) of ``data``: the one's complement of the
    one's complement sum of its 16-bit words.  That sum is the number the bytes
    write modulo 0xFFFF (2**16 is 1 modulo 0xFFFF), but for the sum's two zeros:
    0 only when every word is 0, 0xFFFF otherwise (``checksum_reference``)."""
    if len(data) % 2:
        data += b"\x00"
    total = int.from_bytes(data, "big") % 0xFFFF
    if not total and data.count(0) != len(data):
        total = 0xFFFF
    return ~total & 0xFFFF


def checksum_reference(data: bytes) -> int:
    """RFC 1071 word by word, with the carries folded (``_checksum`` is checked
    against it)."""
    if len(data) % 2:
        data += b"\x00"
    total: int = sum(struct.unpack(f">{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def dpkt_packet(
    src: tuple[bytes, int],
    dst: tuple[bytes, int],
    seq: int,
    ack: int,
    flags: int,
    data: bytes,
    to_server: bool = True,
) -> bytes:
    """The same frame built by dpkt (the reference ``tcp_packet`` is checked against)."""
    segment = dpkt.tcp.TCP(
        sport=src[1], dport=dst[1], seq=seq, ack=ack, flags=flags, win=WINDOW, data=data
    )
    packet = dpkt.ip.IP(src=src[0], dst=dst[0], p=dpkt.ip.IP_PROTO_TCP, ttl=64, data=segment)
    macs = (CLIENT_MAC, SERVER_MAC) if to_server else (SERVER_MAC, CLIENT_MAC)
    frame = dpkt.ethernet.Ethernet(
        src=macs[0], dst=macs[1], type=dpkt.ethernet.ETH_TYPE_IP, data=packet
    )
    return bytes(frame)


class PcapWriter:
    """Writes the TCP-borne Modbus frames published on ``bus`` to ``path``."""

    def __init__(
        self,
        bus: EventBus,
        path: str | Path,
        *,
        report: Report | None = None,
        start_wall: float | None = None,
        rtu_lines: bool = False,
    ) -> None:
        self.path = Path(path)
        self.rtu_lines = rtu_lines  # write pty and serial RTU lines too (`fieldtwin run` does)
        try:
            raw: BinaryIO = open(self.path, "wb")  # noqa: SIM115
        except OSError as exc:
            raise ConfigError(f"--pcap {path}: cannot write it ({exc.strerror})") from None
        self._raw: BinaryIO | None = raw
        self._pcap = dpkt.pcap.Writer(raw, linktype=dpkt.pcap.DLT_EN10MB)
        self._report = report or (lambda text: None)
        self._start = time.time() if start_wall is None else start_wall
        self._conns: dict[tuple[str, str], _Connection] = {}
        self.packets = 0
        self.failed: str | None = None
        self._lines: dict[str, int] = {}  # RTU lines, numbered in order of first traffic
        self._out: list[tuple[float, bytes]] = []  # packets made, written at the drain's end
        self._sub: Subscription | None = bus.subscribe(
            ("modbus", KIND_CONNECTION), maxlen=QUEUE, notify=self._drain, raw=True
        )

    def _drain(self) -> None:
        sub = self._sub
        if sub is None:
            return
        try:
            for event in sub.take():
                self._event(event)
            self._flush()
        except (OSError, ValueError) as exc:
            self._fail(f"pcap {self.path}: {getattr(exc, 'strerror', None) or exc}")

    def _event(self, event: Event) -> None:
        data = event.data
        transport = data.get("transport")
        if event.kind == KIND_CONNECTION:
            if transport in TCP_TRANSPORTS:
                self._lifecycle(event)
            return
        if "hex" not in data or not data["hex"]:
            return
        payload = bytes.fromhex(str(data["hex"]))
        ts = self._start + event.t_us / 1e6
        if transport == RTU_LINE and self.rtu_lines:
            conn = self._rtu_line(str(data.get("endpoint", "")), str(data.get("listen", "")), ts)
        elif transport in TCP_TRANSPORTS:
            conn = self._connection(str(data.get("listen", "")), str(data.get("conn", "")), ts)
        else:
            return
        push = dpkt.tcp.TH_PUSH | dpkt.tcp.TH_ACK
        if data.get("dir") == "in":
            self._packet(ts, conn, True, conn.client_seq, conn.server_seq, push, payload)
            conn.client_seq += len(payload)
        else:
            self._packet(ts, conn, False, conn.server_seq, conn.client_seq, push, payload)
            conn.server_seq += len(payload)

    def _rtu_line(self, endpoint: str, where: str, ts: float) -> _Connection:
        """The synthetic stream of one RTU line (see the module's docstring)."""
        key = (RTU_LINE, f"{endpoint} {where}")
        conn = self._conns.get(key)
        if conn is not None:
            return conn
        number = self._lines.setdefault(key[1], len(self._lines) + 1)
        high, low = divmod(number, 256)
        conn = _Connection(
            (bytes((127, 1, high * 2, low)), RTU_PORT),
            (bytes((127, 1, high * 2 + 1, low)), RTU_CLIENT_PORT),
        )
        return self._opened(key, conn, ts)

    def _lifecycle(self, event: Event) -> None:
        """A TCP connection opened (SYN) or closed (FIN both ways, or RST)."""
        data = event.data
        ts = self._start + event.t_us / 1e6
        listen, peer = str(data.get("listen", "")), str(data.get("conn", ""))
        state = data.get("state")
        if state == "open":
            self._connection(listen, peer, ts)
            return
        conn = self._conns.pop((listen, peer), None)
        if conn is None:
            return  # never seen open: nothing to close
        ack, fin = dpkt.tcp.TH_ACK, dpkt.tcp.TH_FIN | dpkt.tcp.TH_ACK
        if state == "rst":
            self._packet(ts, conn, True, conn.client_seq, conn.server_seq, dpkt.tcp.TH_RST, b"")
            return
        # FIN from the side that closed, the other's FIN, the last ACK
        first = data.get("by") == "master"
        seq = {True: conn.client_seq, False: conn.server_seq}
        self._packet(ts, conn, first, seq[first], seq[not first], fin, b"")
        seq[first] += 1
        self._packet(ts, conn, not first, seq[not first], seq[first], fin, b"")
        seq[not first] += 1
        self._packet(ts, conn, first, seq[first], seq[not first], ack, b"")

    def _connection(self, listen: str, peer: str, ts: float) -> _Connection:
        key = (listen, peer)
        conn = self._conns.get(key)
        if conn is not None:
            return conn
        server_host, server_port = split_hostport(listen)
        client_host, client_port = split_hostport(peer)
        conn = _Connection(
            (_ipv4(server_host, FALLBACK_SERVER), server_port),
            (_ipv4(client_host, FALLBACK_CLIENT), client_port),
        )
        return self._opened(key, conn, ts)

    def _opened(self, key: tuple[str, str], conn: _Connection, ts: float) -> _Connection:
        """Remember ``conn`` and write its three-way handshake."""
        if len(self._conns) >= MAX_CONNECTIONS:
            self._conns.pop(next(iter(self._conns)))
        self._conns[key] = conn
        syn, ack = dpkt.tcp.TH_SYN, dpkt.tcp.TH_ACK
        self._packet(ts, conn, True, ISN_CLIENT, 0, syn, b"")
        self._packet(ts, conn, False, ISN_SERVER, ISN_CLIENT + 1, syn | ack, b"")
        self._packet(ts, conn, True, ISN_CLIENT + 1, ISN_SERVER + 1, ack, b"")
        return conn

    def _packet(
        self,
        ts: float,
        conn: _Connection,
        from_client: bool,
        seq: int,
        ack: int,
        flags: int,
        payload: bytes,
    ) -> None:
        src, dst = (conn.client, conn.server) if from_client else (conn.server, conn.client)
        seq, ack = seq & 0xFFFFFFFF, ack & 0xFFFFFFFF
        self._out.append((ts, tcp_packet(src, dst, seq, ack, flags, payload, from_client)))
        self.packets += 1

    def _flush(self) -> None:
        """Write the packets made since the last flush (one call per drain)."""
        out = self._out
        if out:
            self._out = []
            self._pcap.writepkts(out)

    def _fail(self, why: str) -> None:
        self.failed = why
        self._report(f"{why}: the capture stopped, the plant keeps running")
        self._stop()

    def _stop(self) -> None:
        if self._sub is not None:
            self._sub.close()
            self._sub = None
        raw, self._raw = self._raw, None
        if raw is not None:
            try:
                raw.close()
            except (OSError, ValueError) as exc:
                if self.failed is None:
                    self.failed = f"pcap {self.path}: {exc}"
                    self._report(f"{self.failed}: the end of the capture is lost")

    def close(self) -> None:
        """Write what is left and close the file (idempotent)."""
        if self._sub is not None:
            self._drain()
        self._stop()


__all__ = ["PcapWriter", "split_hostport", "tcp_packet"]
