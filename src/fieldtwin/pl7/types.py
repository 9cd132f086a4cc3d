"""The types of PL7-3 expressions: a bit, a word, a bit string [n], a word table [n]."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Type:
    kind: str  # "bit", "word", "bits", "words"
    n: int = 1

    def __str__(self) -> str:
        if self.kind == "bits":
            return f"bit string [{self.n}]"
        if self.kind == "words":
            return f"word table [{self.n}]"
        return self.kind


BIT = Type("bit")
WORD = Type("word")


def bits(n: int) -> Type:
    return Type("bits", n)


def words(n: int) -> Type:
    return Type("words", n)
