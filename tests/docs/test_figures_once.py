"""A speed figure on a guide page comes from a results page (issue 48).

The guide pages (``docs/*.md``) state what is true now; measured figures, with their machine
and date, live on the results pages (``docs/results/*.md``). Render times, write times and
real-time factors are the figures most often restated on a guide page and then left behind when
the results page is re-measured. So a guide page that states one, a duration in ms or µs, or a
factor "N× real time", "N× faster" or "N× slower", must

1. link a results page in the same paragraph (a blank-line-separated block: prose, a list or
   a table), and
2. take each number of the figure from a linked results page (``12 ms`` or ``38–47 ms``
   there, with the same unit), so a rounded or stale figure ("about 40–50 ms") fails.

Otherwise the guide says it in words ("tens of milliseconds") and links the results.
Durations that are settings, not measurements, are exempt: a physics step, a firing interval,
a test's sleep, a time constant, the exposure cap, a test's clock offset (``_SETTING_*``).
"""

from __future__ import annotations

import re
from pathlib import Path

DOCS = Path(__file__).resolve().parents[2] / "docs"

_CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)
_NUM = r"\d[\d,]*(?:\.\d+)?"
_FIGURE = re.compile(
    rf"(?P<a>{_NUM})(?:\s*[–-]\s*(?P<b>{_NUM}))?\s*"
    r"(?:(?P<unit>ms|µs)\b|(?P<x>×)\s*(?:real[- ]time|faster|slower)\b)"
)
# What a results page states: the same figures, a "×" figure in any context (table cells).
_STATED = re.compile(rf"(?P<a>{_NUM})(?:\s*[–-]\s*(?P<b>{_NUM}))?\s*(?P<unit>ms|µs|×)")
# Settings: "a 2 ms step", "2.304 µs apart", "20 ms at the default 50 Hz", "a 3 ms offset",
# "1 ms → 100 ms" (after the figure); "every 2 ms", "sleeping 200 ms", "30 steps of 1 ms",
# "time constant (20 ms)" (before it).
_SETTING_AFTER = re.compile(r"\s*\)?\s*(?:steps?\b|apart\b|at the default\b|offset\b|→)", re.I)
_SETTING_BEFORE = re.compile(r"(?:\bevery|\bsleep\w*|\bsteps of|\bconstant \(|→)\s*$", re.I)
_RESULTS_LINK = re.compile(r"\]\((?:\./)?results/(?P<page>[\w-]+)\.md|</?results/(?P<doc>[\w-]+)>")

# Guide pages left out, each with its reason.
EXEMPT: dict[str, str] = {
    "changelog.md": "includes the changelog, whose entries are dated history",
}


def _numbers(m: re.Match[str]) -> list[str]:
    return [n.replace(",", "") for n in (m.group("a"), m.group("b")) if n]


def _stated(page: str) -> set[tuple[str, str]]:
    text = (DOCS / "results" / f"{page}.md").read_text(encoding="utf-8")
    return {(n, m.group("unit")) for m in _STATED.finditer(text) for n in _numbers(m)}


def unsourced_figures(text: str) -> list[str]:
    """The speed figures of a guide page's text that break the rule, with the reason."""
    found = []
    for para in re.split(r"\n\s*\n", _CODE.sub(" ", text)):
        pages = {m.group("page") or m.group("doc") for m in _RESULTS_LINK.finditer(para)}
        stated = set().union(*(_stated(p) for p in pages)) if pages else set()
        for m in _FIGURE.finditer(para):
            if _SETTING_AFTER.match(para, m.end()) or _SETTING_BEFORE.search(para[: m.start()]):
                continue
            unit = m.group("unit") or "×"
            if not pages:
                found.append(f"{m.group()!r}: no results page linked in its paragraph")
            elif missing := [n for n in _numbers(m) if (n, unit) not in stated]:
                where = ", ".join(sorted(f"results/{p}.md" for p in pages))
                found.append(f"{m.group()!r}: {'/'.join(missing)} {unit} not stated in {where}")
    return found


def test_guide_speed_figures_come_from_a_linked_results_page() -> None:
    found = []
    for page in sorted(DOCS.glob("*.md")):
        if page.name not in EXEMPT:
            found += [f"{page.name}: {f}" for f in unsourced_figures(page.read_text("utf-8"))]
    assert not found, "state it in words or quote a linked results page:\n" + "\n".join(found)


def test_the_rule_catches_a_rounded_or_unlinked_figure() -> None:
    linked = "A frame renders in about 40–50 ms ([results](results/camera.md))."
    assert unsourced_figures(linked) == ["'40–50 ms': 50 ms not stated in results/camera.md"]
    assert unsourced_figures("It costs 24 ms per image (Performance).") == [
        "'24 ms': no results page linked in its paragraph"
    ]
    assert unsourced_figures("Steps of 2 ms; lasers 2.304 µs apart; a 10 ms step.") == []
    assert unsourced_figures("At 3 ms a frame on a GPU ([results](results/camera.md)).") == []
