"""Static worst-case stack bound of the flight C code, and its proof of no recursion.

    python -m guidance.stack_bound [--no-build] [--json]

``make stack-info`` (c_runtime/stack.mk) compiles every flight source (SOCP runtime, guidance,
networks, the generated model) again with the flight build's own flags -- inlining decides the
frames -- and GCC's ``-fstack-usage -fcallgraph-info=su``, into build/stack/. This module reads
the frames (.su: bytes and qualifier) and the call graph (.ci), and checks:

- no function has a dynamic, unbounded frame (a VLA or alloca: qualifier ``dynamic`` without
  ``bounded``; GCC's ``dynamic,bounded`` frames are counted at the bound GCC states);
- every indirect call is resolved to the functions it may reach (``resolve_site``): the call
  ``kk->backend->solve(...)`` goes through the member ``solve`` of the struct type its holder
  ``backend`` is declared with, and may reach every function a table of that type puts there
  (``tscvx_method_sparse``, ``tscvx_method_banded``, the LDL backends) or an assignment stores
  there (``opt.mask_fn = network_mask``); a member of a public struct may also hold the
  caller's own callback. A call site the tool cannot resolve so is refused, never ignored;
- no call graph cycle (no recursion), over every function compiled;
- every function called outside the compiled set (libc, libm, SuiteSparse) has a stated
  allowance (EXTERNAL_ALLOWANCE; a new one is refused until it has one).

The bound of a function is its frame plus the largest bound among what it calls (an
external's allowance; a caller's callback adds nothing: its depth is the caller's to add).
GCC's x86-64 frame sizes include the return address, so a bound compares with a stack
painted below the caller's frame (``stack_high_water`` of the budget drivers).
"""

from __future__ import annotations

import argparse
import functools
import json
import re
import subprocess
import sys
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from guidance.errors import LibraryNotBuiltError
from guidance.paths import BUILD_DIR, ROOT

STACK_DIR = BUILD_DIR / "stack"
UNITS = STACK_DIR / "units"  # written by `make stack-info`: the .ci files, one a line
PUBLIC_HEADERS = sorted((ROOT / "c_runtime" / "include").glob("*.h"))
# The guidance call of the budget (guidance/budget.py) and the network inference.
BUDGET_CALLS = ("pdg_solve", "pdg_solve_tscvx", "tscvx_nn_run")
INDIRECT = "__indirect_call"
CALLBACK = "caller's callback"

# Stack allowance of each function called outside the compiled set, in bytes (with its own
# callees). Not a proof: figures of the host's libraries, measured or compiled (docs/budget.md,
# "The static stack bound"), with margin; the flight OS's libc and libm need their own.
#   libm (glibc 2.36, x86-64): stack painted around each over edge arguments (0, +-1, 1e-300,
#     1e300, 7e22, pi/2, 710, -745, NaN, inf, subnormals): 24 to 192 B.
#   memcpy, memset, memcmp: leaf routines, 8 B painted.
#   snprintf, vsnprintf: glibc's printf, 4,552 B painted for the flight code's formats
#     (%g, %.17g, %.9g, %.3f, %d, %s) over the same arguments; %.3f of DBL_MAX (309 digits
#     built on the stack) is the deepest.
#   AMD, LDL (SuiteSparse 5.12, Debian's sources compiled -O3 -fstack-usage): amd_2 with
#     amd_postorder and amd_post_tree 528 B (+ memset, sqrt); ldl_* at most 56 B, leaves.
LIBM_ALLOWANCE = 512
EXTERNAL_ALLOWANCE: dict[str, int] = {
    **dict.fromkeys(("acos", "cos", "exp", "pow", "sincos", "tan", "sqrt", "fmax", "fmin"),
                    LIBM_ALLOWANCE),
    **dict.fromkeys(("memcpy", "memset", "memcmp"), 256),
    **dict.fromkeys(("snprintf", "vsnprintf"), 8192),
    **dict.fromkeys(("amd_2", "amd_defaults"), 1024),
    **dict.fromkeys(("ldl_symbolic", "ldl_numeric", "ldl_lsolve", "ldl_dsolve",
                     "ldl_ltsolve"), 256),
}  # fmt: skip


class StackCheckError(RuntimeError):
    """The code breaks a rule the bound rests on (recursion, an unbounded frame), or the tool
    cannot see all of a call (an unresolved indirect call, an external without allowance)."""


