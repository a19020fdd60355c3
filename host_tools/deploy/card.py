"""Deploying to a mounted JEVOIS partition: a pure plan of file changes, and the adapters that read the card
and carry the plan out (numbered backups, durable atomic writes: card_fs).

The plan is computed from the card's current contents, then checked whole against what is on the card (a
folder where a file goes, a write-protected file, a symlink off the card), all before anything is written, so a
bad card, a bad module or a damaged config file stops the deploy with nothing changed; `--dry-run` prints the
same plan and stops. A write that fails anyway undoes the deploy; temporary files an interrupted deploy left
are removed after a successful one.
"""
import os
import re
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

from host_tools.deploy import card_fs
from host_tools.deploy.initscript import block_mapping, headless_commands, plan_initscript
from host_tools.deploy.modes import CameraMode
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


@dataclass(frozen=True)
class CardState:
    files: dict  # {card path: bytes} of every file the deploy may change
    names: frozenset  # card paths of the files present in config/ and the module folder
    stray: tuple = ()  # card paths of temporary files an interrupted deploy left


@dataclass(frozen=True)
class FileChange:
    path: str
    action: str  # create, update, same or remove (a stray temporary file)
    data: bytes
    backup: str = None
    detail: tuple = ()
    old_size: int = 0  # bytes of the file on the card now (what its backup takes)


@dataclass(frozen=True)
class DeployPlan:
    changes: list
    notes: list


def module_dir(vendor: str, module: str) -> str:
    return "%s/%s/%s" % (MODULES_DIR, vendor, module)


def decode(data: bytes) -> str:
    return data.decode(*TEXT_CODEC)


def encode(text: str) -> bytes:
    return text.encode(*TEXT_CODEC)


def backup_path(path: str, names: Collection[str]) -> str:
    """`<path>.foranav-bak-<n>`, n one more than the highest backup of `path` already on the card."""
    numbers = [int(m.group("n")) for m in (_BACKUP_RE.match(name) for name in names)
               if m and m.group("path") == path]
    return "%s%s%d" % (path, BACKUP_MARK, max(numbers, default=0) + 1)


def is_backup(path: str) -> bool:
    return _BACKUP_RE.match(path) is not None


def plan_file(state: CardState, path: str, data: bytes, detail: Sequence[str] = ()) -> FileChange:
    old = state.files.get(path)
    if old is None:
        return FileChange(path, "create", data, None, tuple(detail))
    if old == data:
        return FileChange(path, "same", data, None, ())
    return FileChange(path, "update", data, backup_path(path, state.names), tuple(detail), len(old))


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


def plan_deploy(state: CardState, payload: dict, vendor: str, module: str, mode: CameraMode,
                headless: bool) -> DeployPlan:
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
        if name.startswith(folder + "/") and name not in deployed and not is_backup(name) \
                and name not in state.stray:
            notes.append("%s is not part of this module release; left in place" % name)
    removals = [FileChange(path, "remove", b"") for path in state.stray]
    notes += ["%s: temporary file of an interrupted deploy, removed" % path for path in state.stray]
    return DeployPlan(removals + changes, notes)


def check_card(root: str | os.PathLike) -> Path:
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
    real = card_fs.real_root(root)
    for folder in (CONFIG_DIR, MODULES_DIR):
        card_fs.on_card(real, folder)
    kind = card_fs.entry(real, VIDEOMAPPINGS).kind
    if kind == "missing":
        raise ForaNavError("--sd %s: %s is missing; boot the camera once with this card to create it"
                           % (root, VIDEOMAPPINGS))
    if kind != "file":
        raise ForaNavError("--sd %s: %s is a %s, not a file" % (root, VIDEOMAPPINGS, kind))
    return real


def _relative_files(root, folder, needed=None):
    """Card paths of the files in `folder`. A symlink off the card is refused if deploy needs that file
    (`needed` None: every file of the folder), and otherwise left out: deploy neither reads nor writes it."""
    if card_fs.entry(root, folder).kind != "folder":
        return []
    base = card_fs.on_card(root, folder)
    names = []
    for name in (folder + "/" + path.name for path in sorted(base.iterdir())):
        try:
            kind = card_fs.entry(root, name).kind
        except ForaNavError:
            if needed is None or name in needed:
                raise
            continue
        if kind == "file":
            names.append(name)
    return names


