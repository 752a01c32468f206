"""Output files that are never half-written.

Every file anchorplan writes for a user (a plan's ``result.json`` and ``layout.json``, the
report, the mounting sheet, the DXF, figures, JSON tables) is written to a temporary file
in the same folder, flushed to disk and renamed over its name. A rename within a folder
is atomic, so a reader sees the old file or the new one, never a truncated one, also when
the run is killed or two runs write into the same folder at once. When writing fails (a
full disk, a folder that became read-only), the temporary files are removed, the files of
the previous run are left as they were and the error says so.

Several files written together (:func:`write_files`) are all written to temporary files
first and renamed only when every one of them was written: a failure leaves all of them
as they were.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path


def _temporary(path: Path) -> Path:
    """A temporary name beside ``path``, hidden, unique to this process and call, with the
    same suffix (libraries that write by name read the format from it)."""
    return path.with_name(f".{path.stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp{path.suffix}")


def _sync(path: Path) -> None:
    """Flush the file's data to disk (a crash after the rename must not leave it empty)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _failed(exc: OSError, paths) -> OSError:
    """``exc`` restated: nothing was written, the previous files are left as they were."""
    names = ", ".join(str(p) for p in paths)
    what = exc.strerror or str(exc)
    return OSError(exc.errno, f"{what}; nothing was written: {names} as before", str(paths[0]))


@contextlib.contextmanager
def replacing(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path to write ``path``'s new content to; renamed over ``path`` when the
    block ends without an error, removed otherwise (the previous file left as it was; an
    ``OSError`` says so). Missing parent folders are created."""
    with replacing_all([path]) as (tmp,):
        yield tmp


@contextlib.contextmanager
def replacing_all(paths) -> Iterator[list[Path]]:
    """Temporary paths (one per path of ``paths``) to write new contents to; all renamed
    over their paths when the block ends without an error, all removed otherwise."""
    paths = [Path(p) for p in paths]
    for p in paths:
        p.parent.mkdir(parents=True, exist_ok=True)
    temps = [_temporary(p) for p in paths]
    try:
        yield temps
        for t in temps:
            _sync(t)
    except BaseException as exc:
        for t in temps:
            with contextlib.suppress(OSError):
                t.unlink()
        if isinstance(exc, OSError):
            raise _failed(exc, paths) from None
        raise
    for t, p in zip(temps, paths, strict=True):
        os.replace(t, p)


def write_files(contents: Mapping[str | os.PathLike, str | bytes]) -> list[Path]:
    """Write every ``path: content`` (text as UTF-8, or bytes) together (module docstring);
    returns the paths."""
    paths = list(contents)
    with replacing_all(paths) as temps:
        for t, data in zip(temps, contents.values(), strict=True):
            if isinstance(data, str):
                t.write_text(data, encoding="utf-8")
            else:
                t.write_bytes(data)
    return [Path(p) for p in paths]


def write_file(path: str | os.PathLike, content: str | bytes) -> Path:
    """Write one file's ``content`` (text as UTF-8, or bytes) atomically; returns the path."""
    return write_files({path: content})[0]


def write_with(path: str | os.PathLike, writer: Callable[[Path], object]) -> Path:
    """Write ``path`` atomically by calling ``writer(temporary_path)`` (a library that
    writes by name: matplotlib, ezdxf); returns the path."""
    with replacing(path) as tmp:
        writer(tmp)
    return Path(path)