@dataclass(frozen=True)
class Frame:
    name: str  # as GCC names it (clones: build.part.0, f.constprop.0)
    location: str  # file:line:col of the definition
    bytes: int
    qualifier: str  # static | dynamic,bounded | dynamic


@dataclass
class CallGraph:
    frames: dict[str, Frame] = field(default_factory=dict)  # node -> frame (compiled set)
    calls: dict[str, set[str]] = field(default_factory=dict)  # node -> nodes or externals
    indirect: dict[str, set[str]] = field(default_factory=dict)  # node -> call sites
    sources: set[Path] = field(default_factory=set)  # the units' C files
    base: Path = ROOT  # the folder the compiler ran in (the .ci's paths are relative to it)

    def function(self, name: str, file: Path) -> str | None:
        """The node a function name in `file` refers to: its static function, else the global."""
        for node, f in self.frames.items():
            if ":" in node and f.name == name and self.source(f) == file.resolve():
                return node
        return name if name in self.frames else None

    def source(self, f: Frame) -> Path:
        return (self.base / f.location.rsplit(":", 2)[0]).resolve()

    def node(self, name: str) -> str:
        """The node of a global function by its C name."""
        if name not in self.frames:
            raise StackCheckError(f"{name} is not defined in the compiled flight sources")
        return name


@dataclass
class Bound:
    entry: str
    bytes: int  # frames + external allowances on the deepest path
    own_bytes: int  # the compiled frames alone (externals at 0): the proven part
    path: list[str]  # the deepest path, entry first (externals as named)
    externals: list[str]  # external functions reachable (any path)
    callbacks: list[str]  # caller's callbacks reachable: their depth comes on top


# ---- reading GCC's output ----------------------------------------------------------------
_CI_NODE = re.compile(r'^node: \{ title: "([^"]+)" label: "([^"]*)"(.*)\}$')
_CI_EDGE = re.compile(
    r'^edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"(?: label: "([^"]*)")? \}$'
)
_CI_FRAME = re.compile(r"^(\S+)\\n(\S+)\\n(\d+) bytes \(([\w,]+)\)$")


def _unit_id(title: str, unit: Path) -> str:
    """Globals by name; a static function (GCC titles it file:name) by unit and name, since
    a static inline function of a header is a different function in each unit."""
    return f"{unit.stem}@{title}" if ":" in title else title


def parse_unit(ci: Path, graph: CallGraph) -> None:
    """Adds one unit's frames, calls and indirect call sites (its .ci and .su) to graph."""
    frames: list[Frame] = []
    for line in ci.read_text().splitlines():
        if m := _CI_NODE.match(line):
            title, label, rest = m.groups()
            if "ellipse" in rest:
                continue  # declared here, defined elsewhere (or outside the compiled set)
            f = _CI_FRAME.match(label)
            if f is None:
                raise StackCheckError(f"{ci}: no frame size for {title} ({label!r})")
            node = _unit_id(title, ci)
            if node in graph.frames:
                raise StackCheckError(f"{node} is defined twice ({ci})")
            frame = Frame(f.group(1), f.group(2), int(f.group(3)), f.group(4))
            graph.frames[node] = frame
            graph.calls.setdefault(node, set())
            frames.append(frame)
            graph.sources.add(graph.source(frame))
        elif m := _CI_EDGE.match(line):
            src, dst, site = m.groups()
            s = _unit_id(src, ci)
            if dst == INDIRECT:
                if not site:
                    raise StackCheckError(f"{ci}: an indirect call of {src} without its place")
                graph.indirect.setdefault(s, set()).add(site)
            else:
                graph.calls.setdefault(s, set()).add(_unit_id(dst, ci))
        elif line.startswith(("node:", "edge:")):  # never skip a call unread
            raise StackCheckError(f"{ci}: cannot read {line!r}")
    _check_su(ci.with_suffix(".su"), frames)


def _check_su(su: Path, frames: list[Frame]) -> None:
    """The .su file must say what the .ci says: the same frames, sizes and qualifiers."""
    if not su.is_file():
        raise StackCheckError(f"{su} missing: compile with -fstack-usage")
    listed = sorted(tuple(line.split("\t")) for line in su.read_text().splitlines() if line)
    seen = sorted((f"{f.location}:{f.name}", str(f.bytes), f.qualifier) for f in frames)
    if listed != seen:
        raise StackCheckError(f"{su} and its .ci disagree on the frames")