def _module_folders(vendor, module):
    return [MODULES_DIR + "/" + vendor, module_dir(vendor, module)]


def read_card(root: str | os.PathLike, vendor: str, module: str) -> CardState:
    """Adapter: CardState with the bytes of every file the deploy may change and the names already present.

    Every path it reads is resolved first: a symlink off the card stops the deploy here, before any write.
    """
    shown = root
    root = check_card(root)
    for folder in _module_folders(vendor, module):
        card_fs.on_card(root, folder)
    folder = module_dir(vendor, module)
    module_files = _relative_files(root, folder)
    names = _relative_files(root, CONFIG_DIR, (VIDEOMAPPINGS, INITSCRIPT)) + module_files
    wanted = set(module_files) | {VIDEOMAPPINGS, INITSCRIPT}
    try:
        files = {name: card_fs.on_card(root, name).read_bytes() for name in names if name in wanted}
        stray = card_fs.stray_temp_files(root, CONFIG_DIR) + card_fs.stray_temp_files(root, folder)
    except OSError as err:
        raise ForaNavError("--sd %s: cannot read the card: %s" % (shown, err))
    files = {name: data for name, data in files.items() if name not in stray}
    return CardState(files, frozenset(names), tuple(stray))


def _parents(path):
    parts = path.split("/")[:-1]
    return ["/".join(parts[:i]) for i in range(1, len(parts) + 1)]


def check_plan(plan: DeployPlan, entries: dict, force: bool, shown_root: str | os.PathLike) -> None:
    """Pure: the plan against what is on the card (`entries`: {card path: card_fs.Entry}, for every path the
    plan writes, its backups and their folders). ForaNavError on the first path that would fail or that the
    user protected; nothing has been written yet."""
    protected = []
    for change in plan.changes:
        if change.action == "same":
            continue
        for folder in _parents(change.path):
            if entries[folder].kind not in ("folder", "missing"):
                raise ForaNavError("--sd %s: %s is a %s where deploy needs a folder; move it away and deploy "
                                   "again" % (shown_root, folder, entries[folder].kind))
        parent = entries[_parents(change.path)[-1]]
        if parent.kind == "folder" and parent.write_protected:
            raise ForaNavError("--sd %s: %s/ is not writable (mounted read-only, or its permissions?)"
                               % (shown_root, _parents(change.path)[-1]))
        kind = entries[change.path].kind
        if change.action == "remove":
            continue
        if kind not in ("file", "missing"):
            raise ForaNavError("--sd %s: %s is a %s, not a file; move it away and deploy again"
                               % (shown_root, change.path, kind))
        if change.backup and entries[change.backup].kind != "missing":
            raise ForaNavError("--sd %s: %s is in the way of the backup; move it away and deploy again"
                               % (shown_root, change.backup))
        if kind == "file" and entries[change.path].write_protected:
            protected.append(change.path)
    if protected and not force:
        more = " (and %d more)" % (len(protected) - 1) if len(protected) > 1 else ""
        raise ForaNavError("--sd %s: %s%s is write-protected; deploy leaves it alone unless you give --force"
                           % (shown_root, protected[0], more))


def inspect_plan(root: str | os.PathLike, plan: DeployPlan) -> dict:
    """Adapter: card_fs.Entry of every path `plan` touches (raises if one leads off the card)."""
    root = card_fs.real_root(root)
    paths = set()
    for change in plan.changes:
        paths.update([change.path] + _parents(change.path) + ([change.backup] if change.backup else []))
    return {path: card_fs.entry(root, path) for path in sorted(paths)}


