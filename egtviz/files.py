"""Safe file reads and writes for whatever a user names: refuse devices, FIFOs, directories and huge files.

Layer 0 of egtviz (standard library only). Reads never block and never read more than a stated limit;
writes go through a unique temporary file in the target's folder and an atomic rename, so a reader sees
the old file or the new one, never half of one, and nothing is left behind on failure.
"""

from __future__ import annotations

import os
import stat
import tempfile
import unicodedata
from pathlib import Path

__all__ = ["FileSafetyError", "check_write_target", "printable", "read_limited", "too_large", "write_atomic"]


class FileSafetyError(OSError):
    """A file that egtviz refuses to read or write; the message names the file and the reason."""


def printable(text: object) -> str:
    """``text`` with every control character (C0, DEL, C1, ESC included) written as ``\\xNN``.

    For file names and titles shown on a terminal: a name cannot move the cursor or change colours.
    """
    s = str(text)
    if s.isprintable():
        return s
    return "".join(
        c if c == " " or unicodedata.category(c)[0] != "C" else f"\\x{ord(c):02x}" if ord(c) < 256 else f"\\u{ord(c):04x}"
        for c in s
    )


def _checked_name(path: str | os.PathLike) -> str:
    """``path`` as shown in messages; a name no file can have (a NUL byte) is refused here."""
    name = os.fspath(path)
    if isinstance(name, bytes):
        name = os.fsdecode(name)
    if "\0" in name:
        raise FileSafetyError(f"{printable(name)}: a file name cannot contain a NUL character")
    return printable(name)


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    return "not a regular file"


def too_large(size: int, limit: int) -> str:
    """``"1,000,001 bytes, more than the 1,000,000-byte limit"``: exact sizes, so a file one byte over says so."""
    return f"{size:,} bytes, more than the {limit:,}-byte limit"


def read_limited(path: str | os.PathLike, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, refusing anything else before reading a byte.

    The file is checked with ``stat`` before it is opened (a device or FIFO is never opened), opened with
    ``O_NONBLOCK`` (a file swapped for a FIFO in between cannot block), checked again with ``fstat`` on the
    open descriptor, and read up to ``max_bytes + 1`` bytes (a file that grows is refused too). A symbolic
    link to a regular file is read; a link to anything else is refused like its target.

    Args:
        path: the file to read.
        max_bytes: the largest size accepted, bytes.

    Raises:
        FileSafetyError: no such file, not a regular file, larger than ``max_bytes``, or unreadable.
    """
    shown = _checked_name(path)
    try:
        before = os.stat(path)
    except FileNotFoundError:
        raise FileSafetyError(f"{shown}: no such file") from None
    except OSError as exc:
        raise FileSafetyError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    if not stat.S_ISREG(before.st_mode):
        raise FileSafetyError(f"{shown}: not a regular file ({_kind(before.st_mode)})")
    if before.st_size > max_bytes:
        raise FileSafetyError(f"{shown}: {too_large(before.st_size, max_bytes)}")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise FileSafetyError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    try:
        now = os.fstat(fd)
        if not stat.S_ISREG(now.st_mode) or (now.st_dev, now.st_ino) != (before.st_dev, before.st_ino):
            raise FileSafetyError(f"{shown}: the file changed while it was opened; not read")
        chunks: list[bytes] = []
        left = max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as exc:
        if isinstance(exc, FileSafetyError):
            raise
        raise FileSafetyError(f"{shown}: cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > max_bytes:
        raise FileSafetyError(f"{shown}: grew while it was read to more than the {max_bytes:,}-byte limit")
    return data


def check_write_target(path: str | os.PathLike, *, overwrite: bool = True) -> Path:
    """Check that ``path`` may be written, before any long work is done; returns it as a :class:`Path`.

    The folder must exist and be writable; the target must be absent or a regular file (never a device,
    FIFO, directory or symbolic link); with ``overwrite=False`` it must be absent.

    Raises:
        FileSafetyError: the reason, naming the file.
    """
    shown = _checked_name(path)
    p = Path(path)
    if not os.fspath(path) or p.name in ("", ".", ".."):
        raise FileSafetyError(f"{shown or repr(os.fspath(path))}: expected a file name")
    folder = p.parent
    try:
        fst = os.stat(folder)
    except OSError:
        raise FileSafetyError(f"{shown}: the folder {printable(folder)} does not exist") from None
    if not stat.S_ISDIR(fst.st_mode):
        raise FileSafetyError(f"{shown}: {printable(folder)} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise FileSafetyError(f"{shown}: the folder {printable(folder)} is not writable")
    try:
        st = os.lstat(p)
    except FileNotFoundError:
        return p
    except OSError as exc:
        raise FileSafetyError(f"{shown}: cannot check the target: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        raise FileSafetyError(f"{shown}: will not replace {_kind(st.st_mode)}")
    if not overwrite:
        raise FileSafetyError(f"{shown}: exists already")
    return p


def _umask() -> int:
    """The process umask, read without changing it (Linux), else the usual 022."""
    try:
        with open("/proc/self/status", encoding="ascii", errors="replace") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    return 0o022


def write_atomic(path: str | os.PathLike, data: bytes, *, overwrite: bool = True) -> None:
    """Write ``data`` to ``path`` atomically: readers see the old file or the new one, never a mix.

    :func:`check_write_target` first; then a unique temporary file in the same folder
    (``tempfile.mkstemp``) is written, flushed to disk (``fsync``), given the replaced file's permissions
    (or the umask's for a new file), checked once more and renamed over the target (``os.replace``; with
    ``overwrite=False`` a hard link that fails if the target appeared). The temporary file is removed on
    any failure.

    Raises:
        FileSafetyError: the target is refused, or the write failed (the message says why).
    """
    p = check_write_target(path, overwrite=overwrite)
    shown = printable(os.fspath(path))
    try:
        existing = os.lstat(p)
        mode = stat.S_IMODE(existing.st_mode)
    except OSError:
        mode = 0o666 & ~_umask()
    try:
        fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name}.", suffix=".tmp")
    except OSError as exc:
        raise FileSafetyError(f"{shown}: cannot write: {exc.strerror or exc}") from None
    try:
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view):]
            os.fchmod(fd, mode)
            os.fsync(fd)
        finally:
            os.close(fd)
        check_write_target(p, overwrite=overwrite)
        if overwrite:
            os.replace(tmp, p)
        else:
            os.link(tmp, p)
            os.unlink(tmp)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, FileSafetyError):
            raise
        if isinstance(exc, FileExistsError):
            raise FileSafetyError(f"{shown}: exists already") from None
        if isinstance(exc, OSError):
            raise FileSafetyError(f"{shown}: cannot write: {exc.strerror or exc}") from None
        raise
    try:  # make the rename itself durable
        dfd = os.open(p.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except OSError:
        pass
