"""Every file this package writes goes through here: written whole or not at all.

The bytes go to a hidden temporary file beside the target (``.NAME.PID-THREAD.tmp``: no glob
of the package's own files picks it up, and two writers of one file never share it), which
then replaces the target in one step. An interruption (Ctrl-C, a killed job, an exception in
the writer) leaves the previous file or the new one, never a truncated one, and no temporary
file. A target that is a symbolic link is written through the link: the link stays and the
file it points to gets the new content, as a shell redirection would do (a plain rename would
replace the link by a regular file). A missing folder is made here (a link's target's), for
every writer. A file replaced keeps its permissions (a private file
stays private); being a new file, it is no longer shared with any hard link to the old one.
"""

from __future__ import annotations

import os
import stat
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO


@contextmanager
def atomic_write(path: str | Path) -> Iterator[BinaryIO]:
    """``with atomic_write(path) as f: np.savez(f, ...)``: the binary file to write."""
    target = Path(os.path.realpath(path))
    target.parent.mkdir(parents=True, exist_ok=True)  # the one place writers make folders
    tmp = target.with_name(f".{target.name}.{os.getpid()}-{threading.get_ident()}.tmp")
    try:
        with open(tmp, "wb") as f:
            yield f
        if target.exists():  # the replaced file's permissions, not the umask's default
            os.chmod(tmp, stat.S_IMODE(target.stat().st_mode))
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def write_bytes_atomic(path: str | Path, data: bytes) -> None:
    with atomic_write(path) as f:
        f.write(data)


def write_text_atomic(path: str | Path, text: str) -> None:
    write_bytes_atomic(path, text.encode())
