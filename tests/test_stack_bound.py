"""Static stack bound of the flight C code (guidance/stack_bound.py): every public function has
a bound, the flight code has no recursion and no unbounded frame, the bound covers the
stack the budget drivers measure by painting, and it is small against the memory budget.

The tool is also shown able to fail, on tiny C files compiled here: it finds recursion (direct
and mutual) and a variable-length array, refuses an indirect call it cannot resolve and an
external function without an allowance, and resolves a call through a table of functions to
every function in the table."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from guidance import budget, stack_bound
from guidance.stack_bound import StackCheckError

needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc missing")
needs_build = pytest.mark.skipif(
    shutil.which("gcc") is None or not budget.LIBS[0].exists(),
    reason="gcc or the built library missing (make lib)",
)


# ---- the tool on tiny C files ------------------------------------------------------------------
def _compile(tmp_path: Path, source: str, opt: str = "-O0") -> list[Path]:
    """One unit compiled as the tool expects (-fstack-usage, -fcallgraph-info=su); its .ci."""
    src = tmp_path / "unit.c"
    src.write_text(source)
    cmd = ["gcc", "-std=c99", opt, "-fstack-usage", "-fcallgraph-info=su", "-c", str(src),
           "-o", str(tmp_path / "unit.o")]  # fmt: skip
    subprocess.run(cmd, check=True, cwd=tmp_path, capture_output=True)
    return [tmp_path / "unit.ci"]


def _analyse(tmp_path: Path, source: str, *entries: str) -> dict[str, stack_bound.Bound]:
    return stack_bound.analyse(_compile(tmp_path, source), entries, base=tmp_path)


# (what is wrong, the unit's source, the entry point analysed, what the refusal says)
REFUSALS = [
    (
        "direct recursion",
        "int fact(int n);\nint fact(int n) { return n <= 1 ? 1 : n * fact(n - 1); }\n",
        "fact",
        r"recursion: fact -> fact",
    ),
    (
        "mutual recursion",
        "int odd(int n);\nint even(int n);\n"
        "int even(int n) { return n == 0 ? 1 : odd(n - 1); }\n"
        "int odd(int n) { return n == 0 ? 0 : even(n - 1); }\n"
        "int top(int n);\nint top(int n) { return even(n); }\n",
        "top",
        r"recursion: (even -> odd -> even|odd -> even -> odd)",
    ),
    (
        "variable-length array",
        "double sum(int n);\n"
        "double sum(int n) { volatile double a[n]; double s = 0;\n"
        "  for (int i = 0; i < n; i++) a[i] = i;\n"
        "  for (int i = 0; i < n; i++) s += a[i];\n  return s; }\n",
        "sum",
        r"unbounded stack frame.*sum",
    ),
    (
        "bare function pointer",
        "int apply(int (*fn)(int), int x);\nint apply(int (*fn)(int), int x) { return fn(x); }\n",
        "apply",
        r"indirect call at .*unit.c:2:.*cannot tell",
    ),
    (
        "member no table fills",
        "struct ops { int (*run)(int); };\n"
        "int go(const struct ops *o, int x);\n"
        "int go(const struct ops *o, int x) { return o->run(x) + 1; }\n",
        "go",
        r"unresolved indirect call at .*o->run",
    ),
    (
        "member set from a variable",
        "struct ops { int (*run)(int); };\n"
        "int go(struct ops *o, int (*f)(int), int x);\n"
        "int go(struct ops *o, int (*f)(int), int x) { o->run = f; return o->run(x); }\n",
        "go",
        r"cannot tell what 'f' stored in .run",
    ),
    (
        "table written in a form the reader skips",
        "typedef struct { int (*run)(int); } ops;\n"
        "static int small(int x) { return x; }\n"
        "static int large(int x) { volatile int a[300]; a[0] = x; return a[0]; }\n"
        "static const ops fast = { small };\n"
        "static ops const slow = { large };\n"
        "int go(const ops *o, int x);\n"
        "int go(const ops *o, int x) { return o->run(x) + (&slow != o); }\n",
        "go",
        r"unit.c:5: the address of large is taken, but no table",
    ),
    (
        "external without allowance",
        'int puts(const char *s);\nint hello(void);\nint hello(void) { return puts("hi"); }\n',
        "hello",
        r"hello calls puts.*no stack allowance",
    ),
]


@needs_gcc
@pytest.mark.parametrize(
    ("source", "entry", "refusal"), [r[1:] for r in REFUSALS], ids=[r[0] for r in REFUSALS]
)
def test_the_tool_refuses(tmp_path: Path, source: str, entry: str, refusal: str) -> None:
    with pytest.raises(StackCheckError, match=refusal):
        _analyse(tmp_path, source, entry)


TABLE = """
typedef struct { const char *name; int (*run)(int); } ops;
static int small(int x) { volatile int a[4] = {x, x, x, x}; return a[0] + a[3]; }
static int large(int x) { volatile int a[300]; a[0] = x; a[299] = x; return a[0] + a[299]; }
const ops ops_small = {"small, with a comma", small};
const ops ops_large = {.name = "large", .run = large};
int go(const ops *o, int x);
int go(const ops *o, int x) { return o->run(x) + 1; }
"""


@needs_gcc
def test_a_call_through_a_table_reaches_every_function_of_its_type(tmp_path: Path) -> None:
    bounds = _analyse(tmp_path, TABLE, "go")
    frames = {}
    for line in (tmp_path / "unit.su").read_text().splitlines():
        where, size, _ = line.split("\t")
        frames[where.rsplit(":", 1)[1]] = int(size)
    b = bounds["go"]
    assert b.bytes == frames["go"] + max(frames["small"], frames["large"])
    assert b.path == ["go", "large"]
    assert b.externals == [] and b.callbacks == []


@needs_gcc
def test_it_refuses_a_table_it_cannot_read(tmp_path: Path) -> None:
    # an array of tables would give the member targets the tool does not see
    src = TABLE + 'const ops all_ops[2] = {{"a", small}, {"b", large}};\n'
    with pytest.raises(StackCheckError, match=r"cannot read the initializer"):
        _analyse(tmp_path, src, "go")


# ---- the flight code -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def bounds() -> dict[str, stack_bound.Bound]:
    """Every public function's bound (`make stack-info`: the flight sources compiled for the
    analysis, about 40 s the first time, then kept by make)."""
    return stack_bound.flight_bounds(do_build=True)


@needs_build
def test_every_public_function_has_a_bound(bounds: dict[str, stack_bound.Bound]) -> None:
    public = stack_bound.public_functions()
    assert set(stack_bound.BUDGET_CALLS) <= set(public)
    assert "tscvx_solve" in public and "pdg_setup" in public
    assert set(bounds) == set(public)
    for b in bounds.values():
        assert 0 < b.own_bytes <= b.bytes, b
        assert b.path[0] == b.entry


@needs_build
def test_the_guidance_call_reaches_the_kkt_methods_and_no_amd(
    bounds: dict[str, stack_bound.Bound],
) -> None:
    # both KKT methods are reached through the method table (LDL's numeric and solves by the
    # sparse one); AMD's ordering is set-up only
    b = bounds["pdg_solve"]
    assert {"ldl_numeric", "ldl_lsolve", "snprintf"} <= set(b.externals)
    assert not {"amd_2", "amd_defaults", "ldl_symbolic"} & set(b.externals)
    assert "amd_2" in bounds["tscvx_setup"].externals
    assert set(b.externals) <= set(stack_bound.EXTERNAL_ALLOWANCE)


def _driver_stack(args: list[str], driver: Path = budget.DRIVER) -> int:
    out = subprocess.run([str(driver), *args], capture_output=True, text=True, check=False)
    assert out.returncode in budget.DRIVER_OK, out.stderr[-2000:]
    kv = dict(line.split(" ", 1) for line in out.stdout.splitlines() if " " in line)
    return int(kv["stack_high_water"])


@needs_build
def test_the_bound_covers_the_measured_stack(bounds: dict[str, stack_bound.Bound]) -> None:
    budget.build()
    models = {k: str(v) for k, v in budget.NN_MODELS.items()}
    for variant, (args, function) in budget.VARIANTS.items():
        measured = _driver_stack(["--repeat", "1", *(a.format(**models) for a in args)])
        assert measured <= bounds[function].bytes, (variant, measured, bounds[function])
        # the compiled frames alone come close to it: the painted stack includes libm's
        # frames, the bound each external's allowance
        assert measured <= bounds[function].own_bytes + 512, (variant, measured)
    for path in budget.NN_MODELS.values():
        measured = _driver_stack([str(path), "--repeat", "1"], budget.NN_DRIVER)
        assert measured <= bounds["tscvx_nn_run"].bytes, (path, measured)


@needs_build
def test_the_bound_is_small_against_the_budget(bounds: dict[str, stack_bound.Bound]) -> None:
    deepest = max(b.bytes for b in bounds.values())
    assert deepest <= 32 * 1024  # a flight task's stack of 32 KiB would hold any call
    assert deepest <= budget.MEMORY_BUDGET_B / 1000
