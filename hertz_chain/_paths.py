"""Output files of the command line: checked before a run, written atomically after it.

`check_output_path(path, key, suffixes, force)` refuses, before anything is simulated, an output that
could not be written where it was asked for:

* the parent folder is missing, or is a file, or is not writable;
* the file name is longer than the file system allows (`os.pathconf(folder, "PC_NAME_MAX")`,
  `NAME_MAX_FALLBACK` = 255 bytes where the system does not say);
* the extension is not one of `suffixes` (`.nc`/`.csv` for `--output`, `.png` for `--plot`);
* the path is a folder, or an existing file and `force` is false.

`write_atomically(path, write_fn, force)` lets `write_fn(tmp)` write a temporary file in the same
folder (a short hidden name with the target's extension, so that writers that pick the format from
the extension keep working), then publishes it in one step:

* without `force`, `os.link(tmp, path)`: the link fails if `path` appeared in the meantime (another
  run wrote it), so of two runs writing the same output exactly one wins; the other gets an
  `OutputPathError` and the winner's file is left untouched;
* with `force`, `os.replace(tmp, path)`, atomic on POSIX: a reader sees the old file or the new one,
  never a half-written one.

The temporary file is removed in every case. Both raise `OutputPathError` (one line: option, path,
problem) and nothing else for a problem with the path or the folder.
"""

from __future__ import annotations

import errno
import os
import secrets
from pathlib import Path
from typing import Callable

from .errors import OutputPathError

__all__ = ["NAME_MAX_FALLBACK", "check_output_path", "name_max", "write_atomically"]

NAME_MAX_FALLBACK = 255
"""The longest file name (bytes) assumed where `os.pathconf` cannot tell (POSIX `NAME_MAX` on Linux)."""

# errors of os.link meaning "this file system has no hard links", where an exclusive create is used
_NO_LINKS = {errno.EPERM, errno.EXDEV, errno.EMLINK, getattr(errno, "ENOTSUP", -1),
             getattr(errno, "EOPNOTSUPP", -1), errno.ENOSYS}


def name_max(folder: str | Path) -> int:
    """The longest file name (in bytes) allowed in `folder`."""
    try:
        value = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        return NAME_MAX_FALLBACK
    return value if isinstance(value, int) and value > 0 else NAME_MAX_FALLBACK


def _show(path: Path) -> str:
    return str(path)


def check_output_path(path: str | Path, key: str, suffixes: tuple[str, ...], force: bool) -> Path:
    """Check that `path` can be written as the output `key` (e.g. `"--output"`) before a run; see
    the module docstring. Returns the path; raises `OutputPathError`."""
    path = Path(path)
    allowed = " or ".join(suffixes)
    if not path.name or path.name in (".", ".."):
        raise OutputPathError(key, _show(path), f"is not a file name; expected a {allowed} file")
    if path.suffix.lower() not in suffixes:
        raise OutputPathError(key, _show(path), f"unknown extension {path.suffix or '(none)'!r}; "
                                                f"expected a {allowed} file")
    folder = path.parent
    try:
        if not folder.exists():
            raise OutputPathError(key, _show(path), f"the folder {_show(folder)} does not exist")
        if not folder.is_dir():
            raise OutputPathError(key, _show(path), f"{_show(folder)} is not a folder")
    except OSError as exc:  # e.g. a path component that is too long, or a loop of links
        raise OutputPathError(key, _show(path), f"cannot use the folder ({exc.strerror or exc})") from None
    limit = name_max(folder)
    size = len(os.fsencode(path.name))
    if size > limit:
        raise OutputPathError(key, f"{path.name[:24]}...", f"the file name has {size} bytes; the file "
                                                            f"system allows at most {limit}")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputPathError(key, _show(path), f"the folder {_show(folder)} is not writable")
    if path.is_dir():
        raise OutputPathError(key, _show(path), "is a folder; expected a file name")
    if path.exists() or path.is_symlink():
        if not force:
            raise OutputPathError(key, _show(path), "exists; pass --force to overwrite it")
    return path


def _tmp_name(path: Path) -> Path:
    # short and hidden, whatever the target's length; the extension keeps the writer's format
    return path.with_name(f".hertz-chain-{os.getpid()}-{secrets.token_hex(4)}{path.suffix}")


def _unlink(p: Path) -> None:
    try:
        os.unlink(p)
    except FileNotFoundError:
        pass


def write_atomically(path: str | Path, write_fn: Callable[[Path], object], force: bool,
                     key: str = "output") -> Path:
    """Write `path` through `write_fn(tmp_path)` and publish it atomically (see the module
    docstring). Without `force` an existing `path` is never replaced. Raises `OutputPathError`."""
    path = Path(path)
    tmp = _tmp_name(path)
    try:
        try:
            write_fn(tmp)
        except OSError as exc:  # (the writer's own words name the temporary file: name the user's instead)
            why = str(exc.strerror or exc).replace(str(tmp), str(path)).replace(tmp.name, path.name)
            raise OutputPathError(key, _show(path), f"cannot write it ({why})") from None
        if not tmp.exists():
            raise OutputPathError(key, _show(path), "the writer produced no file")
        if force:
            try:
                os.replace(tmp, path)
            except OSError as exc:
                raise OutputPathError(key, _show(path), f"cannot replace it ({exc.strerror or exc})") from None
            return path
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise OutputPathError(key, _show(path), "was created by someone else while this run was "
                                                    "working; left as it is (pass --force to overwrite)") from None
        except OSError as exc:
            if exc.errno not in _NO_LINKS:
                raise OutputPathError(key, _show(path), f"cannot create it ({exc.strerror or exc})") from None
            _publish_exclusive(tmp, path, key)
        return path
    finally:
        _unlink(tmp)


def _publish_exclusive(tmp: Path, path: Path, key: str) -> None:
    """Without hard links: reserve `path` with an exclusive create, then move the data over it."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except FileExistsError:
        raise OutputPathError(key, _show(path), "was created by someone else while this run was "
                                                "working; left as it is (pass --force to overwrite)") from None
    except OSError as exc:
        raise OutputPathError(key, _show(path), f"cannot create it ({exc.strerror or exc})") from None
    os.close(fd)
    try:
        os.replace(tmp, path)
    except OSError as exc:
        _unlink(path)
        raise OutputPathError(key, _show(path), f"cannot create it ({exc.strerror or exc})") from None
