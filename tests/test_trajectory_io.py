"""Trajectory .npz files (guidance/trajectory_io.py): what is written is read back."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from c_library import needs_c_library

from guidance.errors import InputError
from guidance.params import NC, InitialState, Params, Scenario, SCvxSettings
from guidance.scvx import SCvxResult
from guidance.trajectory_io import REQUIRED_KEYS, read_trajectory, write_trajectory

N = 5


def _result(status: str, reason: str) -> SCvxResult:
    x = np.arange(N * 14, dtype=float).reshape(N, 14)
    u = np.full((N, 3), 0.5)
    masks = np.zeros((2, NC * N), np.uint8)
    masks[1, 3] = 1
    return SCvxResult(status, reason, x, u, 4.25, 7, 9, 0.125, masks=masks,
                      settings=SCvxSettings(iter_max=7))  # fmt: skip


@pytest.mark.parametrize(
    ("status", "reason"),
    [("infeasible", "virtual control 0.3 > 1e-06"), ("max_iterations", "iteration limit")],
)
def test_status_and_fields_are_read_back(tmp_path: Path, status: str, reason: str) -> None:
    path = tmp_path / "t.npz"
    p = Params(N=N)
    write_trajectory(path, _result(status, reason), p, Scenario(params=p), "scvx", "clarabel")
    d = read_trajectory(path)
    assert str(d["status"]) == status
    assert str(d["reason"]) == reason
    assert float(d["t_f"]) == 4.25 and int(d["iterations"]) == 7
    assert float(d["solve_time_s"]) == 0.125
    np.testing.assert_array_equal(d["x"], np.arange(N * 14).reshape(N, 14))
    np.testing.assert_array_equal(d["u"], np.full((N, 3), 0.5))
    assert d["masks"].shape == (2, NC * N) and d["masks"].sum() == 1
    assert d["params"]["N"] == N  # type: ignore[index]
    assert d["settings"]["iter_max"] == 7  # type: ignore[index]
    assert int(d["rk4_steps_per_interval"]) == 25  # 98 steps over N - 1 = 4 intervals
    assert str(d["method"]) == "scvx" and str(d["backend"]) == "clarabel"


@pytest.mark.parametrize("missing", ["t_f", "status"])
def test_a_file_missing_a_required_key_is_refused(tmp_path: Path, missing: str) -> None:
    path = tmp_path / "t.npz"
    p = Params(N=N)
    write_trajectory(path, _result("solved", "converged"), p, Scenario(params=p), "scvx", "c")
    with np.load(path) as data:
        kept = {k: data[k] for k in data.files if k != missing}
    bad = tmp_path / "bad.npz"
    np.savez(bad, **kept)
    assert missing in REQUIRED_KEYS
    with pytest.raises(ValueError, match=f"not a trajectory file, missing {missing}"):
        read_trajectory(bad)


def _rewritten(tmp_path: Path, **changes: object) -> Path:
    """A written trajectory file with some entries replaced, as another tool could write it."""
    path = tmp_path / "t.npz"
    p = Params(N=N)
    write_trajectory(path, _result("solved", "converged"), p, Scenario(params=p), "scvx", "c")
    with np.load(path) as data:
        entries = {k: data[k] for k in data.files}
    bad = tmp_path / "bad.npz"
    np.savez(bad, **{**entries, **changes})
    return bad


@pytest.mark.parametrize(
    ("entry", "key"),
    [("params", "N"), ("scenario", "r0"), ("settings", "iter_max")],
)
def test_a_json_key_given_twice_is_refused(tmp_path: Path, entry: str, key: str) -> None:
    """json.loads kept the last of two equal keys: a file could say N = 5 and N = 6."""
    with np.load(_rewritten(tmp_path)) as data:
        text = str(data[entry])
    doubled = text.replace("{", f'{{"{key}": 6, ', 1)
    bad = _rewritten(tmp_path, **{entry: np.str_(doubled)})
    with pytest.raises(
        InputError, match=rf"{re.escape(str(bad))}: {entry}: key '{key}' given twice"
    ):
        read_trajectory(bad)


def test_a_json_key_given_twice_in_a_nested_object_is_refused(tmp_path: Path) -> None:
    nested = '{"params": {"N": 5, "N": 6}}'
    bad = _rewritten(tmp_path, scenario=np.str_(nested))
    with pytest.raises(InputError, match="scenario: key 'N' given twice"):
        read_trajectory(bad)


@pytest.mark.parametrize("reason", ["stopped\x00", "a\x00b", "\x00"])
def test_a_text_with_a_nul_is_refused_before_writing(tmp_path: Path, reason: str) -> None:
    """A reason ending in NUL was written and read back without it (numpy's fixed-width
    strings are NUL-padded): the contract's texts hold no NUL, refused before any file or
    folder is made."""
    path = tmp_path / "new" / "t.npz"
    p = Params(N=N)
    with pytest.raises(InputError, match=r"reason .* holds a NUL character"):
        write_trajectory(path, _result("solved", reason), p, Scenario(params=p), "scvx", "c")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("key", ["status", "method", "backend"])
def test_every_text_entry_is_checked_for_nul_on_writing(tmp_path: Path, key: str) -> None:
    text = {"status": "solved", "method": "scvx", "backend": "c", key: "x\x00"}
    p = Params(N=N)
    result = _result(text["status"], "converged")
    with pytest.raises(InputError, match=rf"{key} .* holds a NUL character"):
        write_trajectory(
            tmp_path / "t.npz", result, p, Scenario(params=p), text["method"], text["backend"]
        )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("key", ["status", "reason", "method"])
def test_a_file_with_a_nul_in_its_text_is_refused(tmp_path: Path, key: str) -> None:
    """A file another tool wrote with a NUL inside a text (a trailing one reads back as
    padding): refused on reading too, naming the file and the entry."""
    bad = _rewritten(tmp_path, **{key: np.str_("sol\x00ved")})
    with pytest.raises(InputError, match=rf"{re.escape(str(bad))}: {key} .* holds a NUL character"):
        read_trajectory(bad)


def test_json_texts_keep_their_nul_characters(tmp_path: Path) -> None:
    """A NUL inside a JSON value is written escaped (\\u0000) and round-trips."""
    prov = '{"note": "end\\u0000"}'
    data = read_trajectory(_rewritten(tmp_path, provenance=np.str_(prov)))
    assert data["provenance"] == {"note": "end\x00"}


@pytest.mark.parametrize(
    ("backend", "library"), [("c", "libtscvx_gnc.so"), ("c-socp", "libtscvx.so")]
)
def test_a_file_solved_in_c_names_the_library_build(
    backend: str, library: str, tmp_path: Path
) -> None:
    """Review of 27 Nov: a trajectory solved in the C library recorded the git commit of its
    sources but nothing of the binary that solved it (a stale build/ would go unseen). Its
    provenance names the library and its sha256, checked here against the file's bytes."""
    import hashlib

    from guidance import cgnc, csocp
    from guidance.cli import main

    out = tmp_path / "t.npz"
    assert main(["solve", "--backend", backend, "--out", str(out)]) == 0
    recorded = read_trajectory(out)["provenance"]["files"]["c_library"]  # type: ignore[index]
    # the library the bindings load (build/, or make coverage's instrumented one)
    lib = cgnc.LIB_PATH if backend == "c" else csocp.library_path()
    assert lib.name == library
    assert recorded == {"path": str(lib), "sha256": hashlib.sha256(lib.read_bytes()).hexdigest()}


