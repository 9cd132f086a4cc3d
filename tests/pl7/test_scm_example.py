"""The SCM 4.6 full-duplex example (examples/scm_exchange.pl7) against the in-memory
memory: configuration by TXT1, transmission by TXT7 (SR5), reception by TXT0 (SR7)."""

from __future__ import annotations

from fieldtwin.pl7 import Executor, InMemory, Started, parse
from fieldtwin.words import bytes_to_words

from .helpers import EXAMPLES


def test_configures_sends_and_receives() -> None:
    memory = InMemory()
    executor = Executor(parse((EXAMPLES / "scm_exchange.pl7").read_text()), memory)
    memory.module(0, 2).iw[0] = 1 << 3  # IW2,0,3: the module is available
    executor.run_master_task()
    assert memory.started == [Started(1, "EXCHG", 0x0201, 0x40, 18)]  # SR17, CW48..CW56
    memory.finish(1, v=0xFE)  # SCM 3: H'00FE' correct configuration
    executor.run_master_task()
    assert memory.b[0] == 1
    assert memory.started[-1] == Started(0, "EXCHG", 0x0201, 7, 4)  # SR7: 5 bytes, 10 s
    assert memory.w[1130:1132] == [0x100, 5]
    memory.b[128] = 1  # the transmission command
    executor.run_master_task()
    assert memory.started[-1] == Started(7, "EXCHG", 0x0201, 7, 9)  # 4 + 5 bytes
    assert memory.w[2510:2515] == [0, 0, *bytes_to_words(b"HELLO")]
    assert memory.b[128] == 0
    memory.w[1000:1003] = bytes_to_words(b"WORLD")
    memory.finish(0, v=0, s=5)  # H'0000': stop on reaching the number of characters
    executor.run_master_task()
    assert memory.w[1200:1203] == bytes_to_words(b"WORLD") and memory.w[1210] == 1
    executor.run_master_task()
    assert memory.started[-1].index == 0 and len(memory.started) == 4  # reception re-armed