def load(ci_files: Iterable[Path], base: Path = ROOT) -> CallGraph:
    graph = CallGraph(base=base)
    for ci in ci_files:
        parse_unit(ci, graph)
    return graph


# ---- indirect calls: the function-pointer members and what may be in them -------------------
_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
_STRING = re.compile(r'"(?:\\.|[^"\\])*"')
_STRUCT = re.compile(
    r"typedef\s+struct\s*\w*\s*\{(?P<body>[^{}]*)\}\s*(?P<name>\w+)\s*;"
    r"|struct\s+(?P<tag>\w+)\s*\{(?P<tbody>[^{}]*)\}\s*;"
)
_FN_TYPEDEF = re.compile(r"typedef\s+[^;()]*\(\s*\*\s*(\w+)\s*\)\s*\(")
_FN_FIELD = re.compile(r"\(\s*\*\s*(\w+)\s*\)\s*\(")
_INIT = re.compile(r"\b(\w+)\s+(\w+)\s*=\s*\{(?P<body>[^{};]*)\}\s*;")
_MEMBER_SET = re.compile(r"(?:\.|->)\s*(\w+)\s*=(?!=)\s*([^;]+);")
_CHAIN = re.compile(r"\(?\s*([A-Za-z_]\w*(?:\s*(?:->|\.)\s*[A-Za-z_]\w*)*)\s*\(")


def _clean(text: str) -> str:
    return _STRING.sub('""', _COMMENT.sub(" ", text))


@dataclass
class Seams:
    """Struct types with function-pointer members: field order, and each member's targets."""

    fields: dict[str, list[tuple[str, bool]]] = field(default_factory=dict)  # type -> (name, fn?)
    targets: dict[tuple[str, str], set[str]] = field(default_factory=dict)
    texts: dict[Path, str] = field(default_factory=dict)  # cleaned sources and headers

    def fn_members(self, member: str) -> list[str]:
        return [t for t, fs in self.fields.items() if (member, True) in fs]


def _fields(body: str, fn_types: set[str]) -> list[tuple[str, bool]]:
    out = []
    for decl in body.split(";"):
        if not decl.strip():
            continue
        if m := _FN_FIELD.search(decl):
            out.append((m.group(1), True))
            continue
        words = re.findall(r"[A-Za-z_]\w*", decl.split("[")[0])
        is_fn = bool(set(words) & fn_types)
        for piece in decl.split(","):
            names = re.findall(r"[A-Za-z_]\w*", piece.split("[")[0])
            if names:
                out.append((names[-1], is_fn))
    return out


def find_seams(graph: CallGraph, files: Iterable[Path], public: Iterable[Path]) -> Seams:
    """Every struct type with function-pointer members, and every function each member may
    hold: table initializers (positional or designated), member assignments, and for a
    public struct the caller's callback. An assignment of anything else is refused."""
    seams = Seams(texts={p: _clean(p.read_text()) for p in files})
    public = {p.resolve() for p in public}
    fn_types = {m for t in seams.texts.values() for m in _FN_TYPEDEF.findall(t)}
    public_types: set[str] = set()
    for path, text in seams.texts.items():
        for m in _STRUCT.finditer(text):
            name, body = (m["name"], m["body"]) if m["name"] else (m["tag"], m["tbody"])
            fs = _fields(body, fn_types)
            if any(is_fn for _, is_fn in fs):
                seams.fields[name] = fs
                if path.resolve() in public:
                    public_types.add(name)
    for t in public_types:  # the caller may put its own function in any of these
        for member, is_fn in seams.fields[t]:
            if is_fn:
                seams.targets.setdefault((t, member), set()).add(f"{CALLBACK} {member}")
    for path, text in seams.texts.items():
        function = functools.partial(graph.function, file=path)
        _table_targets(seams, text, function)
        _assigned_targets(seams, text, function, public_types)
    return seams


