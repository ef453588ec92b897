"""guidance.runs: a run resumed by other code warns and records every code version."""

from __future__ import annotations

import json
import shutil

from dataset_runs import EASY

from guidance.dataset import pack
from guidance.dataset_run import generate, read_sample, sample_path, write_sample
from guidance.provenance import code_version


def test_resume_by_other_code_warns_and_the_header_lists_every_version(tiny_run, tmp_path, capsys):
    run = tmp_path / "run"
    shutil.copytree(tiny_run[0], run)
    config = json.loads((run / "run.json").read_text())
    assert config["code_versions"] == [code_version()]
    (run / "run.json").write_text(json.dumps({**config, "code_versions": ["guidance 0.0 old"]}))
    rec = read_sample(sample_path(run, 0))
    write_sample(run, {**rec, "code_version": "guidance 0.0 old"})
    # nothing left to solve: the resume only checks the run
    generate(run, 2, seed=11, ranges=EASY, workers=1, progress=False, backend="clarabel")
    err = capsys.readouterr().err
    assert "warning:" in err and "guidance 0.0 old" in err and code_version() in err
    config = json.loads((run / "run.json").read_text())
    assert config["code_versions"] == ["guidance 0.0 old", code_version()]
    header = pack(run, tmp_path / "d.npz")
    assert header["code_versions"] == sorted(["guidance 0.0 old", code_version()])
