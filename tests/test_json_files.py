"""The one checked reader of the JSON files the commands read back (guidance.json_files):
every way a file can be wrong is an InputError naming the file, the problem and the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from guidance.errors import InputError
from guidance.json_files import NUMBER, read_json_object

NEEDS = {"kind": str, "macs": int, "loss": NUMBER, "arch.d_model": int, "shipped.*.file": str}
GOOD = '{"kind": "solution", "macs": 3, "loss": 0.5, "arch": {"d_model": 8}, "shipped": {}}'


@pytest.mark.parametrize(
    "text, problem",
    [
        ("{", "not valid JSON (Expecting property name"),
        ("[]", "a list, not a JSON object"),
        ('"text"', "a string, not a JSON object"),
        ('{"a": 1, "a": 2}', "key 'a' given twice"),
        (GOOD.replace('"macs": 3, ', ""), "no 'macs'"),
        (GOOD.replace('"macs": 3', '"macs": "x"'), "'macs' is a string, not an integer"),
        (GOOD.replace('"macs": 3', '"macs": true'), "'macs' is true/false, not an integer"),
        (GOOD.replace('"loss": 0.5', '"loss": null'), "'loss' is null, not an integer or"),
        (GOOD.replace('{"d_model": 8}', "[8]"), "'arch' is a list, not an object"),
        (GOOD.replace('"shipped": {}', '"shipped": {"c": {}}'), "no 'shipped.c.file'"),
        ("\ufeff{}".encode("utf-16"), "not UTF-8 text"),
    ],
)
def test_each_problem_is_named_with_the_file_and_the_fix(text, problem, tmp_path) -> None:
    path = tmp_path / "report.json"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with pytest.raises(InputError) as exc:
        read_json_object(path, "a trained model's report", "re-run `guidance train`", NEEDS)
    message = str(exc.value)
    assert message.startswith(f"{path}: not a trained model's report (")
    assert problem in message and message.endswith("; re-run `guidance train`")


def test_a_good_file_and_a_missing_one(tmp_path: Path) -> None:
    path = tmp_path / "report.json"
    path.write_text(GOOD)
    assert read_json_object(path, "a report", "fix", NEEDS)["arch"] == {"d_model": 8}
    assert read_json_object(path, "a report", "fix", {"loss": NUMBER})["loss"] == 0.5
    with pytest.raises(InputError, match=r"none.json: cannot read it \(No such file"):
        read_json_object(tmp_path / "none.json", "a report", "fix")


def test_every_missing_entry_is_listed(tmp_path: Path) -> None:
    path = tmp_path / "report.json"
    path.write_text("{}")
    with pytest.raises(InputError, match="no 'kind', no 'macs', no 'loss', no 'arch', no "):
        read_json_object(path, "a report", "fix", NEEDS)


def test_a_dataset_run_record_is_read_by_it(tmp_path: Path) -> None:
    """dataset.py's run.json reader is this one (it was its own, with its own messages)."""
    from guidance.dataset import pack

    (tmp_path / "run.json").write_text('{"seed": 0}')
    with pytest.raises(InputError) as exc:
        pack(tmp_path, tmp_path / "out.npz")
    message = str(exc.value)
    assert message.startswith(f"{tmp_path / 'run.json'}: not a dataset run's record (no 'ranges'")
    assert message.endswith("; restore it from a copy, or start the run in another --run-dir")


def test_a_byte_order_mark_at_the_start_is_ignored(tmp_path: Path) -> None:
    """RFC 8259 lets a parser ignore a leading BOM (Windows editors write one): read, as a
    scenario file is (one reader, json_files.load_json)."""
    path = tmp_path / "report.json"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD.encode())
    assert read_json_object(path, "a report", "fix", NEEDS)["macs"] == 3
