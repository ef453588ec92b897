"""Every file this package writes goes through here: written whole or not at all.

The bytes go to a hidden temporary file beside the target (``.NAME.PID-THREAD.tmp``: no glob
of the package's own files picks it up, and two writers of one file never share it), which
then replaces the target in one step. An interruption (Ctrl-C, a killed job, an exception in
the writer) leaves the previous file or the new one, never a truncated one, and no temporary
file. A target that is a symbolic link is written through the link: the link stays and the
file it points to gets the new content, as a shell redirection would do (a plain rename would
replace the link by a regular file). A missing folder is made here (a link's target's), for
every writer, and only here; a write that fails removes the folders it made (when still
empty), so a failed command leaves no trace. A file replaced keeps its permissions (a private
file stays private); being a new file, it is no longer shared with any hard link to the old one.

``check_outputs`` is the commands' check before their work: each output can be written, and
no two of them are one file (or one inside the other). It makes no folder: a refused command
leaves nothing behind, and one that stops before writing leaves no empty folder.
"""

from __future__ import annotations

import itertools
import json
import os
import shutil
import stat
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

from guidance.errors import InputError


@contextmanager
def atomic_write(path: str | Path) -> Iterator[BinaryIO]:
    """``with atomic_write(path) as f: np.savez(f, ...)``: the binary file to write."""
    target = Path(os.path.realpath(path))
    made = _make_folders(target.parent)  # the one place writers make folders
    tmp = target.with_name(f".{target.name}.{os.getpid()}-{threading.get_ident()}.tmp")
    written = False
    try:
        with open(tmp, "wb") as f:
            yield f
        if target.exists():  # the replaced file's permissions, not the umask's default
            os.chmod(tmp, stat.S_IMODE(target.stat().st_mode))
        os.replace(tmp, target)
        written = True
    finally:
        tmp.unlink(missing_ok=True)
        if not written:
            _remove_folders(made)


@contextmanager
def staged_files(folder: str | Path, first: str | None = None) -> Iterator[Path]:
    """``with staged_files(models) as stage: write files into stage``: a set of files that
    replaces its namesakes in ``folder``. The block writes them into ``stage``, a new hidden
    folder beside ``folder``; only when the block has finished are they moved into ``folder``
    (each through atomic_write: the file named ``first``, then the others in name order). An
    exception in the block leaves ``folder`` as it was (not even made), and the stage is
    removed either way. The moves are one file at a time: one interrupted between two of them
    (a killed process, a full disk) leaves new files beside old ones, which a manifest of the
    new set moved ``first`` (names and sha256) makes detectable."""
    folder = Path(folder)
    near = _first_existing(folder.parent)
    try:
        stage = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".tmp", dir=near))
    except OSError as exc:
        raise InputError(f"{folder}: cannot write beside it in {near} ({exc.strerror})") from None
    try:
        yield stage
        for staged in sorted(stage.iterdir(), key=lambda p: (p.name != first, p.name)):
            with open(staged, "rb") as src, atomic_write(folder / staged.name) as dst:
                shutil.copyfileobj(src, dst)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    with atomic_write(path) as f:
        f.write(data)


def write_text_atomic(path: str | Path, text: str) -> None:
    write_bytes_atomic(path, text.encode())


def write_json_atomic(path: Path, obj: dict) -> None:
    """JSON through a temporary file: an interruption leaves the old file or the new."""
    write_text_atomic(path, json.dumps(obj, indent=2))


def _make_folders(folder: Path) -> list[Path]:
    """Make ``folder`` and its missing parents; the ones this call made, outermost first."""
    missing: list[Path] = []
    while not folder.is_dir() and folder != folder.parent:
        missing.append(folder)
        folder = folder.parent
    made: list[Path] = []
    try:
        for p in reversed(missing):
            try:
                p.mkdir()
            except FileExistsError:
                if not p.is_dir():
                    raise
                continue  # made meanwhile by another writer: not ours to remove
            made.append(p)
    except BaseException:
        _remove_folders(made)
        raise
    return made


