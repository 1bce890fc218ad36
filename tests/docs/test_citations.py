"""Every author–year citation in the docs resolves to an entry of docs/science/references.md."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
REFERENCES = (DOCS / "science" / "references.md").read_text(encoding="utf-8")
#: "Name (2001)", "Name 2001", "Name et al. 2001", "Name & Other (2001)", "Name and Other 2001"
CITATION = re.compile(r"\b([A-Z][a-zA-Zéèöüá\-]+)(?: et al\.| (?:&|and) [A-Z][a-zA-Zéèöü\-]+)?,? "
                      r"\(?((?:19|20)\d\d)\b")
NOT_NAMES = {"Ga", "Ma", "Eq", "Eqs", "Table", "Figure", "Mars", "Sec", "Std", "IEEE", "MY",
             "Before", "After", "Since"}


def test_every_citation_is_in_the_reference_list() -> None:
    pages = [p for p in DOCS.rglob("*.md") if p.name != "references.md"
             and "_build" not in p.parts and "generated" not in p.parts]
    missing: list[str] = []
    for page in pages:
        for m in CITATION.finditer(page.read_text(encoding="utf-8")):
            name, year = m.group(1), m.group(2)
            if name in NOT_NAMES or int(year) >= 2026:  # 2026-...: dates of measurements
                continue
            if not re.search(rf"{re.escape(name)}\b[^\n]*\n?[^\n]*\(?{year}", REFERENCES):
                missing.append(f"{page.relative_to(DOCS)}: {m.group(0)}")
    assert not missing, "\n".join(sorted(set(missing)))