@pytest.mark.parametrize(
    ("entry", "value"),
    [
        ("t_f", np.array([4.25])),  # DESIGN.md: a scalar
        ("t_f", np.float64(np.nan)),
        ("t_f", np.bool_(True)),
        ("iterations", np.str_("7")),
        ("iterations", np.float64(7.0)),  # a count is an integer
        ("iterations", np.int64(-1)),
        ("iterations", np.arange(3)),
        ("solve_time_s", np.float64(np.nan)),
        ("solve_time_s", np.str_("0.125")),
        ("solve_time_s", np.float64(-0.5)),
    ],
)
def test_a_contract_scalar_of_the_wrong_kind_is_refused(
    tmp_path: Path, entry: str, value: np.ndarray
) -> None:
    """Audit of 28 Nov: DESIGN.md fixes t_f (scalar), iterations (int), solve_time_s (float),
    but only status was checked: iterations = "7" or NaN and t_f = [4.25] were read as
    trajectory files (and `guidance verify` passed them)."""
    bad = _rewritten(tmp_path, **{entry: value})
    with pytest.raises(InputError, match=rf"{re.escape(str(bad))}: {entry}: expected one"):
        read_trajectory(bad)


@pytest.mark.parametrize("entry", ["params", "scenario", "settings", "provenance"])
@pytest.mark.parametrize(
    ("value", "problem"),
    [
        (np.str_("{not json"), "is not valid JSON"),
        (np.str_('{"N": ' + "9" * 5000 + "}"), "is not valid JSON"),
        (np.arange(3.0), "must be a JSON text"),
    ],
)
def test_a_json_entry_that_is_no_json_text_is_named(
    tmp_path: Path, entry: str, value: np.ndarray, problem: str
) -> None:
    """Audit of 28 Nov: a params (or scenario, settings, provenance) entry that was not JSON
    made the whole file "damaged (not an .npz numpy can read)", which it is not; the entry is
    named and what is wrong with it said."""
    bad = _rewritten(tmp_path, **{entry: value})
    with pytest.raises(InputError) as exc:
        read_trajectory(bad)
    assert f"{bad}: not a readable trajectory file: its {entry} entry {problem}" in str(exc.value)
    assert "damaged" not in str(exc.value)


