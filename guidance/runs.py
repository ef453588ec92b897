"""A resumable run's folder (``--run-dir``): its record, ``run.json`` (the options that define
the run and the code versions that worked on it), checked on every resume, and for the runs of
items solved one by one (dispersion, agreement) each finished item's result."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from guidance.atomic import set_aside, write_json_atomic, write_text_atomic
from guidance.errors import InputError
from guidance.json_files import read_json_object
from guidance.provenance import code_version


def record_code_version(run_json: Path, record: dict) -> list[str]:
    """Adds this code's version to a resumable run's record (``code_versions`` in run.json)
    and returns every version that worked on the run. A resume by another version is not
    refused (each version's results are sound) but warned about: the run then mixes them."""
    version = code_version()
    versions = list(record.get("code_versions", []))
    if version not in versions:
        if versions:
            print(
                f"warning: {run_json.parent} holds results of {', '.join(versions)}; this code "
                f"is {version}. The run records every version.",
                file=sys.stderr,
            )
        versions.append(version)
        write_json_atomic(run_json, {**record, "code_versions": versions})
    return versions


def check_run(run_dir: Path, config: dict, what: str) -> list[str]:
    """A resumable run's record (``run_dir/run.json``): made with ``config`` (JSON values)
    and this code's version when the folder holds none; else a resume, which must have the
    recorded value of every key of ``config`` (InputError naming the keys that differ, and
    the recorded and given values of those that are numbers or short words). Returns the code
    versions that worked on the run (record_code_version). ``what``: what the folder holds,
    for the message ("neighbours", "landings")."""
    path = run_dir / "run.json"
    config = json.loads(json.dumps(config))  # as read back: tuples as lists
    if not path.exists():
        run_dir.mkdir(parents=True, exist_ok=True)
        return record_code_version(path, config)
    old = read_json_object(
        path,
        f"the record of a run of {what}",
        f"delete the folder {run_dir} (its {what} are solved again) or use another --run-dir",
    )
    differ = [k for k in config if old.get(k) != config[k]]
    if differ:
        values = "".join(  # of the options (numbers, words), not of settings or digests
            f"; it records {k} {old.get(k)!r}, not {config[k]!r}"
            for k in differ
            if not isinstance(config[k], (dict, list)) and len(repr(config[k])) <= 24
        )
        raise InputError(
            f"{run_dir} holds {what} of another run (different {', '.join(differ)}){values}; "
            "rerun with the options that made it to resume, or use another --run-dir"
        )
    return record_code_version(path, old)


T = TypeVar("T")


def result_path(run_dir: str | Path, i: int) -> Path:
    """Where a run folder keeps item ``i``'s result (RunResults)."""
    return Path(run_dir) / "results" / f"{i:06d}.json"


def results_kept(run_dir: str | Path, n: int) -> int:
    """How many of items 0..n-1 a run folder holds (RunResults), read at any time: before
    the run's record is checked too."""
    return sum(result_path(run_dir, i).exists() for i in range(n))


def landings_kept(
    run_dir: str | Path | None, total: int | None, finished: int | None, resume: str
) -> str:
    """What an interrupted run of landings solved one by one kept, and how to go on (said
    after "interrupted: "): with a run folder, how many of the ``total`` it holds (None: not
    known yet) and ``resume``; without, how many of them this process ``finished`` (None:
    not solving) and that nothing is kept."""
    if run_dir is None:
        done = "" if finished is None else f"{finished} of {total} landings were finished; "
        return (
            f"{done}nothing is kept without --run-dir (with --run-dir DIR each landing is kept "
            "as it finishes, and the same command resumes)"
        )
    kept = (
        "the landings finished are"
        if total is None
        else f"{results_kept(run_dir, total)} of {total} landings are"
    )
    return f"{kept} kept in {run_dir}; {resume}"


class RunResults:
    """A resumable run's folder (``--run-dir``) of items solved one by one: its record,
    ``run.json`` (check_run: the run's options and the code versions that worked on it), and
    each finished item's result as ``results/NNNNNN.json`` (its index, six digits or more),
    written atomically as it comes with the run's options and the code version that made it.
    A rerun of the same run reads them back (``kept``) and solves only the others."""

    def __init__(self, run_dir: str | Path, config: dict, what: str) -> None:
        self.run_dir = Path(run_dir)
        self.config = json.loads(json.dumps(config))  # as read back: tuples as lists
        self.versions = check_run(self.run_dir, self.config, what)
        self.version = code_version()

    def path(self, i: int) -> Path:
        return result_path(self.run_dir, i)

    def keep(self, i: int, result: dict) -> None:
        """Item ``i``'s result (strict JSON: no NaN), written whole or not at all."""
        record = {"id": i, "run": self.config, "code_version": self.version, "result": result}
        write_text_atomic(self.path(i), json.dumps(record, indent=1, allow_nan=False) + "\n")

    def kept(self, n: int, parse: Callable[[Any], T]) -> dict[int, T]:
        """The results of items 0..n-1 the folder holds, by index. A file that is unreadable,
        or is not item i's of this run (another run's options, another index, a result that
        ``parse`` refuses with ValueError, KeyError or TypeError), is set aside as
        ``NNNNNN.unreadable`` (atomic.set_aside) and its item solved again."""
        out: dict[int, T] = {}
        for i in range(n):
            path = self.path(i)
            if not path.exists():
                continue
            try:
                record = json.loads(path.read_text(encoding="utf-8"))
                if record["id"] != i or record["run"] != self.config:
                    raise ValueError(f"not item {i} of this run")
                out[i] = parse(record["result"])
            except (OSError, ValueError, KeyError, TypeError, RecursionError) as exc:
                aside = set_aside(path)
                print(f"{path}: {exc}; set aside as {aside}, solved again", file=sys.stderr)
        return out

    def count(self, n: int) -> int:
        """How many of items 0..n-1 the folder holds."""
        return results_kept(self.run_dir, n)