def _table_targets(seams: Seams, text: str, function: Callable[[str], str | None]) -> None:
    read = set()
    for m in _INIT.finditer(text):
        t = m.group(1)
        if t not in seams.fields:
            continue
        read.add(m.start(1))
        entries = [x.strip() for x in m["body"].split(",")]
        for i, entry in enumerate(e for e in entries if e):
            d = re.fullmatch(r"\.(\w+)\s*=\s*(.+)", entry)
            member, value = (d.group(1), d.group(2)) if d else (seams.fields[t][i][0], entry)
            value = value.lstrip("&").strip()
            if dict(seams.fields[t]).get(member) and (node := function(value)):
                seams.targets.setdefault((t, member), set()).add(node)
            elif dict(seams.fields[t]).get(member) and value not in ("NULL", "0"):
                raise StackCheckError(f"{t} {m.group(2)}: .{member} = {value} is no function")
    for t in seams.fields:  # an array of tables, a compound literal: not read, so refused
        for m in re.finditer(rf"\b{t}\s+\w+\s*(?:\[[^\]]*\])?\s*=\s*\{{|\(\s*{t}\s*\)\s*\{{", text):
            if m.start() not in read:
                raise StackCheckError(
                    f"cannot read the initializer {m.group(0)!r}: a table of {t} is read "
                    "only as `T name = {...};`"
                )


def _assigned_targets(
    seams: Seams, text: str, function: Callable[[str], str | None], public: set[str]
) -> None:
    for m in _MEMBER_SET.finditer(text):
        member, value = m.group(1), m.group(2).strip().lstrip("&").strip()
        types = seams.fn_members(member)
        if not types:
            continue  # not a function-pointer member
        if node := function(value):
            new = {node}
        elif value in ("NULL", "0"):
            continue
        elif (tail := re.fullmatch(r".*(?:->|\.)\s*(\w+)", value)) and any(
            (t, tail.group(1)) in seams.targets and t in public for t in seams.fields
        ):
            new = {f"{CALLBACK} {tail.group(1)}"}
        else:
            raise StackCheckError(
                f"cannot tell what {value!r} stored in .{member} may point to: assign a "
                "function by name, or teach guidance/stack_bound.py the new seam"
            )
        for t in types:
            seams.targets.setdefault((t, member), set()).update(new)


_NOT_CALLED = re.compile(r"(?<![\w.>])([A-Za-z_]\w*)\b(?!\s*\()")


def check_address_taken(graph: CallGraph, seams: Seams) -> None:
    """Every compiled function named other than in a call (its address taken: a table entry,
    an assignment, an argument) must be one the seams hold, or an indirect call could reach
    it unseen: a table the readers above do not know (`T const name = {...}`, a nested
    initializer, a cast) would leave the bound short without a word."""
    held: set[str] = set().union(*seams.targets.values()) if seams.targets else set()
    names = {f.name for f in graph.frames.values()}
    for path, text in seams.texts.items():
        for m in _NOT_CALLED.finditer(text):
            if m.group(1) not in names:
                continue
            target = graph.function(m.group(1), path)
            if target is not None and target not in held:
                line = text.count("\n", 0, m.start()) + 1
                raise StackCheckError(
                    f"{path.name}:{line}: the address of {m.group(1)} is taken, but no table "
                    "or assignment the tool reads holds it: an indirect call could reach it "
                    "unseen (write the table as `T name = {...};`, or teach "
                    "guidance/stack_bound.py the new form)"
                )


def resolve_site(site: str, seams: Seams, base: Path = ROOT) -> set[str]:
    """The functions an indirect call at file:line:col may reach, or StackCheckError."""
    file, line, col = site.rsplit(":", 2)
    path = (base / file).resolve()
    text = path.read_text().splitlines()
    rest = "\n".join([text[int(line) - 1][int(col) - 1 :], *text[int(line) : int(line) + 3]])
    m = _CHAIN.match(_clean(rest))
    parts = re.split(r"\s*(?:->|\.)\s*", m.group(1)) if m else []
    if len(parts) < 2:
        raise StackCheckError(
            f"indirect call at {site} ({rest.splitlines()[0].strip()!r}) is not a call through "
            "a struct member: the tool cannot tell what it reaches"
        )
    holder, member = parts[-2], parts[-1]
    pattern = re.compile(rf"\b(\w+)\s*(?:\*\s*)*(?:const\s+)?\b{holder}\s*[;,=)\[]")
    scope = [seams.texts.get(path, _clean(path.read_text()))]
    scope += [t for p, t in seams.texts.items() if p.suffix == ".h"]
    types = {t for s in scope for t in pattern.findall(s) if (member, True) in
             seams.fields.get(t, [])}  # fmt: skip
    targets = set().union(*(seams.targets.get((t, member), set()) for t in types))
    if not targets:
        raise StackCheckError(
            f"unresolved indirect call at {site}: {holder}->{member} "
            f"({'of no known struct type' if not types else ', '.join(sorted(types))}, "
            "no table or assignment gives it a function)"
        )
    return targets