@needs_c_library
def test_every_backend_writes_the_same_contract(tmp_path: Path) -> None:
    """What `guidance solve --out` writes, read back: the same entries with the same dtypes
    and shapes whichever backend solved it (a coarse grid keeps it quick), the
    discretization that ran (audit of 28 Nov: every file said "auto", and the C loop's
    "auto" or "casadi" discretized in C all the same) and the C builds that computed it."""
    from guidance.cli import main

    scenario = tmp_path / "s.json"
    scenario.write_text(
        '{"r0": [4, 4, 0], "v0": [0, -1, -2], "q0": [1, 0, 0, 0], "w0": [0, 0, 0], '
        '"m0": 3.0, "glideslope_deg": 20.0, "tilt_max_deg": 90.0, "N": 20}'
    )
    layouts, builds = {}, {}
    for backend in ("clarabel", "c-socp", "c"):
        out = tmp_path / f"{backend}.npz"
        assert main(["solve", str(scenario), "--backend", backend, "--out", str(out)]) == 0
        d = read_trajectory(out)
        layouts[backend] = {  # masks: one row per iteration, which the backends may differ in
            k: (v.dtype.kind, v.shape[k == "masks" :]) if isinstance(v, np.ndarray) else sorted(v)  # type: ignore[call-overload]
            for k, v in d.items()
            if k != "provenance"  # its files differ: the C library that solved it
        }
        assert d["x"].shape == (20, 14) and d["u"].shape == (20, 3)  # type: ignore[union-attr]
        assert d["masks"].shape[1] == NC * 20  # type: ignore[union-attr]
        assert d["scenario"]["N"] == d["params"]["N"] == 20  # type: ignore[index]
        assert d["settings"]["discretization"] == "c"  # type: ignore[index]
        builds[backend] = set(d["provenance"]["files"])  # type: ignore[index]
    assert builds == {
        "clarabel": {"c_discretization"},
        "c-socp": {"c_library", "c_discretization"},
        "c": {"c_library"},
    }
    assert layouts["c-socp"] == layouts["clarabel"] == layouts["c"]


def _no_trajectory() -> SCvxResult:
    nan = float("nan")
    return SCvxResult("solver_error", "the first subproblem failed", np.full((N, 14), nan),
                      np.full((N, 3), nan), nan, 0, 0, 0.01)  # fmt: skip


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("params_not_the_scenarios", "params and scenario disagree on T_max"),
        ("another_N", r"x is \(5, 14\), the params ask for \(6, 14\)"),
        ("no_trajectory", r"no trajectory to write \(status solver_error"),
        ("non_unit_q0", "scenario field 'q0': must be a unit quaternion"),
    ],
)
def test_the_writer_refuses_a_file_the_readers_would(
    tmp_path: Path, case: str, message: str
) -> None:
    """Audit of 28 Nov: write_trajectory (guidance.write_trajectory) wrote whatever it was
    given: params that were not the scenario's, x of another N than the params', a solve
    without a trajectory (t_f NaN), a scenario a scenario file could not hold. Each file was
    then refused by read_trajectory or guidance verify; the writer now refuses it, and
    writes nothing."""
    p = Params(N=N)
    result, params, scenario = _result("solved", "converged"), p, Scenario(params=p)
    if case == "params_not_the_scenarios":
        params = p.replace(T_max=4.0)
    elif case == "another_N":
        params = Params(N=N + 1)
        scenario = Scenario(params=params)
    elif case == "non_unit_q0":  # verify refused its scenario entry
        scenario = Scenario(InitialState(q0=(1.0, 0.5, 0.0, 0.0)), p)
    else:
        result = _no_trajectory()
    path = tmp_path / "new" / "t.npz"
    with pytest.raises(InputError, match=message):
        write_trajectory(path, result, params, scenario, "scvx", "c")
    assert list(tmp_path.iterdir()) == []


