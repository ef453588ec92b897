"""Scenario contract: every kind of bad input gets a clear error naming the field, exit 2."""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from guidance.cli import main
from guidance.errors import InputError
from guidance.params import ALPHA_MIN, Params, SCvxSettings
from guidance.scenario import ScenarioError, load_scenario, scenario_from_dict

GOOD = {
    "r0": [4, 4, 0],
    "v0": [0, -1, -2],
    "q0": [1, 0, 0, 0],
    "w0": [0, 0, 0],
    "m0": 3.0,
    "glideslope_deg": 20.0,
    "tilt_max_deg": 90.0,
}

BAD = [
    ({"colour": 1}, "colour"),
    ({"r0": [4, 4]}, "r0"),
    ({"v0": [0, -1, "x"]}, "v0"),
    ({"m0": float("nan")}, "m0"),
    ({"m0": 10**400}, "m0"),  # an integer no float holds (JSON allows it)
    ({"r0": [4, 10**400, 0]}, "r0"),
    ({"r0": [4, float("inf"), 0]}, "r0"),
    ({"q0": [1, 0.1, 0, 0]}, "q0"),
    ({"m0": 2.0}, "m0"),
    ({"m0": 1.5}, "m0"),
    ({"r0": [1, 4, 0]}, "r0"),  # below the 20 deg glideslope cone
    ({"tilt_max_deg": 10.0, "q0": [0.9659258262890683, 0, 0.25881904510252074, 0]}, "q0"),
    ({"w0": [0, 2.0, 0]}, "w0"),  # |w0| above 90 deg/U_T
    ({"w0": [0.1, 0, 0]}, "w0"),  # roll rate cannot change
    ({"omega_f": [0.1, 0, 0]}, "omega_f"),  # the same conflict, caused by the terminal rate
    ({"T_min": 6.0}, "T_min"),
    ({"N": 2}, "N"),
    ({"final_roll_free": "yes"}, "final_roll_free"),
    ({"J_B": [0.001, 0.01]}, "J_B"),
    # DESIGN.md's format has these keys; a missing one is not quietly the default landing's
    ({"m0": None}, "m0"),
    ({"r0": None}, "r0"),
    ({"tilt_max_deg": None}, "tilt_max_deg"),
    # terminal states outside the path constraints of the last node
    ({"omega_f": [0, 0, 2.0]}, "omega_f"),
    ({"q_f": [0, 0, 1, 0], "final_roll_free": False}, "q_f"),
    ({"q_f": [0.9800665778412416, 0, 0.19866933079506122, 0]}, "q_f"),  # roll-free but tilted
    ({"r_f": [0, 1, 0]}, "r_f"),
    # a final velocity that reaches the landing point (on the cone's boundary) from outside
    # the glideslope cone: accepted until 27 Nov, then "solved" below the surface or outside
    # the cone between the last two nodes
    ({"v_f": [0.1, 0, 0]}, "v_f"),  # rising out of the ground at touchdown (e1 is up)
    ({"v_f": [0, 0.3, 0]}, "v_f"),  # sliding in along the surface
    ({"v_f": [0.1, 0, 0], "glideslope_deg": 0.0}, "v_f"),
]


def _with(change: dict) -> dict:
    """GOOD with the change applied; a None value removes the key."""
    data = {**GOOD, **change}
    return {k: v for k, v in data.items() if v is not None}


@pytest.mark.parametrize(("change", "field"), BAD)
def test_bad_scenario_is_rejected_naming_the_field(change: dict, field: str) -> None:
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(_with(change))
    assert err.value.field == field
    assert field in str(err.value)


@pytest.mark.parametrize(("change", "field"), BAD)
def test_cli_exit_code_2_and_nothing_written(
    change: dict, field: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "s.json"
    # allow_nan writes NaN / Infinity literals, which the loader must reject by field
    path.write_text(json.dumps(_with(change), allow_nan=True))
    out, fig = tmp_path / "t.npz", tmp_path / "t.png"
    code = main(["solve", str(path), "--out", str(out), "--plot", str(fig)])
    assert code == 2
    assert field in capsys.readouterr().err
    assert not out.exists() and not fig.exists()


def test_unreadable_and_malformed_files(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["solve", str(tmp_path / "missing.json")]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["solve", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("error: scenario file: ") == 2 and "field" not in err


def test_values_are_shown_as_json() -> None:
    with pytest.raises(ScenarioError, match="expected a number, got true"):
        scenario_from_dict({**GOOD, "m0": True})


def test_pinned_attitude_from_either_sign_of_q0() -> None:
    """q0 and -q0 are the same attitude: the pinned q(t_f) = q_f is reached from both, by the
    same turn (the target is taken in q0's hemisphere), to the same landing."""
    from guidance.scvx import solve_scvx

    landings = []
    for sign in (1, -1):
        scn = scenario_from_dict({**GOOD, "q0": [sign, 0, 0, 0], "final_roll_free": False})
        np.testing.assert_array_equal(scn.x_final_target()[6:10], [sign, 0, 0, 0])
        landings.append(solve_scvx(scn))
    assert [r.status for r in landings] == ["solved", "solved"]
    assert landings[1].m_f == pytest.approx(landings[0].m_f, rel=1e-9)
    np.testing.assert_allclose(landings[1].x[:, 6:10], -landings[0].x[:, 6:10], atol=1e-9)


def test_bad_settings_exit_2_naming_the_setting(capsys: pytest.CaptureFixture[str]) -> None:
    for value in ("0", "101", "-3", "2.5", "many"):
        with pytest.raises(SystemExit) as exc:
            main(["solve", "--iter-max", value])
        assert exc.value.code == 2
        assert "--iter-max" in capsys.readouterr().err
    bad = {"iter_max": 0, "socp_max_iter": 501, "lam": float("inf"), "rho1": -1.0,
           "alpha": 0.5, "socp_tol": 1.0, "vc_tol": -1e-9}  # fmt: skip
    for name, value in bad.items():
        with pytest.raises(ValueError, match=name):
            SCvxSettings(**{name: value})  # type: ignore[arg-type]


def test_counts_and_figure_format_are_checked_before_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for args in (["agreement", "--landings", "-1"], ["agreement", "--workers", "-1"],
                 ["bench", "--repeats", "0"]):  # fmt: skip
        with pytest.raises(SystemExit) as exc:
            main(args)
        assert exc.value.code == 2
    out = tmp_path / "t.npz"
    assert main(["solve", "--out", str(out), "--plot", str(tmp_path / "fig.xyz")]) == 2
    assert "unknown figure format 'xyz'" in capsys.readouterr().err
    assert not out.exists()
    (tmp_path / "a_file").write_text("")
    os.mkfifo(tmp_path / "a_pipe")  # as /dev/full would be: a root run replaced the device
    refused = {
        "--trust-update: applies to --method tscvx only": ["--trust-update", "alg1"],
        f"--out {tmp_path}: is a folder": ["--out", str(tmp_path)],
        "--plot": ["--out", str(out), "--plot", str(tmp_path / "a_file" / "fig.png")],
        "--out /proc/t.npz: cannot write there": ["--out", "/proc/t.npz"],
        "a_pipe: is a device, pipe or socket": ["--out", str(tmp_path / "a_pipe")],
    }
    for message, args in refused.items():
        assert main(["solve", *args]) == 2, args
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, err
        assert not out.exists()
    assert stat.S_ISFIFO((tmp_path / "a_pipe").stat().st_mode)  # left as it was


def test_missing_models_and_data_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Model folders and data files the user names are input too: a message, not a trace."""
    for backend in ("clarabel", "c"):
        code = main(["solve", "--method", "tscvx", "--backend", backend, "--models",
                     str(tmp_path)])  # fmt: skip
        assert code == 2, backend
        assert capsys.readouterr().err.startswith("error: ")
    assert main(["baselines", "--dataset", str(tmp_path / "none.npz")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_corrupt_models_and_data_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Files that exist but are not what they are named: a message, not a trace."""
    for kind in ("solution", "constraint"):
        (tmp_path / f"{kind}.onnx").write_text("not a model")
    for backend in ("clarabel", "c"):
        code = main(["solve", "--method", "tscvx", "--backend", backend, "--models",
                     str(tmp_path)])  # fmt: skip
        assert code == 2, backend
        err = capsys.readouterr().err
        assert err.startswith("error: ") and "Traceback" not in err, err
    (tmp_path / "solution.onnx").write_bytes(b"")  # parses as an empty ONNX model
    assert main(["solve", "--method", "tscvx", "--backend", "c", "--models", str(tmp_path)]) == 2
    assert "not a T-SCvx model export" in capsys.readouterr().err
    (tmp_path / "text.npz").write_text("garbage")
    (tmp_path / "empty.npz").write_bytes(b"")
    np.save(tmp_path / "array.npy", np.zeros(3))
    header = np.array(json.dumps({"format": "tscvx-dataset", "format_version": 1}))
    np.savez(tmp_path / "layout.npz", header=header, theta=np.zeros(3))
    expect = {
        "text.npz": "not a readable .npz",
        "empty.npz": "not a readable .npz",
        "array.npy": "a single array",
        "layout.npz": "arrays do not match the tscvx-dataset layout",
    }
    for name, words in expect.items():
        for cmd in (["train", "--train-dir", str(tmp_path / "t")], ["baselines"]):
            assert main([*cmd, "--dataset", str(tmp_path / name)]) == 2
            err = capsys.readouterr().err
            assert err.startswith("error: ") and words in err, (name, err)


def test_a_key_given_twice_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "twice.json"
    path.write_text(json.dumps(GOOD)[:-1] + ', "m0": 2.5}')  # json would keep the last
    with pytest.raises(ScenarioError, match="scenario field 'm0': given twice"):
        load_scenario(path)


def test_parameter_override_and_defaults() -> None:
    s = scenario_from_dict({**GOOD, "T_max": 4.5, "final_roll_free": False, "N": 30})
    assert s.params.T_max == 4.5 and s.params.N == 30 and not s.params.final_roll_free
    p = Params()
    # derived values of DESIGN.md
    assert p.alpha_mdot == pytest.approx(1 / 30)
    assert p.beta_mdot == pytest.approx(0.1 * 0.5 / 30)
    assert p.aero_coeff == pytest.approx(0.1)
    assert p.J_B == (0.001, 0.01, 0.01)


@pytest.mark.parametrize("weight", ["-0.01", "nan", "inf", "heavy", "0.1", "10"])
def test_bad_proximal_weight_exits_2(weight: str, capsys: pytest.CaptureFixture[str]) -> None:
    for command in ("solve", "agreement"):
        with pytest.raises(SystemExit) as exc:
            main([command, "--prox-u", weight])
        assert exc.value.code == 2
        assert "--prox-u" in capsys.readouterr().err
    with pytest.raises(InputError, match="prox_u"):
        SCvxSettings(prox_u=float("nan") if weight == "heavy" else float(weight))


@pytest.mark.parametrize("radius", ["0", "-1", "20", "nan", "inf", "wide"])
def test_bad_initial_radius_exits_2(radius: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["solve", "--eta-init", radius])
    assert exc.value.code == 2
    assert "--eta-init" in capsys.readouterr().err
    with pytest.raises(InputError, match=r"eta_init must (lie within \[eta_lb, eta_ub\]|be fin)"):
        SCvxSettings(eta_init=float("nan") if radius == "wide" else float(radius))


# Limits of _validate_params (scenario.py) and SCvxSettings.__post_init__ (params.py): the
# first value past each limit is refused naming the field, the last one inside is accepted.
OVER_THE_LIMIT = [
    ({"N": 401}, "N"),
    ({"T_min": 5.0, "T_max": 5.0}, "T_min"),
    ({"tilt_max_deg": 181.0}, "tilt_max_deg"),
    ({"gimbal_max_deg": 90.0}, "gimbal_max_deg"),
]
JUST_INSIDE = [{"N": 400}, {"N": 3}, {"T_min": 4.999, "T_max": 5.0}, {"tilt_max_deg": 180.0},
               {"gimbal_max_deg": 89.9},
               # touchdown at rest, or along the cone's edge; rising to a point above the cone's
               # apex; any horizontal velocity on the ground without a glideslope
               {"v_f": (0.0, 0.0, 0.0)}, {"v_f": (-1.0, 0.0, 1.0 / math.tan(math.radians(20)))},
               {"v_f": (0.1, 0.0, 0.0), "r_f": (1.0, 0.0, 0.0)},
               {"v_f": (0.0, 0.3, 0.0), "glideslope_deg": 0.0}]  # fmt: skip


@pytest.mark.parametrize(("change", "field"), OVER_THE_LIMIT)
def test_parameter_past_its_limit_is_refused_naming_it(change: dict, field: str) -> None:
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(_with(change))
    assert err.value.field == field
    assert f"'{field}'" in str(err.value)


@pytest.mark.parametrize("change", JUST_INSIDE)
def test_parameter_just_inside_its_limit_is_accepted(change: dict) -> None:
    scn = scenario_from_dict(_with(change))
    for key, value in change.items():
        assert getattr(scn.params, key) == value


def test_trust_region_factors_and_ratio_thresholds_are_checked() -> None:
    with pytest.raises(ValueError, match="beta"):
        SCvxSettings(beta=0.5)
    with pytest.raises(ValueError, match="rho1 <= rho2"):
        SCvxSettings(rho1=0.8, rho2=0.7)
    with pytest.raises(ValueError, match="rho0 <= rho1"):
        SCvxSettings(rho0=0.2, rho1=0.1)
    # the limits themselves are allowed: alpha at ALPHA_MIN, beta = 1 (no growth)
    assert SCvxSettings(alpha=ALPHA_MIN, beta=1.0).beta == 1.0
    # alpha = 1 retried a rejected step at the same radius until max_subproblems was spent
    for alpha in (1.0, 1.001, 1.09):
        with pytest.raises(ValueError, match=rf"^alpha must be >= {ALPHA_MIN:g}"):
            SCvxSettings(alpha=alpha)
    assert SCvxSettings(rho0=0.7, rho1=0.7, rho2=0.7).rho1 == 0.7


def test_scenario_all_lists_every_parameter_and_reads_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`guidance scenario --all` prints every parameter a scenario file may set (an override
    kept, the rest at their defaults), and the printed file is the same scenario."""
    path = tmp_path / "s.json"
    path.write_text(json.dumps({**GOOD, "T_max": 4.5}))
    assert main(["scenario", "--all", str(path)]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert set(Params().to_json_dict()) <= set(printed)
    assert printed["T_max"] == 4.5 and printed["m_dry"] == Params().m_dry
    assert scenario_from_dict(printed) == scenario_from_dict({**GOOD, "T_max": 4.5})


def test_the_printed_scenario_lists_only_what_differs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`guidance scenario` (and the solve's first line) show the overrides only; --all every
    parameter: what a file written by the package holds."""
    from guidance.scenario import scenario_to_dict

    path = tmp_path / "s.json"
    path.write_text(json.dumps({**GOOD, "T_max": 4.5}))
    assert main(["scenario", str(path)]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown == {**GOOD, "T_max": 4.5}
    assert set(scenario_to_dict(load_scenario(path))) == set(GOOD) | set(Params().to_json_dict())


@pytest.mark.parametrize("content", ["utf16", "digits", "nested"])
def test_unreadable_scenario_files_are_refused_by_name(content: str, tmp_path: Path) -> None:
    """A UTF-16 file (what some shells write), an integer of 5,000 digits and arrays nested
    100,000 deep escaped load_scenario as UnicodeDecodeError, ValueError and RecursionError
    (a traceback, exit 1); each is now a ScenarioError of the file (exit 2)."""
    path = tmp_path / "s.json"
    if content == "utf16":
        path.write_text(json.dumps({"m0": 3.0}), encoding="utf-16")
    elif content == "digits":
        path.write_text('{"m0": ' + "3" * 5000 + "}")
    else:
        path.write_text('{"r0": ' + "[" * 100_000 + "]" * 100_000 + "}")
    with pytest.raises(ScenarioError, match=r"scenario file: .* is not (UTF-8 text|valid JSON)"):
        load_scenario(path)
    assert main(["scenario", str(path)]) == 2


def test_a_scenario_file_starting_with_a_byte_order_mark_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Audit of 28 Nov: a scenario file saved as "UTF-8 with BOM" (Windows editors) was
    refused as not valid JSON; RFC 8259 lets a parser ignore the mark, and every JSON file
    is now read so (guidance.json_files.load_json). A mark elsewhere is no JSON."""
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps({**GOOD, "T_max": 4.5}).encode())
    assert load_scenario(path) == scenario_from_dict({**GOOD, "T_max": 4.5})
    assert main(["scenario", str(path)]) == 0
    assert json.loads(capsys.readouterr().out)["T_max"] == 4.5
    path.write_bytes(b"\xef\xbb\xbf\xef\xbb\xbf" + json.dumps(GOOD).encode())
    with pytest.raises(ScenarioError, match="is not valid JSON"):
        load_scenario(path)
