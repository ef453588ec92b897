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
    blocks = re.findall(r"### From Python\n.*?```python\n(.*?)```", text, re.S)
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
