"""The card's file system as deploy touches it: paths that must stay on the card, durable writes, and the
temporary files an interrupted deploy leaves behind.

- Every path deploy reads or writes is resolved (symlinks included) and must stay under the card's root: a
  symlink that leads off the card is refused, never written through.
- A write goes to a temporary file next to the target, which is flushed and fsync'ed before it is renamed over
  the target; the folder is fsync'ed after the rename, so a power cut or a yanked card leaves the old file or
  the new one, never an empty one.
- Our temporary files are named `.<name>.foranav-tmp-<8 random characters>`. A deploy killed before its rename
  leaves one; the next deploy removes those (and the ones the project's generic writer used to leave,
  `.<stem>.<8 random characters><suffix>.tmp<suffix>`), and nothing else.
"""
import errno
import os
import re
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path

from host_tools.errors import ForaNavError

TEMP_MARK = ".foranav-tmp-"
_RANDOM = r"[a-z0-9_]{8}"  # tempfile's names: 8 characters of [a-z0-9_]
TEMP_FILE_RE = re.compile(r"^\..+" + re.escape(TEMP_MARK) + _RANDOM + r"$")
# host_tools.fileio's temporary files (what a deploy killed mid-write left before this module existed).
LEGACY_TEMP_FILE_RE = re.compile(r"^\..+\." + _RANDOM + r"(\.[^.]+)\.tmp\1$")
# Folders cannot be fsync'ed on every file system (some answer EINVAL); the rename itself is still atomic.
_NO_DIR_FSYNC = (errno.EINVAL, errno.ENOTSUP, errno.EBADF, errno.EACCES, errno.EPERM)


@dataclass(frozen=True)
class Entry:
    """What is at a card path now (after following symlinks that stay on the card)."""
    kind: str  # "file", "folder", "missing" or "other" (a device, a fifo, a socket)
    # A file with no write permission for anyone (FAT's read-only attribute), or a folder we may not write in.
    write_protected: bool = False


def real_root(root: str | os.PathLike) -> Path:
    return Path(os.path.realpath(str(root)))


def on_card(root: Path, relative: str) -> Path:
    """The real path of `relative` under the card's (real) root; ForaNavError when a symlink leads off the card."""
    real = os.path.realpath(str(root / relative))
    if real != str(root) and not real.startswith(str(root) + os.sep):
        raise ForaNavError("--sd %s: %s leads off the card (a symlink, to %s); deploy never reads or writes "
                           "through it: replace the link by a file or folder on the card" % (root, relative, real))
    return Path(real)


def entry(root: Path, relative: str) -> Entry:
    path = on_card(root, relative)
    try:
        info = os.stat(str(path))
    except (FileNotFoundError, NotADirectoryError):  # under a file: check_plan names that file
        return Entry("missing")
    if stat.S_ISDIR(info.st_mode):
        return Entry("folder", not os.access(str(path), os.W_OK | os.X_OK))
    if not stat.S_ISREG(info.st_mode):
        return Entry("other")
    # Root may write anything, so os.access alone would miss a read-only file on a card mounted by root.
    protected = not info.st_mode & 0o222 or not os.access(str(path), os.W_OK)
    return Entry("file", protected)


def stray_temp_files(root: Path, folder: str) -> list[str]:
    """Card paths of our temporary files in `folder` (regular files only, never a symlink)."""
    base = on_card(root, folder)
    if not base.is_dir():
        return []
    found = []
    for path in sorted(base.iterdir()):
        if (TEMP_FILE_RE.match(path.name) or LEGACY_TEMP_FILE_RE.match(path.name)) and not path.is_symlink() \
                and path.is_file():
            found.append(folder + "/" + path.name)
    return found


def _fsync_folder(folder: Path) -> None:
    try:
        fd = os.open(str(folder), os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as err:
        if err.errno not in _NO_DIR_FSYNC:
            raise
    finally:
        os.close(fd)


def _set_mode(path: str, mode: int) -> None:
    # mkstemp makes the file private (0600); a FAT card ignores modes and may refuse chmod.
    try:
        os.chmod(path, mode)
    except OSError:
        pass


def _make_folders(folder: Path, made: list) -> None:
    """mkdir -p, with each new folder's entry fsync'ed into its parent; each new folder is appended to `made`."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    for new in reversed(missing):
        new.mkdir()
        made.append(new)
        _fsync_folder(new.parent)


def free_space(root: Path) -> tuple[int, int]:
    """(bytes free for us, allocation block in bytes) of the card's file system."""
    info = os.statvfs(str(root))
    block = info.f_frsize or info.f_bsize
    return info.f_bavail * block, block


def write_file(root: Path, relative: str, data: bytes, mode: int, made_folders: list | None = None) -> None:
    """Write `data` to the card path durably: temporary file, fsync, rename, fsync of the folder. Folders it
    makes are appended to `made_folders` (so a failed deploy can remove them)."""
    target = on_card(root, relative)
    _make_folders(target.parent, [] if made_folders is None else made_folders)
    fd, tmp = tempfile.mkstemp(prefix="." + target.name + TEMP_MARK, dir=str(target.parent))
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        _set_mode(tmp, mode)
        os.replace(tmp, str(target))
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)
    _fsync_folder(target.parent)


def restore_file(root: Path, backup: str, relative: str) -> None:
    """Put the backup back in place of the file (a rename: it needs no free space)."""
    os.replace(str(on_card(root, backup)), str(on_card(root, relative)))
    _fsync_folder(on_card(root, relative).parent)


def remove_folder(folder: Path) -> None:
    folder.rmdir()
    _fsync_folder(folder.parent)


def remove_file(root: Path, relative: str) -> None:
    path = on_card(root, relative)
    os.unlink(str(path))
    _fsync_folder(path.parent)


def file_mode(root: Path, relative: str, default: int) -> int:
    """The permission bits a rewritten file keeps (a new file gets `default`)."""
    try:
        return on_card(root, relative).stat().st_mode & 0o777
    except FileNotFoundError:
        return default
