"""A small reader for PDS3 labels (PVL: ``KEY = VALUE``, ``OBJECT``/``GROUP`` blocks).

Pure Python, no I/O beyond the bytes it is given. Values become ``int``, ``float``, ``str`` or
tuples of them; a unit such as ``1.0 <METERS/PIXEL>`` becomes :class:`Quantity`; a based integer
``16#FF7FFFFB#`` becomes :class:`Based` (which keeps the raw digits, so a float32 missing constant
is compared by its bit pattern, never through a rounded float). Objects and groups are nested
:class:`Label` mappings; keys keep their label spelling and are looked up case-insensitively.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from marsscene.errors import DEMReadError

__all__ = ["Based", "Label", "Quantity", "label_length", "parse_label"]


@dataclass(frozen=True)
class Quantity:
    """A number with a unit, e.g. ``MAP_SCALE = 1.0 <METERS/PIXEL>``."""

    value: float | int | str
    unit: str


@dataclass(frozen=True)
class Based:
    """A based integer ``radix#digits#`` (e.g. ``16#FF7FFFFB#``)."""

    radix: int
    digits: str

    @property
    def value(self) -> int:
        return int(self.digits, self.radix)


class Label(dict[str, Any]):
    """Label mapping with case-insensitive lookup; nested objects are ``Label`` too."""

    def find(self, key: str, default: Any = None) -> Any:
        """Value of ``key`` (case-insensitive) at this level, else ``default``."""
        k = key.upper()
        for name, value in self.items():
            if name.upper() == k:
                return value
        return default

    def obj(self, name: str) -> Label | None:
        """The nested ``OBJECT``/``GROUP`` called ``name`` at this level, if any."""
        value = self.find(name)
        return value if isinstance(value, Label) else None

    def walk(self) -> Iterator[tuple[str, Any]]:
        """All ``(key, value)`` pairs, depth first."""
        for name, value in self.items():
            yield name, value
            if isinstance(value, Label):
                yield from value.walk()


_TOKEN = re.compile(
    r"""\s*(?:
        (?P<comment>/\*.*?\*/)
      | (?P<string>"[^"]*")
      | (?P<symbol>'[^']*')
      | (?P<unit><[^>]*>)
      | (?P<punct>[=(){},])
      | (?P<word>[^\s=(){},"'<]+)
    )""",
    re.VERBOSE | re.DOTALL,
)
_BASED = re.compile(r"^([+-]?)(\d+)#([0-9A-Fa-f]+)#$")


def label_length(blob: bytes) -> int:
    """Byte offset just after the ``END`` line of a label at the start of ``blob``."""
    m = re.search(rb"(?m)^\s*END\s*(?:\r?\n|$)", blob)
    if m is None:
        raise DEMReadError("no END statement found: not a PDS3 label")
    return m.end()


def _scalar(word: str) -> Any:
    m = _BASED.match(word)
    if m:
        return Based(int(m.group(2)), m.group(3).upper())
    for cast in (int, float):
        try:
            return cast(word)
        except ValueError:
            pass
    return word


def _tokens(text: str) -> list[tuple[str, str]]:
    out = []
    pos = 0
    n = len(text)
    while pos < n:
        m = _TOKEN.match(text, pos)
        if m is None:
            if text[pos:].strip() == "":
                break
            raise DEMReadError(f"cannot parse PDS3 label near {text[pos:pos + 40]!r}")
        pos = m.end()
        kind = m.lastgroup
        if kind and kind != "comment":
            out.append((kind, m.group(kind)))
    return out


class _Parser:
    def __init__(self, tokens: list[tuple[str, str]]) -> None:
        self.toks = tokens
        self.i = 0

    def peek(self) -> tuple[str, str] | None:
        return self.toks[self.i] if self.i < len(self.toks) else None

    def next(self) -> tuple[str, str]:
        tok = self.peek()
        if tok is None:
            raise DEMReadError("PDS3 label ends in the middle of a statement")
        self.i += 1
        return tok

    def value(self) -> Any:
        kind, text = self.next()
        if kind == "punct" and text in "({":
            items = []
            close = ")" if text == "(" else "}"
            while True:
                tok = self.peek()
                if tok is None:
                    raise DEMReadError("unterminated list in PDS3 label")
                if tok == ("punct", close):
                    self.i += 1
                    break
                if tok == ("punct", ","):
                    self.i += 1
                    continue
                items.append(self.value())
            return tuple(items)
        if kind in ("string", "symbol"):
            val: Any = " ".join(text[1:-1].split())
        elif kind == "word":
            val = _scalar(text)
        else:
            raise DEMReadError(f"unexpected {text!r} in PDS3 label")
        tok = self.peek()
        if tok is not None and tok[0] == "unit":
            self.i += 1
            return Quantity(val, tok[1][1:-1].strip().upper())
        return val

    def block(self, end_words: tuple[str, ...]) -> Label:
        out = Label()
        while True:
            tok = self.peek()
            if tok is None:
                return out
            kind, word = self.next()
            upper = word.upper()
            if kind == "word" and upper in end_words:
                if self.peek() == ("punct", "="):
                    self.i += 2
                return out
            if kind != "word":
                raise DEMReadError(f"expected a keyword in PDS3 label, got {word!r}")
            if self.next() != ("punct", "="):
                raise DEMReadError(f"expected '=' after {word!r} in PDS3 label")
            if upper in ("OBJECT", "GROUP"):
                name = str(self.value())
                out[name] = self.block((f"END_{upper}",))
            else:
                out[word] = self.value()


def parse_label(text: str | bytes) -> Label:
    """Parse PDS3 label text (attached-label bytes may include the image: only the part up to
    ``END`` is read).

    Raises
    ------
    DEMReadError
        The text is not a PDS3 label.
    """
    if isinstance(text, bytes):
        text = text[: label_length(text)].decode("latin-1")
    else:
        text = text[: label_length(text.encode("latin-1", "replace"))]
    label = _Parser(_tokens(text)).block(("END",))
    if label.find("PDS_VERSION_ID") is None and label.find("ODL_VERSION_ID") is None:
        raise DEMReadError("no PDS_VERSION_ID keyword: not a PDS3 label")
    return label
