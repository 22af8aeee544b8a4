"""Output files: checked before any work, written atomically, never left half-written.

Every command checks its output paths first (`check_output_file`, `check_output_folder`), so a
typo in `-o` fails in a second rather than after minutes of learning or simulation. Every file
is then written through `atomic_output`: a temporary file beside the target, renamed into place
when complete and removed on any failure, so a crash or Ctrl-C leaves the old file (or none).
"""

from __future__ import annotations

import glob
import os
import re
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, Iterator

from stl_lfd.errors import OutputError


def check_output_file(path: Path | str, suffixes: tuple[str, ...] = (), what: str = "output file") -> Path:
    """`path` as a Path, after checking that a file can be written there.

    Args:
        suffixes: accepted suffixes (lower case, with the dot); empty accepts any.

    Raises:
        OutputError: naming the path and the problem.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; give a file name for the {what}")
    if suffixes and path.suffix.lower() not in suffixes:
        raise OutputError(f"{path}: the {what} must end in {_either(suffixes)}")
    folder = path.parent
    if not folder.is_dir():
        problem = "is a file" if folder.exists() else "does not exist"
        raise OutputError(f"{path}: cannot write the {what}: the folder {folder} {problem}")
    if not os.access(folder, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise OutputError(f"{path}: cannot write the {what}: permission denied")
    return path


def check_output_folder(path: Path | str, what: str = "output folder") -> Path:
    """`path` as a Path, after checking that it is (or can be created as) a writable folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{path}: is a file; the {what} must be a folder")
    existing = path
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise OutputError(f"{path}: cannot create the {what}: {existing} is a file")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise OutputError(f"{path}: cannot write the {what}: {existing} is not writable (permission denied)")
    return path


class UnreadableFile(Exception):
    """Why `read_text` could not read a file; callers turn it into their own error class."""


MAX_TEXT_BYTES = 256_000_000  # a recorded trial is a few MB; this is a file given by mistake


def read_text(path: Path | str, what: str, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """The text of a regular UTF-8 file of at most `max_bytes`, a byte-order mark dropped.

    Only a regular file is read (a FIFO, a device such as /dev/zero or a socket is refused
    without blocking), and never more than `max_bytes` of it, whatever its size claims.

    Raises:
        UnreadableFile: "no such WHAT", "is a folder, not a WHAT", "not a regular file ...",
            "larger than ...", "not a text file ...".
    """
    try:
        return decoded(read_bounded(path, what, max_bytes), what)
    except FileNotFoundError:
        problem = f"no such {what}"
    except IsADirectoryError:
        problem = f"is a folder, not a {what}"
    except OSError as error:
        problem = f"cannot read the {what} ({error.strerror or error})"
    raise UnreadableFile(problem)


def open_regular(path: Path | str, what: str) -> BinaryIO:
    """`path` opened for reading in binary when it is a regular file, without waiting (a FIFO
    opens without a writer, then is refused, as a device or socket is: UnreadableFile);
    IsADirectoryError for a folder, OSError when it cannot be opened."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    mode = os.fstat(descriptor).st_mode
    if not stat.S_ISREG(mode):
        os.close(descriptor)
        if stat.S_ISDIR(mode):
            raise IsADirectoryError(path)
        raise UnreadableFile(f"not a regular file (a pipe, device or socket); expected a {what}")
    return os.fdopen(descriptor, "rb")


def read_bounded(path: Path | str, what: str, max_bytes: int) -> bytes:
    """The bytes of the regular file at `path`, refused when over `max_bytes` (UnreadableFile);
    OSError when it cannot be opened."""
    with open_regular(path, what) as stream:
        data = stream.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise UnreadableFile(f"the file is larger than {_size(max_bytes)}; is it the right {what}?")
    return data


def decoded(data: bytes, what: str) -> str:
    """`data` as UTF-8 text without a byte-order mark; UnreadableFile for binary data."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise UnreadableFile(f"not a text file (it is not UTF-8); expected a {what}") from None
    if "\0" in text:
        raise UnreadableFile(f"not a text file (it holds NUL bytes); expected a {what}")
    return text


def _size(count: int) -> str:
    return f"{count / 1e6:g} MB" if count >= 1_000_000 else f"{count / 1e3:g} kB"


@contextmanager
def atomic_output(path: Path | str) -> Iterator[Path]:
    """A temporary path beside `path` to write to; synced to disk and renamed to `path` when the
    block succeeds, removed when it fails. The file gets the permissions of an ordinary new file
    (umask)."""
    path = Path(path)
    remove_leftovers(path)
    descriptor, name = tempfile.mkstemp(prefix=f".{path.stem}.{os.getpid()}.", suffix=f".tmp{path.suffix}", dir=path.parent)
    os.close(descriptor)
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, 0o666 & ~_umask())
        with open(temporary, "rb") as written:  # on disk before it replaces the old file
            os.fsync(written.fileno())
        os.replace(temporary, path)
    except OSError as error:
        temporary.unlink(missing_ok=True)
        raise OutputError(f"{path}: cannot write ({error.strerror or error})") from None
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


_TIDIED: set[tuple[Path, str]] = set()  # (folder, suffix) whose leftovers this process removed


def remove_leftovers(path: Path) -> None:
    """Remove the temporary files that killed processes left beside `path` (`atomic_output`
    names them `.STEM.PID.XXXXXXXX.tmpSUFFIX`): those of this suffix whose process no longer
    runs on this machine. Once per folder and suffix per process: a run writes thousands of
    files into one folder."""
    key = (path.parent.resolve(), path.suffix)
    if key in _TIDIED:
        return
    _TIDIED.add(key)
    pattern = re.compile(rf"\..+\.(\d+)\.[A-Za-z0-9_]{{8}}\.tmp{re.escape(path.suffix)}")
    for leftover in path.parent.glob(f".*.tmp{glob.escape(path.suffix)}"):
        match = pattern.fullmatch(leftover.name)
        if match and not _running(int(match.group(1))):
            try:
                leftover.unlink()
            except OSError:  # gone already, or not ours to remove
                pass


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's
        return True
    return True


def write_atomically(path: Path | str, text: str) -> None:
    """Write `text` to `path` so that `path` is never half-written."""
    with atomic_output(path) as temporary:
        temporary.write_text(text)


def folder_mode() -> int:
    """The permissions of an ordinary new folder under the current umask."""
    return 0o777 & ~_umask()


def _either(suffixes: tuple[str, ...]) -> str:
    return suffixes[0] if len(suffixes) == 1 else f"{', '.join(suffixes[:-1])} or {suffixes[-1]}"


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask
