"""The package's public names and the README's Python example, run as written."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import guidance

README = Path(__file__).resolve().parent.parent / "README.md"


def _readme_example() -> str:
    text = README.read_text()
    blocks = re.findall(r"## From Python\n.*?```python\n(.*?)```", text, re.S)
    assert len(blocks) == 1, "README: one python block under 'From Python'"
    return blocks[0]


def test_every_exported_name_resolves() -> None:
    for name in guidance.__all__:
        assert getattr(guidance, name) is not None


def test_the_readme_example_runs_and_lands() -> None:
    namespace: dict[str, object] = {}
    exec(compile(_readme_example(), str(README), "exec"), namespace)
    result, warm, check = namespace["result"], namespace["warm"], namespace["check"]
    assert result.status == "solved", result.reason
    assert warm.status == "solved", warm.reason
    replan, onward = namespace["replan"], namespace["onward"]
    assert replan.status == "solved", replan.reason
    assert onward.status == "solved", onward.reason  # in flight, from the plan's remainder
    assert check.landing_position_error <= 1e-3 and check.max_path_violation <= 1e-6
    assert np.isfinite(check.path_between_nodes).all()  # sampled between the nodes


@pytest.mark.parametrize("kw", [{"method": "scp"}, {"backend": "ecos"}])
def test_bad_method_or_backend_is_an_input_error(kw: dict[str, str]) -> None:
    with pytest.raises(guidance.InputError, match="use one of"):
        guidance.solve(**kw)


@pytest.mark.parametrize(
    "call",
    [
        lambda: guidance.solve(settings=guidance.SCvxSettings(eta_init=50.0)),
        lambda: guidance.solve(eta_init=50.0),
        lambda: guidance.solve(backend="c", settings=guidance.SCvxSettings(iter_max=0)),
    ],
    ids=["settings", "eta_init", "c-settings"],
)
def test_a_bad_setting_is_an_input_error(call) -> None:
    """What the README promises: bad input raises guidance.InputError, settings included."""
    with pytest.raises(guidance.InputError, match=r"eta_init|iter_max"):
        call()


BAD_SCENARIOS = {
    "m0": guidance.Scenario(guidance.InitialState(m0=1.0)),
    "q0": guidance.Scenario(guidance.InitialState(q0=(2.0, 0.0, 0.0, 0.0))),
    "T_min": guidance.Scenario(params=guidance.Params(T_min=6.0)),
    "N": guidance.Scenario(params=guidance.Params(N=2)),
    "r0": guidance.Scenario(guidance.InitialState(r0=(1.0, 4.0))),  # type: ignore[arg-type]
}


@pytest.mark.parametrize("backend", ["clarabel", "c-socp", "c"])
@pytest.mark.parametrize("field", list(BAD_SCENARIOS))
def test_a_scenario_built_in_python_is_checked_on_every_backend(field: str, backend: str) -> None:
    """A Scenario object meets the scenario file's rules before any backend solves it (the
    Python backends used to solve m0 below the dry mass into a negative final mass)."""
    with pytest.raises(guidance.InputError, match=f"scenario field '{field}'"):
        guidance.solve(BAD_SCENARIOS[field], backend=backend)


def test_numpy_numbers_in_a_scenario_are_numbers() -> None:
    scn = guidance.Scenario(guidance.InitialState(r0=np.array([4, 4, 0]), m0=np.float64(3.0)))
    result = guidance.solve(scn, backend="c")
    assert result.status == "solved" and result.m_f == pytest.approx(
        guidance.solve(backend="c").m_f
    )


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"tau_r_update": "no"}, "tau_r_update must be True or False"),  # "no" is truthy
        ({"socp_warm_start": 1}, "socp_warm_start must be True or False"),
        ({"discretization": "foo"}, "discretization must be one of auto, c, casadi"),
        ({"lam": "500"}, "lam must be a number"),
    ],
)
def test_a_setting_of_the_wrong_type_is_refused(change: dict, message: str) -> None:
    with pytest.raises(guidance.InputError, match=message):
        guidance.SCvxSettings(**change)


def test_settings_of_another_type_and_a_boolean_t_f_are_refused_by_name() -> None:
    """A settings dict reached the backends and failed there with AttributeError (a different
    one per backend); a guess whose t_f is True was taken as t_f = 1; models_dir=None raised
    TypeError where it means the shipped networks."""
    with pytest.raises(guidance.InputError, match=r"settings: expected a guidance\.SCvxSettings"):
        guidance.solve(settings={"iter_max": 2}, backend="c")  # type: ignore[arg-type]
    first = guidance.solve(backend="c", settings=guidance.SCvxSettings(iter_max=2))
    with pytest.raises(guidance.InputError, match="t_f: expected one real number, got True"):
        guidance.solve(backend="c", guess=(first.x, first.u, True))
    assert guidance.solve(method="tscvx", backend="c", models_dir=None).status == "solved"
