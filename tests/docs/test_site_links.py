"""Every internal link and image of the built site resolves (pages, files and #anchors).

The Sphinx build already fails on a broken cross-reference (``-W``, MyST's ``xref_missing``);
this test checks the written HTML itself, so a link that Sphinx passes through unchecked (a raw
``href``, a template, an image) cannot break either.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit


class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.refs: list[tuple[str, str]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        for key in ("id", "name"):
            if a.get(key):
                self.ids.add(str(a[key]))
        for key in ("href", "src"):
            value = a.get(key)
            if value and not (tag == "link" and a.get("rel") in ("preload", "prefetch")):
                self.refs.append((tag, value))


def _parse(path: Path) -> _Links:
    p = _Links()
    p.feed(path.read_text(encoding="utf-8"))
    return p


def test_internal_links_and_images_resolve(site_dir: Path) -> None:
    pages = sorted(site_dir.rglob("*.html"))
    pages = [p for p in pages if not {"_static", "_sources"} & set(p.relative_to(site_dir).parts)]
    assert len(pages) > 50
    parsed = {p.resolve(): _parse(p) for p in pages}
    broken: list[str] = []
    for page, links in parsed.items():
        for tag, ref in links.refs:
            parts = urlsplit(ref)
            if parts.scheme or ref.startswith(("//", "mailto:", "javascript:", "data:")):
                continue  # external: not checked offline
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(site_dir.resolve())}: <{tag}> {ref}")
                continue
            if parts.fragment and target.suffix == ".html" and target in parsed:
                if parts.fragment not in parsed[target].ids:
                    broken.append(f"{page.relative_to(site_dir.resolve())}: #{parts.fragment} "
                                  f"not in {target.name}")
    assert not broken, "\n".join(broken[:40])


def test_no_page_cites_the_internal_science_notes(site_dir: Path) -> None:
    offenders = [p.name for p in site_dir.rglob("*.html")
                 if re.search(r"SCIENCE\.md", p.read_text(encoding="utf-8"))]
    assert not offenders
