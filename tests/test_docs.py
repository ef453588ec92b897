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


# ---- names the documents cite (drift audit, 28 Nov) ------------------------------------------
# The README and docs/ name make targets, `guidance` options and tests by hand; each check
# below reads what the documents cite and asks the code whether it exists.

HEADERS = sorted((ROOT / "c_runtime" / "include").glob("*.h"))  # their comments cite them too
TEXT = {doc: doc.read_text(encoding="utf-8") for doc in [*DOCUMENTS, *HEADERS]}
SPAN = re.compile(r"`([^`]+)`")  # an inline code span (it may run over a line break)
MAKEFILES = [
    ROOT / "Makefile",
    *sorted((ROOT / "c_runtime").rglob("*.mk")),
    ROOT / "models" / "models.mk",
]


def code_of(text: str) -> list[str]:
    """The inline code spans and the indented code blocks' lines (a trailing backslash joins
    the next line) of a document, each as one line of text."""
    spans = [" ".join(s.split()) for s in SPAN.findall(text)]
    block = re.sub(r"\\\n\s*", " ", text)
    return spans + [line.strip() for line in block.splitlines() if line.startswith("    ")]


def make_rules() -> tuple[set[str], set[str]]:
    """The targets (with $(BUILD) as build; a pattern rule's with its %) and the variables the
    Makefile and its includes define."""
    targets: set[str] = set()
    variables: set[str] = set()
    for path in MAKEFILES:
        for line in path.read_text(encoding="utf-8").splitlines():
            line = line.replace("$(BUILD)", "build")
            if m := re.match(r"^([A-Za-z_][A-Za-z0-9_]*)\s*(?:\?|:|\+)?=", line):
                variables.add(m.group(1))
            elif m := re.match(r"^([^\s:=#$][^:=#]*?)\s*::?(?!=)", line):
                targets.update(m.group(1).split())
    return targets, variables


def is_target(word: str, targets: set[str]) -> bool:
    return any(re.fullmatch(re.escape(t).replace("%", ".+"), word) for t in targets)


def test_make_rules_reads_targets_and_variables() -> None:
    targets, variables = make_rules()
    assert {"lib", "test", "demo", "build/ctest/%"} <= targets
    assert is_target("build/ctest/bench_driver", targets) and not is_target("tests", targets)
    assert {"VENV", "MODELS_N_BASE"} <= variables


@pytest.mark.parametrize("doc", TEXT, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_make_target_named_is_a_rule(doc: Path) -> None:
    """`make X [VAR=value]` in the documents: X is a target of the Makefile or its includes,
    VAR one of their variables."""
    targets, variables = make_rules()
    unknown = []
    for code in code_of(TEXT[doc]):
        for args in re.findall(r"(?:^|[;&|(]\s*)make((?: [^\s#;&|)]+)+)", code):
            for word in args.split():
                name, eq, _ = word.partition("=")
                if word.startswith("-"):
                    continue
                if (eq and name not in variables) or (not eq and not is_target(word, targets)):
                    unknown.append(f"make {word}")
    assert not unknown, f"{doc.name}: {unknown}"


def cli_options() -> dict[str, set[str]]:
    """Each `guidance` subcommand's option strings ("" for the top-level parser's)."""
    from guidance import cli

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.choices and isinstance(a.choices, dict))
    options = {"": {s for a in parser._actions for s in a.option_strings}}
    for name, p in sub.choices.items():
        options[name] = {s for a in p._actions for s in a.option_strings}
    return options


def named_options(text: str) -> list[tuple[str, str]]:
    """(subcommand, --option) of each `guidance SUB ... --option` in the code of a document:
    an option belongs to the last subcommand named before it in its line."""
    found = []
    for code in code_of(text):
        for part in re.split(r"(?:^|[\s/])guidance(?= )", code)[1:]:
            words = part.split()
            sub = words[0] if words and not words[0].startswith("-") else ""
            found += [(sub, o) for o in re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", part)]
    return found


def test_named_options_reads_the_subcommand_of_each_option() -> None:
    text = "`guidance solve --method tscvx`\n    .venv/bin/guidance verify a.npz \\\n  --tol-path 1"
    assert named_options(text) == [("solve", "--method"), ("verify", "--tol-path")]
    assert named_options("`python -m guidance.bench_socp --quick`, `guidance --version`") == [
        ("", "--version")
    ]


@pytest.mark.parametrize("doc", TEXT, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_guidance_option_named_exists(doc: Path) -> None:
    """`guidance SUB --flag` in the documents: SUB is a subcommand and --flag one of its
    options (argparse would take a unique prefix, a reader would not know it is one)."""
    options = cli_options()
    unknown = [
        f"guidance {sub} {opt}" if sub in options else f"guidance {sub}"
        for sub, opt in named_options(TEXT[doc])
        if opt not in options.get(sub, set())
    ]
    assert not unknown, f"{doc.name}: {unknown}"


def test_every_module_option_named_exists() -> None:
    """`python -m guidance.MODULE --flag` in the documents: the module defines --flag."""
    unknown = []
    for doc, text in TEXT.items():
        for code in code_of(text):
            for module, args in re.findall(r"-m (guidance\.[\w.]+)((?: [^\s`]+)*)", code):
                source = (ROOT / (module.replace(".", "/") + ".py")).read_text(encoding="utf-8")
                for opt in re.findall(r"--[a-z][a-z0-9-]*", args):
                    if f'"{opt}"' not in source:
                        unknown.append(f"{doc.name}: {module} {opt}")
    assert not unknown, unknown


TEST_DIRS = [
    ROOT / "tests",
    *sorted((ROOT / "c_runtime").glob("*/tests")),
    ROOT / "c_runtime" / "tests",
]


def test_names() -> set[str]:
    """Test files (without suffix) and the test functions they define, Python and C."""
    names: set[str] = set()
    for folder in TEST_DIRS:
        for path in [*folder.glob("test_*.py"), *folder.glob("test_*.c")]:
            names.add(path.stem)
            text = path.read_text(encoding="utf-8")
            names.update(re.findall(r"^(?:def|static\s+\w+)\s+(test_\w+)\s*\(", text, re.MULTILINE))
    return names


test_names.__test__ = False  # type: ignore[attr-defined]  # a helper, not a test


@pytest.mark.parametrize("doc", TEXT, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_test_cited_exists(doc: Path) -> None:
    """A test cited by name (`test_x`, `tests/test_x.py`, `tests/test_x.py::test_y`; a name
    ending in _ or * is a family) is a test file or a test function of tests/ or the C tests."""
    names = test_names()
    cited = re.findall(r"\b(test_\w+?)(?:\.py|\.c)?\b(?![*])", TEXT[doc])
    unknown = sorted({n for n in cited if not n.endswith("_") and n not in names})
    assert not unknown, f"{doc.name}: {unknown}"
