"""Deploying to a mounted JEVOIS partition: a pure plan of file changes, and the adapters that read the card and
carry the plan out (numbered backups, atomic writes).

The plan is computed from the card's current contents before anything is written, so a bad card, a bad module
or a damaged config file stops the deploy with nothing changed; `--dry-run` prints the same plan and stops.
"""
import collections
import os
import re
from pathlib import Path

from host_tools import fileio
from host_tools.deploy.initscript import block_mapping, headless_commands, plan_initscript
from host_tools.deploy.videomappings import plan_videomappings
from host_tools.errors import ForaNavError

CONFIG_DIR = "config"
MODULES_DIR = "modules"
VIDEOMAPPINGS = CONFIG_DIR + "/videomappings.cfg"
INITSCRIPT = CONFIG_DIR + "/initscript.cfg"
# Backups are numbered, not timestamped, so the same deploy on the same card gives the same files.
BACKUP_MARK = ".foranav-bak-"
_BACKUP_RE = re.compile(r"^(?P<path>.*)" + re.escape(BACKUP_MARK) + r"(?P<n>\d+)$")
BOOT_PARTITION_FILES = ("uImage", "uEnv.txt", "script.bin")
# Config files keep the bytes they had, even in a legacy encoding; only our appended lines are new.
TEXT_CODEC = ("utf-8", "surrogateescape")
NEW_FILE_MODE = 0o644

CardState = collections.namedtuple("CardState", "files names")  # files: {path: bytes}; names: paths present
FileChange = collections.namedtuple("FileChange", "path action data backup detail")  # action: create|update|same
DeployPlan = collections.namedtuple("DeployPlan", "changes notes")


def module_dir(vendor, module):
    return "%s/%s/%s" % (MODULES_DIR, vendor, module)


def decode(data):
    return data.decode(*TEXT_CODEC)


def encode(text):
    return text.encode(*TEXT_CODEC)


def backup_path(path, names):
    """`<path>.foranav-bak-<n>`, n one more than the highest backup of `path` already on the card."""
    numbers = [int(m.group("n")) for m in (_BACKUP_RE.match(name) for name in names)
               if m and m.group("path") == path]
    return "%s%s%d" % (path, BACKUP_MARK, max(numbers, default=0) + 1)


def is_backup(path):
    return _BACKUP_RE.match(path) is not None


def plan_file(state, path, data, detail=()):
    old = state.files.get(path)
    if old is None:
        return FileChange(path, "create", data, None, tuple(detail))
    if old == data:
        return FileChange(path, "same", data, None, ())
    return FileChange(path, "update", data, backup_path(path, state.names), tuple(detail))


def _initscript_changes(state, vendor, module, mode, headless):
    old = state.files.get(INITSCRIPT)
    if headless:
        plan = plan_initscript(None if old is None else decode(old), vendor, module, mode)
        return [plan_file(state, INITSCRIPT, encode(plan.text), headless_commands(vendor, module, mode))], plan.notes
    mapping = block_mapping(None if old is None else decode(old))
    wanted = headless_commands(vendor, module, mode)[0]
    if mapping is not None and mapping != wanted:
        return [], ["initscript.cfg boots %r from an earlier --headless deploy; run with --headless to switch it "
                    "to %r" % (mapping, wanted)]
    return [], []


def plan_deploy(state, payload, vendor, module, mode, headless):
    """The changes that install `payload` ({file name: bytes}) as modules/<vendor>/<module>/ and register it.

    Pure: `state` is what read_card returned. Module files come first and config files last, so the camera never
    has a mapping whose module is not there yet.
    """
    folder = module_dir(vendor, module)
    changes = [plan_file(state, folder + "/" + name, data) for name, data in sorted(payload.items())]
    mappings = plan_videomappings(decode(state.files[VIDEOMAPPINGS]), vendor, module, mode)
    changes.append(plan_file(state, VIDEOMAPPINGS, encode(mappings.text),
                             [line for line in mappings.added if not line.startswith("#")]))
    init_changes, init_notes = _initscript_changes(state, vendor, module, mode, headless)
    changes += init_changes
    notes = list(mappings.notes) + init_notes
    deployed = {change.path for change in changes}
    for name in sorted(state.names):
        if name.startswith(folder + "/") and name not in deployed and not is_backup(name):
            notes.append("%s is not part of this module release; left in place" % name)
    return DeployPlan(changes, notes)


