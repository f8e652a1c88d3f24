"""Writing a file so that it is never seen half written."""

from __future__ import annotations

import contextlib
import os
import secrets


def write_atomically(path: str | os.PathLike, data: bytes) -> None:
    """A temporary file beside ``path``, flushed to disk, then renamed over it.

    On any failure (including KeyboardInterrupt) the temporary file is removed and
    an existing file at ``path`` is left untouched. Created with O_EXCL and mode
    0o666, so the umask applies as for any new file.
    """
    path = os.fspath(path)
    temporary = f"{path}.tmp-{secrets.token_hex(8)}"
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(descriptor, "wb") as file:
            file.write(data)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise
