"""A card without room for the deploy: refused before the first write with the bytes needed and free, and a
write that fails anyway (the card filled up under us) undoes the whole deploy: never half a module."""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from host_tools.deploy import card, card_fs
from host_tools.errors import ForaNavError

from .conftest import BAD_INPUT_EXIT, MODULE, deploy, make_card, make_module_folder, npz_bytes, tree_digest

BLOCK = 4096


def test_that_the_bytes_needed_count_backups_new_files_growth_the_largest_temporary_file_and_new_folders():
    plan = card.DeployPlan([card.FileChange("modules/V/M/a.py", "create", b"a" * 5000),
                            card.FileChange("config/v.cfg", "update", b"b" * 9000, "config/v.cfg.foranav-bak-1",
                                            (), 100),
                            card.FileChange("config/same.cfg", "same", b"c" * 99999)], [])
    entries = {"modules": card_fs.Entry("folder"), "modules/V": card_fs.Entry("missing"),
               "modules/V/M": card_fs.Entry("missing"), "config": card_fs.Entry("folder")}
    # backup 1 block + new file 2 blocks + growth 3-1 blocks + temporary file 3 blocks + 2 new folders + 1 spare
    assert card.bytes_needed(plan, entries, BLOCK) == (1 + 2 + 2 + 3 + 2 + 1) * BLOCK
    card.check_space(plan, entries, 11 * BLOCK, BLOCK, "SD")
    with pytest.raises(ForaNavError, match=r"--sd SD: not enough space .* needs 45056 bytes .* 45055 bytes are free"):
        card.check_space(plan, entries, 11 * BLOCK - 1, BLOCK, "SD")
    assert card.bytes_needed(card.DeployPlan([plan.changes[2]], []), entries, BLOCK) == 0  # nothing to write


def _mount_tiny_card(folder, size):
    """A real file system of `size` bytes (tmpfs); needs root and mount, else the test is skipped."""
    folder.mkdir()
    if os.geteuid() != 0:
        pytest.skip("mounting a small file system needs root")
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=%d" % size, "tmpfs", str(folder)],
                          capture_output=True)
    if done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here: %s" % done.stderr.decode().strip())


@pytest.fixture
def tiny_card(tmp_path):
    mount = tmp_path / "card"
    _mount_tiny_card(mount, 128 * 1024)
    try:
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], check=True)


def test_that_a_nearly_full_128_kib_card_is_refused_with_the_bytes_needed_and_nothing_written(tiny_card, tmp_path,
                                                                                                capsys):
    sd = tiny_card
    subprocess.run(["cp", "-a", str(make_card(tmp_path / "template")) + "/.", str(sd)], check=True)
    module_dir = make_module_folder(tmp_path / "src")
    (module_dir / "foranav_weights.npz").write_bytes(npz_bytes(weights=np.zeros(2500)))  # 20 KB
    (sd / "filler").write_bytes(b"\0" * (72 * 1024))  # what the user's other files take
    before = tree_digest(sd)
    capsys.readouterr()
    assert deploy(sd, module_dir) == BAD_INPUT_EXIT
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(sd) in err[0] and "not enough space" in err[0]
    assert "bytes are free" in err[0] and "deploy needs" in err[0]
    assert tree_digest(sd) == before
    # With the filler gone the same deploy fits.
    (sd / "filler").unlink()
    assert deploy(sd, module_dir) == 0


HARNESS = textwrap.dedent('''
    """Deploy with every file capped at CAP bytes (RLIMIT_FSIZE) once the plan is made: the card 'fills up'
    during the writes, as a real full card does, without root or a small file system."""
    import argparse, resource, signal, sys
    from host_tools.deploy import card, cmd_deploy
    from host_tools.errors import ForaNavError
    parser = argparse.ArgumentParser()
    cmd_deploy.add_arguments(parser)
    args = parser.parse_args(sys.argv[2:])
    plan, mode, notes = cmd_deploy.plan_from_args(args)
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the cap then fails with EFBIG
    cap = int(sys.argv[1])
    resource.setrlimit(resource.RLIMIT_FSIZE, (cap, cap))
    try:
        card.apply_plan(args.sd, plan)
    except ForaNavError as err:
        print(err, file=sys.stderr)
        sys.exit(2)
''')


def test_that_a_write_failing_mid_deploy_puts_the_card_back_as_it_was(tmp_path):
    # Fixture: a deployed card, and a new release that changes the main file, adds a large one, and a new mode.
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src")
    assert deploy(sd, module_dir) == 0
    with open(module_dir / "ForaNavTrees.py", "a") as source:
        source.write("\n# release 2\n")
    (module_dir / "foranav_large.py").write_text("# padding\n" * 4000)
    before = tree_digest(sd)
    # Test
    done = subprocess.run([sys.executable, "-c", HARNESS, "16384", "--sd", str(sd), "--module-dir",
                           str(module_dir), "--mode", "352x288@30"], capture_output=True, text=True,
                          cwd=os.getcwd())
    # Assert: one line naming the card and the file, and every byte as before (backups and new folders gone).
    err = done.stderr.strip().splitlines()
    assert done.returncode == BAD_INPUT_EXIT, done.stderr
    assert len(err) == 1 and "foranav_large.py failed" in err[0] and "as it was before this deploy" in err[0]
    assert tree_digest(sd) == before
    assert sorted(p.name for p in (sd / MODULE).iterdir()) == ["ForaNavTrees.py", "foranav_helper.py",
                                                                 "foranav_oil_palm.npz", "params.cfg", "script.cfg"]
