"""The AEM 5.1 tank application against the in-memory memory and a scripted module.

The script plays the AEM 811 in slot 5 as its register words say (AEM 2.4-3,
4.1-1): IW5,0,3 module ready, IW5,0,C follows the run command OW5,0,C, IW5,2,D
"default configuration" until a configuration is accepted (report H'FE'), the
fault-string read answers H'77' (AEM 4.4-1).
"""

from __future__ import annotations

from fieldtwin.pl7 import Executor, InMemory, Started, parse

from .helpers import EXAMPLES

CONFIGURATION = [0x00A0, 30, 0x00C0, 0x80C0, 10000, 0, 0x00C1, 0x21C0]  # CW0.. (5.1)
THRESHOLDS = [1000] * 4 + [15000] * 4 + [8000] * 4 + [0] * 4  # CW100[16] (5.1)


class ScriptedAem:
    def __init__(self, memory: InMemory) -> None:
        self.memory = memory
        self.image = memory.module(0, 5)
        self.image.iw[0] = 1 << 3  # IW5,0,3: self-test over, module ready
        self.image.iw[2] = 1 << 0xD  # IW5,2,D: operating with the default configuration
        self.answered = 0

    def after_task(self) -> None:
        image, memory = self.image, self.memory
        run = image.ow[0] >> 0xC & 1
        image.iw[0] = (image.iw[0] & ~(1 << 0xC)) | (run << 0xC)
        for started in memory.started[self.answered :]:
            if started.c == 0x40:
                image.iw[2] &= ~(1 << 0xD)
                memory.finish(0, v=0xFE)
            elif started.c in (0x02, 0x04):
                memory.finish(0, v=0xFE)
            elif started.c == 0x47:
                memory.finish(0, v=0x77, s=8)
        self.answered = len(memory.started)


def load() -> tuple[Executor, InMemory, ScriptedAem]:
    memory = InMemory()
    executor = Executor(parse((EXAMPLES / "aem811_tank.pl7").read_text()), memory)
    memory.cw[0:8] = CONFIGURATION
    memory.cw[100:116] = THRESHOLDS
    memory.module(1, 4).i[0] = 1  # I14,0 Run/Stop at Run
    return executor, memory, ScriptedAem(memory)


def cycle(executor: Executor, aem: ScriptedAem, n: int = 1) -> None:
    for _ in range(n):
        executor.run_master_task()
        aem.after_task()


def test_the_tank_program_configures_the_module_and_writes_both_thresholds() -> None:
    executor, memory, aem = load()
    cycle(executor, aem, 5)
    assert memory.started == [
        Started(0, "EXCHG", 0x563, 0x40, 0),  # SR0: the configuration, 68 bytes from CW0
        Started(0, "EXCHG", 0x500, 0x02, 0),  # SR1: threshold 0 of every channel, CW100
        Started(0, "EXCHG", 0x500, 0x04, 0),  # SR1: threshold 1, CW108
    ]
    assert memory.w[20:26] == [1, 108, 16, 0, 0, 0]  # the indirect table of the last one
    assert memory.b[1:8] == [0, 0, 1, 0, 0, 0, 0]  # B3: measurement processing enabled
    assert aem.image.ow[0] >> 0xC & 1 == 1  # the module is in RUN
    assert list(executor.faults) == []


def test_the_tank_program_copies_the_measurements_into_w0_w7() -> None:
    executor, memory, aem = load()
    cycle(executor, aem, 5)
    aem.image.iw[3:7] = [1000, 2000, 3000, 4000]  # levels, IW5,2,0..3 = 0
    cycle(executor, aem)
    aem.image.iw[2] |= 0xF
    aem.image.iw[3:7] = [15001, 14000, 13000, 12000]  # flows
    cycle(executor, aem)
    assert memory.w[0:8] == [1000, 2000, 3000, 4000, 15001, 14000, 13000, 12000]


def test_the_tank_program_copies_the_threshold_bits_to_the_outputs() -> None:
    executor, memory, aem = load()
    cycle(executor, aem, 5)
    bits = [1, 0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0]
    aem.image.i[:] = bits
    cycle(executor, aem)
    o16, o17 = memory.module(1, 6).o, memory.module(1, 7).o
    assert o16[0:4] == bits[0:4] and o16[0xC:0x10] == bits[0:4]  # V1, LL indicators
    assert o16[4:8] == bits[8:12] and o16[8:12] == bits[8:12]  # V2, HL indicators
    assert o17[0:4] == bits[4:8]  # flow alarms


def test_the_fault_processing_reacts_to_a_broken_input() -> None:
    executor, memory, aem = load()
    cycle(executor, aem, 5)
    aem.image.iw[2] |= 0xF
    aem.image.iw[3] = 9000
    cycle(executor, aem)
    assert memory.w[4] == 9000
    aem.image.iw[1] |= 1 << 0xC  # channel 4 fault (a broken wire)
    aem.image.iw[0] |= 1 << 4  # IW5,0,4: a fault
    aem.image.iw[3] = 0
    cycle(executor, aem)
    assert memory.w[4] == 9000  # the faulty channel is no longer copied
    assert memory.started[-1] == Started(0, "EXCHG", 0x563, 0x47, 0)  # read the fault string
    assert memory.w[20:26] == [0, 0, 0, 0, 50, 8]  # into W50[8]
    assert memory.module(1, 7).o[8] == 1  # O17,8: F sensor fault indicator, tank 0
    assert memory.b[4] == 1 and memory.b[8] == 1
    cycle(executor, aem)
    assert memory.b[8] == 0  # the read ended with H'77'


def test_run_stop_at_stop_stops_the_module() -> None:
    executor, memory, aem = load()
    cycle(executor, aem, 5)
    memory.module(1, 4).i[0] = 0
    cycle(executor, aem)
    assert aem.image.ow[0] >> 0xC & 1 == 0  # L6: RESET OW5,0,C