def _remove_folders(made: list[Path]) -> None:
    """Remove the folders a failed write made, innermost first, while they are empty."""
    for p in reversed(made):
        try:
            p.rmdir()
        except OSError:  # another writer's file is in it now: it stays, and so do its parents
            return


def check_outputs(
    *outputs: tuple[str, str | Path | None],
    inputs: tuple[tuple[str, str | Path | None], ...] = (),
) -> None:
    """Refuse, before the work, outputs ``(flag, path)`` (None: not asked for) that could not be
    written or that are one file (the second written would overwrite the first), and outputs
    that are one of the ``inputs`` ``(what, path)`` the work reads (a scenario file)."""
    given = [(flag, path) for flag, path in outputs if path]  # named as the user wrote them
    _check_distinct(given)
    for what, source in inputs:
        for flag, path in given:
            if source and _where(path) == _where(source):
                raise InputError(f"{flag} {path}: is the {what} {source} (it would be overwritten)")
    for flag, path in given:
        _check_writable(flag, path)


def _where(path: str | Path) -> Path:
    """Where a path's writes land: links, "./" and ".." resolved."""
    return Path(os.path.normcase(os.path.realpath(path)))


def _check_distinct(outputs: list[tuple[str, str | Path]]) -> None:
    # compared where the writers write: links, "./" and ".." resolved
    where = [(flag, path, _where(path)) for flag, path in outputs]
    for first, second in itertools.combinations(where, 2):
        if first[2] == second[2]:
            raise InputError(
                f"{first[0]} {first[1]} and {second[0]} {second[1]}: both are {first[2]} (one "
                "output would overwrite the other)"
            )
        for (flag, path, inner), (outer_flag, outer_path, outer) in (
            (first, second),
            (second, first),
        ):
            if outer in inner.parents:
                raise InputError(
                    f"{flag} {path}: inside {outer_flag} {outer_path}, which is to be a file"
                )


def _first_existing(folder: Path) -> Path:
    """The folder itself or, when missing, the ancestor the first missing one is made in."""
    while not os.path.lexists(folder):
        folder = folder.parent
    return folder


def check_folder(flag: str, path: str | Path) -> None:
    """Refuse, before the work, a folder the work makes or fills (a run or train folder) that
    is a file or cannot be made (a file where one of its parents should be)."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{flag} {path}: is a file, not a folder")
    parent = _first_existing(folder.parent)
    if not parent.is_dir():
        raise InputError(f"{flag} {path}: cannot create it ({parent} is not a folder)")


def _check_writable(flag: str, path: str | Path) -> None:
    """The file can be written, its missing folders made: checked without making them."""
    target = Path(os.path.realpath(path))  # where the writers write: a link's target
    if target.is_dir():
        raise InputError(f"{flag} {path}: is a folder, not a file")
    if target.exists() and not target.is_file():  # the writers replace what is there
        raise InputError(f"{flag} {path}: is a device, pipe or socket, not a regular file")
    folder = _first_existing(target.parent)
    what = "write there" if folder == target.parent else "create its folder"
    if not folder.is_dir():
        raise InputError(f"{flag} {path}: cannot {what} ({folder} is not a folder)")
    try:  # a file written and removed there, as the writers do (root passes os.access)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-check-"):
            pass
    except OSError as exc:
        raise InputError(f"{flag} {path}: cannot {what} ({exc.strerror})") from None


MAX_SET_ASIDE = 1000


def set_aside(p: Path) -> Path:
    """Renames a damaged file of a run (a sample, a landing's result) to the first free name
    of NNNNNN.unreadable, NNNNNN.unreadable.1, ... and returns it, for the run to solve its
    item again: one damaged again keeps the earlier evidence (a rename would replace it).
    InputError when MAX_SET_ASIDE names are taken."""
    first = p.with_suffix(".unreadable")
    for n in range(MAX_SET_ASIDE):
        aside = first if n == 0 else first.with_name(f"{first.name}.{n}")
        if not (aside.exists() or aside.is_symlink()):
            p.rename(aside)
            return aside
    raise InputError(
        f"{p} cannot be set aside: {first.name} to {first.name}.{MAX_SET_ASIDE - 1} "
        "exist; move the old ones away and resume"
    )
