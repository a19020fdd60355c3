"""Atomic file output: nothing already written is lost or left half-written. Checked input files.

Every writer in the project goes through these helpers: the data is written to a temporary file in the
target's folder and renamed over the target only once it is complete. A command checks its output location
first (``check_output_file`` / ``check_output_dir``), before any work, so that a wrong ``--out`` costs one
line, not a whole run. Readers of user files (``read_text`` / ``read_json``) turn every way a file can be
bad (missing, a folder, not UTF-8, too big, too deeply nested) into a one-line ForaNavError naming it.
"""
import contextlib
import json
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from host_tools.errors import ForaNavError

MAX_TEXT_BYTES = 256 * 1024 * 1024  # a map, CSV or clip sidecar larger than this is not one of ours
NAME_MAX = 255  # bytes of one file or folder name (Linux filesystems; FAT's long names too)
TEMP_STEM_CHARS = 40  # of the target's name kept in its temporary file's name (so that any name fits)
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")  # what the figure writers (matplotlib) are asked to write


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path`` (same suffix); rename it to ``path`` on success.

    For writers that want a file name (``cv2.imwrite``, ``np.savez``, matplotlib ``savefig``).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = path.suffix if len(path.suffix) <= 16 else ""  # writers choose the format by the suffix
    fd, tmp = tempfile.mkstemp(prefix="." + path.stem[:TEMP_STEM_CHARS] + ".", suffix=".tmp" + suffix,
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        # mkstemp makes the file 0600; give it the mode a plain open() would have.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_figure(figure: Any, path: str | os.PathLike, **savefig_options: Any) -> None:
    """A matplotlib figure written atomically, with no software/date stamp (same data, same bytes)."""
    with atomic_path(path) as tmp:
        figure.savefig(str(tmp), metadata={"Software": None}, **savefig_options)


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path: str | os.PathLike, text: str) -> None:
    write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike, obj: Any, indent: int | None = 2) -> None:
    write_text(path, json.dumps(obj, indent=indent, sort_keys=False) + "\n")


# ---- output locations, checked before the work starts -------------------------------------------------------


def writable_reason(folder: Path) -> str:
    """'' when a file can be created in the existing folder, else the reason (tries it: permissions, ACLs,
    read-only mounts and immutable folders all count, also for root)."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".foranav-probe-", dir=folder)
    except OSError as err:
        return err.strerror or str(err)
    os.close(fd)
    os.unlink(probe)
    return ""


def _nearest_existing(path: Path) -> Path:
    path = Path(os.path.abspath(path))
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def check_output_file(path: str | os.PathLike, option: str = "--out") -> Path:
    """Refuse (ForaNavError) an output file that cannot be written: a folder, a parent folder that is missing
    or is a file, a read-only folder. Creates nothing."""
    path = Path(path)
    if str(path) == "" or path.name in ("", ".", ".."):
        raise ForaNavError("%s %s: not a file name" % (option, path))
    _check_name_lengths(option, path)
    if path.is_dir():
        raise ForaNavError("%s %s: is a folder, expected a file" % (option, path))
    parent = path.parent
    if not parent.exists():
        raise ForaNavError("%s %s: folder %s does not exist" % (option, path, parent))
    if not parent.is_dir():
        raise ForaNavError("%s %s: %s is not a folder" % (option, path, parent))
    _check_writable(option, path, parent)
    return path


def check_output_dir(path: str | os.PathLike, option: str = "--out") -> Path:
    """Refuse (ForaNavError) an output folder that cannot be written: an existing file, a path through a file,
    a read-only folder. A missing folder is fine when it can be created (its nearest existing ancestor is a
    writable folder); it is not created here."""
    path = Path(path)
    if str(path) == "":
        raise ForaNavError("%s: empty folder name" % option)
    _check_name_lengths(option, path)
    if path.exists() and not path.is_dir():
        raise ForaNavError("%s %s: is a file, expected a folder" % (option, path))
    existing = _nearest_existing(path)
    if not existing.is_dir():
        raise ForaNavError("%s %s: %s is a file, not a folder" % (option, path, existing))
    _check_writable(option, path, existing)
    return path


def check_figure_file(path: str | os.PathLike, option: str) -> Path:
    """check_output_file for a figure: also a suffix the figure writer knows (it picks the format by it)."""
    path = check_output_file(path, option)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise ForaNavError("%s %s: a figure is written as %s, not %r" % (option, path, "/".join(FIGURE_SUFFIXES),
                                                                        path.suffix or "(no suffix)"))
    return path


def short_name(path: str | os.PathLike, chars: int = 60) -> str:
    """A path for a one-line message: at most `chars` characters (its start and end)."""
    text = str(path)
    return text if len(text) <= chars else text[:chars // 2 - 2] + "..." + text[-(chars // 2 - 1):]


def _check_name_lengths(option: str, path: Path) -> None:
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > NAME_MAX:
            raise ForaNavError("%s %s: a name of %d bytes; file and folder names are at most %d"
                               % (option, short_name(path), size, NAME_MAX))


def _check_writable(option: str, path: Path, folder: Path) -> None:
    reason = writable_reason(folder)
    if reason:
        raise ForaNavError("%s %s: cannot write in %s: %s" % (option, path, folder, reason))


# ---- input files -------------------------------------------------------------------------------------------


def read_text(path: str | os.PathLike, what: str = "file", max_bytes: int = MAX_TEXT_BYTES) -> str:
    """A UTF-8 text file, or ForaNavError naming it: missing, a folder, unreadable, too big, not UTF-8."""
    path = Path(path)
    try:
        if path.is_dir():
            raise ForaNavError("%s: is a folder, expected a %s" % (path, what))
        if path.exists() and not path.is_file():  # a FIFO or a device: reading it may never end
            raise ForaNavError("%s: not a regular file (a FIFO, socket or device), expected a %s" % (path, what))
        with open(path, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as err:
        raise ForaNavError("%s: cannot read %s: %s" % (path, what, err.strerror or err))
    if len(data) > max_bytes:
        raise ForaNavError("%s: %s larger than %d MiB" % (path, what, max_bytes // (1024 * 1024)))
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data[:err.start].count(b"\n") + 1
        raise ForaNavError("%s: %s is not UTF-8 text (byte 0x%02x on line %d)" % (path, what, data[err.start], line))


def read_json(path: str | os.PathLike, what: str = "JSON file", **loads_kwargs: Any) -> Any:
    """Decoded JSON of a UTF-8 file, or ForaNavError naming it (also for nesting too deep to decode)."""
    text = read_text(path, what)
    try:
        return json.loads(text, **loads_kwargs)
    except json.JSONDecodeError as err:
        raise ForaNavError("%s: not valid JSON: %s (line %d)" % (path, err.msg, err.lineno))
    except RecursionError:
        raise ForaNavError("%s: JSON nested too deeply" % path)
    except ValueError as err:  # e.g. an integer of more digits than int() converts
        raise ForaNavError("%s: not valid JSON: %s" % (path, err))