def test_a_scenario_of_numpy_numbers_is_written_as_json_numbers(tmp_path: Path) -> None:
    """Audit of 28 Nov: a Scenario built in Python with numpy float32 values (which
    guidance.solve takes) made write_trajectory raise json's TypeError (a traceback); it is
    written with the values as floats, as the solve used them."""
    r0 = tuple(np.array([4.0, 4.0, 0.5], np.float32))
    p = Params(N=N, T_max=np.float32(4.5))  # type: ignore[arg-type]
    scenario = Scenario(InitialState(r0=r0), p)  # type: ignore[arg-type]
    path = tmp_path / "t.npz"
    write_trajectory(path, _result("solved", "converged"), p, scenario, "scvx", "c")
    d = read_trajectory(path)
    assert d["scenario"]["r0"] == [4.0, 4.0, 0.5]  # type: ignore[index]
    assert d["params"]["T_max"] == d["scenario"]["T_max"] == 4.5  # type: ignore[index]


def test_the_scenario_entry_carries_every_parameter(tmp_path: Path) -> None:
    """Audit of 28 Nov: the scenario entry listed only the parameters that differed from the
    defaults, so a changed default would read an old file with the new value (guidance verify
    then refused it: "params and scenario disagree"). A data file carries every parameter it
    was made with (DESIGN.md)."""
    from guidance.params import PARAM_NAMES
    from guidance.scenario import scenario_from_dict

    p = Params(N=N, T_max=4.5)
    path = tmp_path / "t.npz"
    write_trajectory(path, _result("solved", "converged"), p, Scenario(params=p), "scvx", "c")
    entry = read_trajectory(path)["scenario"]
    assert set(PARAM_NAMES) <= set(entry)  # type: ignore[arg-type]
    assert entry == {**entry, **p.to_json_dict()}  # type: ignore[dict-item]
    assert scenario_from_dict(entry) == Scenario(params=p)  # type: ignore[arg-type]


@pytest.mark.parametrize("status", ["converged", "SOLVED", "invalid_input", ""])
def test_a_status_no_solver_writes_is_refused(tmp_path: Path, status: str) -> None:
    """Audit of 28 Nov: any text was read (and shown by guidance verify) as a file's status.
    Only the solvers' (scvx.STATUSES) are: another is refused naming the file and the
    statuses, on reading and, before anything is written, on writing."""
    bad = _rewritten(tmp_path, status=np.str_(status))
    with pytest.raises(
        InputError, match=rf"{re.escape(str(bad))}: status '{status}' is none the solvers write"
    ):
        read_trajectory(bad)
    p = Params(N=N)
    path = tmp_path / "new" / "t.npz"
    with pytest.raises(InputError, match="solved, infeasible, max_iterations, solver_error"):
        write_trajectory(path, _result(status, "?"), p, Scenario(params=p), "scvx", "c")
    assert not path.parent.exists()


def test_every_status_a_solver_ends_with_is_read_back(tmp_path: Path) -> None:
    from guidance.cguidance import STATUS_NAMES
    from guidance.scvx import STATUSES

    assert STATUS_NAMES[: len(STATUSES)] == STATUSES  # the C library's, in pdg_status order
    p = Params(N=N)
    for status in STATUSES:
        path = tmp_path / f"{status}.npz"
        write_trajectory(path, _result(status, "why"), p, Scenario(params=p), "scvx", "c")
        assert str(read_trajectory(path)["status"]) == status