def resolve_indirect(graph: CallGraph, seams: Seams, base: Path = ROOT) -> None:
    """Replaces every indirect call site by edges to its possible targets."""
    for node, sites in graph.indirect.items():
        for site in sorted(sites):
            graph.calls.setdefault(node, set()).update(resolve_site(site, seams, base))


# ---- the checks and the bound --------------------------------------------------------------
def check_frames(graph: CallGraph) -> None:
    bad = [f"{f.name} ({f.location}, {f.bytes} B {f.qualifier})" for f in graph.frames.values()
           if "dynamic" in f.qualifier and "bounded" not in f.qualifier]  # fmt: skip
    if bad:
        raise StackCheckError(
            "unbounded stack frame (a variable-length array or alloca): " + "; ".join(bad)
        )


def _label(graph: CallGraph, node: str) -> str:
    return graph.frames[node].name if node in graph.frames else node


def depths(graph: CallGraph, externals: bool = True) -> dict[str, tuple[int, str | None]]:
    """Bound of every function: (bytes, the callee on its deepest path); without
    `externals`, the compiled frames alone (every external at 0). Refuses a cycle."""
    memo: dict[str, tuple[int, str | None]] = {}
    for root in sorted(graph.frames):
        if root in memo:
            continue
        stack: list[tuple[str, list[str]]] = [(root, sorted(graph.calls.get(root, ())))]
        on_path = {root}
        while stack:
            node, todo = stack[-1]
            if todo:
                callee = todo.pop()
                if callee in on_path:
                    cycle = [n for n, _ in stack][[n for n, _ in stack].index(callee) :]
                    raise StackCheckError(
                        "recursion: " + " -> ".join(_label(graph, n) for n in [*cycle, callee])
                    )
                if callee in graph.frames and callee not in memo:
                    stack.append((callee, sorted(graph.calls.get(callee, ()))))
                    on_path.add(callee)
                continue
            stack.pop()
            on_path.discard(node)
            best: tuple[int, str | None] = (0, None)
            for callee in sorted(graph.calls.get(node, ())):
                d = (memo[callee][0] if callee in graph.frames
                     else _external(graph, node, callee) if externals else 0)  # fmt: skip
                if d > best[0] or best[1] is None:
                    best = (d, callee)
            memo[node] = (graph.frames[node].bytes + best[0], best[1])
    return memo


def _external(graph: CallGraph, caller: str, name: str) -> int:
    if name.startswith(CALLBACK):
        return 0
    if name not in EXTERNAL_ALLOWANCE:
        raise StackCheckError(
            f"{_label(graph, caller)} calls {name}, outside the compiled set, which has no "
            "stack allowance (guidance/stack_bound.py EXTERNAL_ALLOWANCE)"
        )
    return EXTERNAL_ALLOWANCE[name]


def _reachable(graph: CallGraph, entry: str) -> set[str]:
    seen, todo = {entry}, [entry]
    while todo:
        for callee in graph.calls.get(todo.pop(), ()):
            if callee not in seen:
                seen.add(callee)
                if callee in graph.frames:
                    todo.append(callee)
    return seen


def bound(
    graph: CallGraph,
    memo: dict[str, tuple[int, str | None]],
    own: dict[str, tuple[int, str | None]],
    entry: str,
) -> Bound:
    node = graph.node(entry)
    path: list[str] = []
    cur: str | None = node
    while cur is not None:
        path.append(_label(graph, cur))
        cur = memo[cur][1] if cur in memo else None
    outside = sorted(n for n in _reachable(graph, node) if n not in graph.frames)
    return Bound(
        entry=entry,
        bytes=memo[node][0],
        own_bytes=own[node][0],
        path=path,
        externals=[n for n in outside if not n.startswith(CALLBACK)],
        callbacks=[n for n in outside if n.startswith(CALLBACK)],
    )


_PROTOTYPE = re.compile(
    r"^(?!typedef|static|#|extern\s+const)[A-Za-z_][\w \t\*]*?\b(\w+)\s*\([^;{}]*\)\s*;", re.M
)


def public_functions(headers: Iterable[Path] = PUBLIC_HEADERS) -> list[str]:
    """The functions declared by the public headers (static inline helpers excluded)."""
    names: list[str] = []
    for h in headers:
        names += [n for n in _PROTOTYPE.findall(_clean(h.read_text())) if n not in names]
    return names


