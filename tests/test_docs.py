"""The README and the documents of docs/ link to each other by relative paths and section
anchors: every link must reach a file of the repository and, with an anchor, one of its
headings (GitHub's rule: lower case, punctuation dropped, spaces to hyphens)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCUMENTS = [
    ROOT / "README.md",
    *sorted((ROOT / "docs").glob("*.md")),
    ROOT / "models" / "MODEL_CARD.md",
]
LINK = re.compile(r"\]\(([^)\s]+)\)")


def anchor(heading: str) -> str:
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    text = path.read_text(encoding="utf-8")
    return {anchor(m.group(1)) for m in re.finditer(r"^#+ (.*)$", text, re.MULTILINE)}


def test_the_anchor_rule() -> None:
    assert anchor("The SOCP runtime's KKT methods") == "the-socp-runtimes-kkt-methods"
    assert anchor("T-SCvx on board (`pdg_solve_tscvx`)") == "t-scvx-on-board-pdg_solve_tscvx"
    assert anchor("Conventions (from DESIGN.md)") == "conventions-from-designmd"


@pytest.mark.parametrize("doc", DOCUMENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_link_reaches_its_file_and_heading(doc: Path) -> None:
    broken = []
    for target in LINK.findall(doc.read_text(encoding="utf-8")):
        if target.startswith(("http://", "https://")):
            continue
        path, _, name = target.partition("#")
        dest = (doc.parent / path).resolve() if path else doc
        if not dest.exists() or (name and dest.suffix == ".md" and name not in anchors(dest)):
            broken.append(target)
    assert not broken, f"{doc.name}: {broken}"
