"""The guide states what is true now: a dated measurement belongs on a results page
(docs/results/), so no guide or science page carries a date of the project's own time (2025
on) outside code: the dates of science (epochs, leap seconds, landings) and the UTC times users
type in code stay."""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"
_CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)
_DATE = re.compile(r"\b20(2[5-9]|[3-9]\d)-[01]\d-[0-3]\d\b")


def test_no_guide_page_carries_a_measurement_date() -> None:
    found = []
    for page in sorted(DOCS.rglob("*.md")):
        rel = page.relative_to(DOCS)
        if rel.parts[0] in ("results", "_build") or rel.name == "changelog.md":
            continue
        prose = _CODE.sub("", page.read_text(encoding="utf-8"))
        found += [f"{rel}: {m.group()}" for m in _DATE.finditer(prose)]
    assert not found, "dated figures belong on docs/results/ pages: " + ", ".join(found)
