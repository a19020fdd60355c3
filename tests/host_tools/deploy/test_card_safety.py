"""Deploy never harms the card: write-protected files, symlinks off the card, a folder where a file goes (all
found before the first write), fsync around every rename, and the temporary files a killed deploy leaves."""
import os
import signal
import stat
import subprocess
import sys

import pytest

from host_tools.deploy import card, card_fs
from host_tools.errors import ForaNavError

from .conftest import BAD_INPUT_EXIT, MODULE, USER_VIDEOMAPPINGS, deploy, make_card, make_module_folder, tree_digest

VIDEOMAPPINGS = "config/videomappings.cfg"
KILL_TIMEOUT_S = 120


def one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_that_a_write_protected_videomappings_cfg_is_refused_with_one_line_and_nothing_written(card_and_module,
                                                                                                 capsys):
    sd, module_dir = card_and_module
    (sd / VIDEOMAPPINGS).chmod(0o444)
    before = tree_digest(sd)
    assert deploy(sd, module_dir) == BAD_INPUT_EXIT
    line = one_error_line(capsys)
    assert VIDEOMAPPINGS in line and "write-protected" in line and "--force" in line
    assert tree_digest(sd) == before


def test_that_force_rewrites_a_write_protected_file_and_keeps_it_protected(card_and_module):
    sd, module_dir = card_and_module
    (sd / VIDEOMAPPINGS).chmod(0o444)
    assert deploy(sd, module_dir, "--force") == 0
    assert "ForaNavTrees" in (sd / VIDEOMAPPINGS).read_text()
    assert stat.S_IMODE((sd / VIDEOMAPPINGS).stat().st_mode) == 0o444


@pytest.mark.parametrize("link", ["modules/ForaNav", "config/initscript.cfg"])
def test_that_a_symlink_off_the_card_is_never_written_through(tmp_path, capsys, link):
    # Fixture: the link points at a folder / file of someone else's, outside the card.
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src")
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    target = outside / "theirs.cfg"
    target.write_text("their file\n")
    (sd / link).unlink() if (sd / link).exists() else None
    os.symlink(str(outside if link == "modules/ForaNav" else target), str(sd / link))
    before_card, before_outside = tree_digest(sd), tree_digest(outside)
    # Test
    assert deploy(sd, module_dir, "--headless") == BAD_INPUT_EXIT
    # Assert
    line = one_error_line(capsys)
    assert link in line and "off the card" in line
    assert tree_digest(outside) == before_outside and sorted(os.listdir(outside)) == ["theirs.cfg"]
    assert tree_digest(sd) == before_card


def test_that_a_symlink_that_stays_on_the_card_is_followed(card_and_module):
    sd, module_dir = card_and_module
    (sd / "modules" / "Shared").mkdir()
    os.symlink("Shared", str(sd / "modules" / "ForaNav"))
    assert deploy(sd, module_dir) == 0
    assert (sd / "modules" / "Shared" / "ForaNavTrees" / "ForaNavTrees.py").is_file()


@pytest.mark.parametrize("blocker", ["config/initscript.cfg", MODULE + "/params.cfg", "modules/ForaNav"])
def test_that_a_folder_or_file_in_the_way_is_found_before_the_first_write(tmp_path, capsys, blocker):
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src")
    if (sd / blocker).exists():
        (sd / blocker).unlink()
    if blocker == "modules/ForaNav":
        (sd / blocker).write_text("a file where the vendor folder goes\n")
    else:
        (sd / blocker).mkdir(parents=True)
    before = tree_digest(sd)
    assert deploy(sd, module_dir, "--headless") == BAD_INPUT_EXIT
    assert blocker in one_error_line(capsys)
    assert tree_digest(sd) == before  # not one file of the twelve was written


def test_that_every_rename_has_its_file_fsynced_before_and_its_folder_after(card_and_module, monkeypatch):
    sd, module_dir = card_and_module
    events = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        events.append(("fsync-dir" if stat.S_ISDIR(os.fstat(fd).st_mode) else "fsync-file", fd))
        real_fsync(fd)

    def replace(src, dst, *args, **kwargs):
        events.append(("replace", str(dst)))
        real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    assert deploy(sd, module_dir) == 0
    kinds = [kind for kind, _ in events]
    renames = [i for i, kind in enumerate(kinds) if kind == "replace"]
    assert len(renames) == 7  # 5 module files, videomappings.cfg and its backup
    for i in renames:
        assert kinds[i - 1] == "fsync-file"
        assert kinds[i + 1] == "fsync-dir"