def _blocks(size: int, block: int) -> int:
    return -(-size // block) * block


def bytes_needed(plan: DeployPlan, entries: dict, block: int) -> int:
    """Pure: the most card space the writes take at once, in whole allocation blocks: every backup and new
    file, what updated files grow by, the largest temporary file (it sits beside the old file until the
    rename), one block per new folder, and one block to spare for folder entries."""
    writes = [change for change in plan.changes if change.action in ("create", "update")]
    total = sum(_blocks(change.old_size, block) for change in writes if change.action == "update")  # backups
    total += sum(_blocks(len(change.data), block) for change in writes if change.action == "create")
    total += sum(max(0, _blocks(len(change.data), block) - _blocks(change.old_size, block))
                 for change in writes if change.action == "update")
    total += max((_blocks(len(change.data), block) for change in writes if change.action == "update"), default=0)
    new_folders = {folder for change in writes for folder in _parents(change.path)
                   if entries.get(folder, card_fs.Entry("folder")).kind == "missing"}
    return total + (len(new_folders) + 1) * block if writes else 0


def check_space(plan: DeployPlan, entries: dict, free: int, block: int, shown_root: str | os.PathLike) -> None:
    """Pure: ForaNavError naming the card, the bytes needed and the bytes free when the writes do not fit."""
    needed = bytes_needed(plan, entries, block)
    if needed > free:
        count = len(changed_paths(plan))
        raise ForaNavError("--sd %s: not enough space on the card: deploy needs %d bytes (%d file%s and their "
                           "backups), %d bytes are free; free %d bytes (old .foranav-bak-<n> backups?) and deploy "
                           "again" % (shown_root, needed, count, "" if count == 1 else "s", free, needed - free))


def preflight(root: str | os.PathLike, plan: DeployPlan, force: bool) -> None:
    """Adapter: everything the writes need is checked before the first one (see check_plan), the card's free
    space included (see check_space)."""
    entries = inspect_plan(root, plan)
    check_plan(plan, entries, force, root)
    free, block = card_fs.free_space(card_fs.real_root(root))
    check_space(plan, entries, free, block, root)


@dataclass
class _Written:
    """What apply_plan has done so far, to undo it when a write fails."""
    backups: list
    created: list
    updated: list  # (path, backup)
    folders: list


def _undo(root: Path, done: _Written) -> list[str]:
    """Put the card back as it was before the deploy: each updated file from its backup, then remove the files
    and folders the deploy made. Returns the paths it could not restore."""
    left = []
    for path, backup in reversed(done.updated):
        try:
            card_fs.restore_file(root, backup, path)
            done.backups.remove(backup)
        except OSError:
            left.append(path)
    for path in reversed(done.created + done.backups):
        try:
            card_fs.remove_file(root, path)
        except OSError:
            left.append(path)
    for folder in reversed(done.folders):
        try:
            card_fs.remove_folder(folder)
        except OSError:
            left.append(str(folder.relative_to(root)) + "/")
    return left


def apply_plan(root: str | os.PathLike, plan: DeployPlan) -> None:
    """Adapter: back up every file that changes, write the new contents durably in plan order, then remove the
    stray temporary files. A write that fails anyway (the card filled up under us, was pulled) undoes
    everything this deploy wrote, so the card is as it was: never half a module."""
    shown, root = root, card_fs.real_root(root)
    if not os.access(str(root), os.W_OK):
        raise ForaNavError("--sd %s: the card is not writable (mounted read-only?)" % shown)
    done = _Written([], [], [], [])
    current = None
    try:
        for change in plan.changes:
            if change.action == "update":
                current = change.backup
                mode = card_fs.file_mode(root, change.path, NEW_FILE_MODE)
                card_fs.write_file(root, change.backup, card_fs.on_card(root, change.path).read_bytes(), mode,
                                   done.folders)
                done.backups.append(change.backup)
        for change in plan.changes:
            if change.action in ("create", "update"):
                current = change.path
                card_fs.write_file(root, change.path, change.data, card_fs.file_mode(root, change.path,
                                                                                     NEW_FILE_MODE), done.folders)
                if change.action == "create":
                    done.created.append(change.path)
                else:
                    done.updated.append((change.path, change.backup))
    except OSError as err:
        left = _undo(root, done)
        state = ("the card is as it was before this deploy" if not left else
                 "could not undo %s: restore them from their .foranav-bak-<n> backups" % ", ".join(left))
        raise ForaNavError("--sd %s: writing %s failed (%s); %s"
                           % (shown, current, err.strerror or err, state))
    for change in plan.changes:
        if change.action == "remove":
            try:
                card_fs.remove_file(root, change.path)
            except OSError:
                pass  # a leftover temporary file; the next deploy tries again


def describe_plan(plan: DeployPlan, root: str | os.PathLike, dry_run: bool) -> list[str]:
    """The lines `foranav deploy` prints: one per file, what is added to config files, then the notes."""
    verb = {"create": "create", "update": "update", "same": "keep  ", "remove": "remove"}
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


def changed_paths(plan: DeployPlan) -> list:
    return [change.path for change in plan.changes if change.action in ("create", "update")]