def check_card(root):
    """Adapter: refuse a PATH that is not a mounted JEVOIS partition, with one line that says what to give."""
    root = Path(root)
    if not root.is_dir():
        raise ForaNavError("--sd %s: no such folder (give the mount point of the card's JEVOIS partition)" % root)
    if any((root / name).exists() for name in BOOT_PARTITION_FILES):
        raise ForaNavError("--sd %s: this is the card's BOOT partition; give the JEVOIS partition instead" % root)
    missing = [name + "/" for name in (CONFIG_DIR, MODULES_DIR) if not (root / name).is_dir()]
    if missing:
        raise ForaNavError("--sd %s: not a JEVOIS partition (no %s); give the mount point of the card's JEVOIS "
                           "partition, e.g. /media/$USER/JEVOIS" % (root, " or ".join(missing)))
    if not (root / VIDEOMAPPINGS).is_file():
        raise ForaNavError("--sd %s: %s is missing; boot the camera once with this card to create it"
                           % (root, VIDEOMAPPINGS))
    return root


def _relative_files(root, folder):
    base = root / folder
    if not base.is_dir():
        return []
    return [folder + "/" + path.name for path in sorted(base.iterdir()) if path.is_file()]


def read_card(root, vendor, module):
    """Adapter: CardState with the bytes of every file the deploy may change and the names already present."""
    root = check_card(root)
    names = _relative_files(root, CONFIG_DIR) + _relative_files(root, module_dir(vendor, module))
    wanted = set(_relative_files(root, module_dir(vendor, module))) | {VIDEOMAPPINGS, INITSCRIPT}
    try:
        files = {name: (root / name).read_bytes() for name in names if name in wanted}
    except OSError as err:
        raise ForaNavError("--sd %s: cannot read the card: %s" % (root, err))
    return CardState(files, frozenset(names))


def _file_mode(path):
    """The permission bits a rewritten file should keep (new files: rw-r--r--, as a copy would get)."""
    try:
        return path.stat().st_mode & 0o777
    except FileNotFoundError:
        return NEW_FILE_MODE


def _set_mode(path, mode):
    # The atomic writer's temporary file is private (0600); a FAT card ignores modes and may refuse chmod.
    try:
        os.chmod(str(path), mode)
    except OSError:
        pass


def apply_plan(root, plan):
    """Adapter: back up every file that changes, then write the new contents atomically, in plan order."""
    root = Path(root)
    if not os.access(str(root), os.W_OK):
        raise ForaNavError("--sd %s: the card is not writable (mounted read-only?)" % root)
    done = []
    try:
        for change in plan.changes:
            if change.action == "update":
                fileio.write_bytes(root / change.backup, (root / change.path).read_bytes())
                _set_mode(root / change.backup, _file_mode(root / change.path))
                done.append(change.backup)
        for change in plan.changes:
            if change.action != "same":
                mode = _file_mode(root / change.path)
                fileio.write_bytes(root / change.path, change.data)
                _set_mode(root / change.path, mode)
                done.append(change.path)
    except OSError as err:
        # Each file is whole (old or new); say how far we got so the user can finish or restore from backups.
        raise ForaNavError("--sd %s: writing stopped after %d file(s) (%s): %s"
                           % (root, len(done), ", ".join(done[-3:]) or "none", err))


def describe_plan(plan, root, dry_run):
    """The lines `foranav deploy` prints: one per file, what is added to config files, then the notes."""
    verb = {"create": "create", "update": "update", "same": "keep  "}
    lines = ["%s %s:" % ("Would change" if dry_run else "Changed", root)]
    for change in plan.changes:
        suffix = "" if change.action != "same" else "  (unchanged)"
        if change.backup:
            suffix = "  (backup: %s)" % Path(change.backup).name
        lines.append("  %s %s%s" % (verb[change.action], change.path, suffix))
        lines += ["           + %s" % item for item in change.detail]
    lines += ["note: %s" % note for note in plan.notes]
    if dry_run:
        lines.append("dry run: nothing was written")
    return lines


def changed_paths(plan):
    return [change.path for change in plan.changes if change.action != "same"]