def analyse(
    ci_files: Iterable[Path],
    entries: Iterable[str],
    base: Path = ROOT,
    headers: Iterable[Path] = (),
    public: Iterable[Path] = (),
) -> dict[str, Bound]:
    """Every check, then the bound of each entry point. `headers`: where the struct types
    are declared; `public`: those of them whose structs the caller fills."""
    graph = load(ci_files, base)
    check_frames(graph)
    files = sorted(graph.sources | {p.resolve() for p in (*headers, *public)})
    seams = find_seams(graph, files, public)
    check_address_taken(graph, seams)
    resolve_indirect(graph, seams, base)
    memo, own = depths(graph), depths(graph, externals=False)
    return {e: bound(graph, memo, own, e) for e in entries}


def build(quiet: bool = True) -> None:
    """`make stack-info`: the flight sources compiled for the analysis (kept up to date by
    make; the library's objects untouched)."""
    cmd = ["make", "-s", "-j2", "-C", str(ROOT), "stack-info"]
    subprocess.run(cmd, check=True, capture_output=quiet)


def flight_bounds(do_build: bool = True) -> dict[str, Bound]:
    """The bound of every public function of the flight library."""
    if do_build:
        build()
    if not UNITS.is_file():
        raise LibraryNotBuiltError(f"{UNITS} not found: run `make stack-info` (or drop --no-build)")
    units = [ROOT / line for line in UNITS.read_text().split()]
    headers = sorted({*PUBLIC_HEADERS, *(ROOT / "c_runtime").glob("*/*.h"),
                      *(BUILD_DIR / "generated").glob("*.h")})  # fmt: skip
    return analyse(units, public_functions(), ROOT, headers, PUBLIC_HEADERS)


def report(bounds: dict[str, Bound]) -> str:
    lines = [
        "Static stack bound of the flight library (GCC -fstack-usage / -fcallgraph-info, "
        "flight flags): no recursion, no unbounded frame, every indirect call resolved",
        f"  {'entry point':32s} {'bound':>8s} {'own':>8s}  deepest path (own: the compiled "
        "frames alone, externals at 0)",
    ]
    for b in sorted(bounds.values(), key=lambda b: -b.bytes):
        path = " > ".join(b.path)
        lines.append(f"  {b.entry:32s} {b.bytes:6d} B {b.own_bytes:6d} B  {path}")
    calls = [bounds[c] for c in BUDGET_CALLS if c in bounds]
    for b in calls:
        lines.append(f"  {b.entry} reaches outside the compiled set: {', '.join(b.externals)}")
        if b.callbacks:
            names = ", ".join(c.removeprefix(CALLBACK + " ") for c in b.callbacks)
            lines.append(f"    and the caller's callbacks (their own depth on top): {names}")
    lines.append("  externals counted at their allowance (guidance/stack_bound.py, docs/budget.md)")
    return "\n".join(lines)


def summary(bounds: dict[str, Bound], measured: dict[str, int]) -> str:
    """The budget's calls: bound, its compiled part, and the painted high-water beside it
    (`measured`: function -> the largest high-water painted in its calls)."""
    lines = [
        "Static stack bound (python -m guidance.stack_bound: every public function; no "
        "recursion, no unbounded frame, every indirect call resolved)",
        f"  {'call':16s} {'bound':>8s} {'compiled frames':>16s} {'painted, largest':>17s}  "
        "deepest path",
    ]
    for fn, high in sorted(measured.items(), key=lambda kv: BUDGET_CALLS.index(kv[0])):
        b = bounds[fn]
        lines.append(f"  {fn:16s} {b.bytes:6d} B {b.own_bytes:14d} B {high:15d} B  "
                     f"{' > '.join(b.path)}")  # fmt: skip
    lines.append(
        "  bound: compiled frames on the deepest path + each external's allowance (libc, libm, "
        "SuiteSparse: docs/budget.md); the budget's memory counts the bound"
    )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m guidance.stack_bound",
                                 description=__doc__.splitlines()[0])  # fmt: skip
    ap.add_argument("--no-build", action="store_true", help="use build/stack as it is")
    ap.add_argument("--json", action="store_true", help="print the bounds as JSON")
    args = ap.parse_args(argv)
    try:
        bounds = flight_bounds(do_build=not args.no_build)
    except StackCheckError as exc:
        print(f"stack check failed: {exc}", file=sys.stderr)
        return 1
    except LibraryNotBuiltError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps({k: asdict(v) for k, v in bounds.items()}, indent=2))
    else:
        print(report(bounds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