def test_that_only_our_own_temporary_files_are_recognised():
    ours = [".params.cfg.foranav-tmp-k2j_9xq1", ".videomappings.abc12_xy.cfg.tmp.cfg"]
    theirs = [".params.cfg.tmp", "notes.tmp", ".videomappings.cfg.swp", ".foranav-tmp-", "params.cfg.foranav-tmp-1",
              ".videomappings.abc12_xy.cfg.tmp.txt"]
    assert [bool(card_fs.TEMP_FILE_RE.match(n) or card_fs.LEGACY_TEMP_FILE_RE.match(n)) for n in ours + theirs] \
        == [True] * len(ours) + [False] * len(theirs)


KILLED_DEPLOY = r"""
import os, signal, sys
from host_tools import cli
real_replace = os.replace
def replace(src, dst, *args, **kwargs):
    if dst.endswith("videomappings.cfg"):
        os.kill(os.getpid(), signal.SIGKILL)  # the user yanks the card / kills the deploy before this rename
    real_replace(src, dst, *args, **kwargs)
os.replace = replace
sys.exit(cli.main(["deploy", "--sd", sys.argv[1], "--module-dir", sys.argv[2]]))
"""


def _temp_files(sd):
    return sorted(str(p.relative_to(sd)) for p in sd.rglob(".*") if "tmp" in p.name)


def test_that_the_next_deploy_removes_the_temporary_file_a_killed_deploy_left(card_and_module, capsys):
    sd, module_dir = card_and_module
    (sd / "config" / ".my-notes.tmp").write_text("the user's own\n")
    killed = subprocess.run([sys.executable, "-c", KILLED_DEPLOY, str(sd), str(module_dir)], capture_output=True,
                            timeout=KILL_TIMEOUT_S)
    assert killed.returncode == -signal.SIGKILL
    assert len(_temp_files(sd)) == 2  # the user's and the killed deploy's
    assert (sd / VIDEOMAPPINGS).read_text() == USER_VIDEOMAPPINGS  # whole: the old bytes
    # Test
    assert deploy(sd, module_dir) == 0
    # Assert
    assert _temp_files(sd) == ["config/.my-notes.tmp"]
    assert "interrupted deploy, removed" in capsys.readouterr().out
    assert "ForaNavTrees" in (sd / VIDEOMAPPINGS).read_text()


def test_that_an_unrelated_symlink_off_the_card_in_config_does_not_block_the_deploy(card_and_module, tmp_path):
    sd, module_dir = card_and_module
    (tmp_path / "elsewhere.cfg").write_text("x\n")
    os.symlink(str(tmp_path / "elsewhere.cfg"), str(sd / "config" / "other-tool.cfg"))
    assert deploy(sd, module_dir) == 0
    assert (tmp_path / "elsewhere.cfg").read_text() == "x\n"


def test_that_a_folder_deploy_may_not_write_in_is_refused_before_writing():
    # Pure: check_plan against what inspect_plan would report for a read-only config/ (root ignores modes, so
    # the entry is made up here rather than by chmod).
    plan = card.DeployPlan([card.FileChange("modules/V/M/a.py", "create", b"a"),
                            card.FileChange(VIDEOMAPPINGS, "update", b"b", VIDEOMAPPINGS + ".foranav-bak-1")], [])
    entries = {"modules": card_fs.Entry("folder"), "modules/V": card_fs.Entry("missing"),
               "modules/V/M": card_fs.Entry("missing"), "modules/V/M/a.py": card_fs.Entry("missing"),
               "config": card_fs.Entry("folder", write_protected=True), VIDEOMAPPINGS: card_fs.Entry("file"),
               VIDEOMAPPINGS + ".foranav-bak-1": card_fs.Entry("missing")}
    with pytest.raises(ForaNavError, match="config/ is not writable"):
        card.check_plan(plan, entries, force=True, shown_root="SD")
    entries["config"] = card_fs.Entry("folder")
    card.check_plan(plan, entries, force=False, shown_root="SD")


def test_that_a_dry_run_lists_a_stray_temporary_file_and_the_deploy_removes_it(card_and_module, capsys):
    # The name host_tools.fileio gave its temporary files, as a deploy killed before this version left them.
    sd, module_dir = card_and_module
    stray = sd / "config" / ".videomappings.k2j_9xq1.cfg.tmp.cfg"
    stray.write_text("half")
    assert deploy(sd, module_dir, "--dry-run") == 0
    assert "remove config/.videomappings.k2j_9xq1.cfg.tmp.cfg" in capsys.readouterr().out and stray.exists()
    assert deploy(sd, module_dir) == 0
    assert not stray.exists()
