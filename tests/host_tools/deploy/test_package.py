"""`foranav package`: the .jvpkg members sit where the camera expects them, the archive is byte-for-byte
reproducible, and its postinstall registers the mappings when run by `sh` against a fake JEVOIS tree, agreeing
with what `foranav deploy` writes."""
import bz2
import io
import os
import shutil
import subprocess
import tarfile

import pytest

from host_tools import cli
from host_tools.deploy import module_files, package
from host_tools.deploy.modes import parse_mode
from host_tools.deploy.videomappings import plan_videomappings

from .conftest import BAD_INPUT_EXIT, MODULE, USER_VIDEOMAPPINGS, make_card, make_module_folder

EXPECTED_FILES = ["ForaNavTrees.py", "foranav_helper.py", "foranav_oil_palm.npz", "params.cfg", "postinstall",
                  "script.cfg"]
POSTINSTALL_TIMEOUT_S = 30

needs_shell_tools = pytest.mark.skipif(not all(shutil.which(tool) for tool in ("sh", "awk", "tail", "tar", "bzcat")),
                                       reason="needs sh, awk, tail, tar and bzcat")


def build(tmp_path, *extra, name="ForaNav-ForaNavTrees.jvpkg"):
    module_dir = tmp_path / "src" / "ForaNavTrees"
    if not module_dir.exists():
        make_module_folder(tmp_path / "src")
    out = tmp_path / name
    code = cli.main(["package", "--out", str(out), "--module-dir", str(module_dir)] + list(extra))
    return code, out


def members(path):
    with tarfile.open(path, mode="r:bz2") as tar:
        return tar.getmembers()


def install(pkg, root):
    """What jevois.sh does at boot: unpack in the JEVOIS root, then `sh postinstall` in the module folder."""
    subprocess.run("bzcat '%s' | tar xf -" % pkg, shell=True, cwd=str(root), check=True)
    return run_postinstall(root)


def run_postinstall(root, path=None):
    env = dict(os.environ, **{package.ROOT_ENV: str(root)})
    if path is not None:
        env["PATH"] = path
    return subprocess.run(["sh", "postinstall"], cwd=str(root / MODULE), env=env, check=True, capture_output=True,
                          text=True, timeout=POSTINSTALL_TIMEOUT_S)


def test_that_the_package_holds_the_module_files_at_the_paths_the_camera_expects(tmp_path):
    code, out = build(tmp_path)
    assert code == 0
    files = [m for m in members(out) if m.isfile()]
    assert sorted(m.name for m in files) == [MODULE + "/" + name for name in EXPECTED_FILES]
    assert all(not m.name.startswith(("/", "./")) and ".." not in m.name.split("/") for m in members(out))
    modes = {m.name.rsplit("/", 1)[1]: m.mode for m in files}
    assert modes["postinstall"] == 0o755 and modes["ForaNavTrees.py"] == 0o644


def test_that_the_package_is_a_bzip2_tar_with_fixed_metadata(tmp_path):
    code, out = build(tmp_path)
    assert out.read_bytes()[:3] == b"BZh"
    tarfile.open(fileobj=io.BytesIO(bz2.decompress(out.read_bytes())), mode="r:")  # a plain tar inside
    assert {(m.uid, m.gid, m.uname, m.gname, m.mtime) for m in members(out)} == {(0, 0, "", "", package.FIXED_MTIME)}
    names = [m.name for m in members(out)]
    assert names == sorted(n for n in names if n.endswith("/")) + sorted(n for n in names if not n.endswith("/"))


def test_that_the_same_command_gives_the_same_bytes(tmp_path):
    _, first = build(tmp_path, name="a.jvpkg")
    os.utime(tmp_path / "src" / "ForaNavTrees" / "ForaNavTrees.py", (1, 1))  # mtimes must not leak in
    _, second = build(tmp_path, name="b.jvpkg")
    assert first.read_bytes() == second.read_bytes()
    _, third = build(tmp_path, "--mode", "352x288@10", name="c.jvpkg")
    assert third.read_bytes() != first.read_bytes()


def test_that_an_output_name_the_camera_would_ignore_is_refused(tmp_path, capsys):
    code, out = build(tmp_path, name="ForaNav.tar.bz2")
    assert code == BAD_INPUT_EXIT
    assert ".jvpkg" in capsys.readouterr().err
    assert not out.exists()


def test_that_a_package_of_a_broken_module_is_refused(tmp_path, capsys):
    make_module_folder(tmp_path / "src", model=False)
    code, out = build(tmp_path)
    assert code == BAD_INPUT_EXIT
    assert "foranav_oil_palm.npz" in capsys.readouterr().err
    assert not out.exists()


@needs_shell_tools
def test_that_the_postinstall_registers_the_mappings_once_like_deploy_does(tmp_path):
    # Fixture
    sd = make_card(tmp_path)
    _, pkg = build(tmp_path)
    expected = plan_videomappings(USER_VIDEOMAPPINGS, "ForaNav", "ForaNavTrees", parse_mode("352x288@15")).text
    # Test
    install(pkg, sd)
    after_first = (sd / "config" / "videomappings.cfg").read_text()
    run_postinstall(sd)
    # Assert
    assert after_first == expected
    assert (sd / "config" / "videomappings.cfg").read_text() == expected  # the second run added nothing
    assert (sd / MODULE / "foranav_oil_palm.npz").is_file()


@needs_shell_tools
@pytest.mark.parametrize("user_text", [
    USER_VIDEOMAPPINGS.rstrip("\n"),                                             # no final newline
    USER_VIDEOMAPPINGS + "YUYV 352 288 15.0 YUYV 352 288 15.0 JeVois PassThrough\n"
                         "YUYV +0 +0 14.0 YUYV 352 288 14.0 JeVois SaveVideo\n",  # our USB rates taken
    "",                                                                          # empty file
])
def test_that_the_postinstall_and_deploy_agree_on_awkward_files(tmp_path, user_text):
    sd = make_card(tmp_path, videomappings=user_text)
    _, pkg = build(tmp_path, "--mode", "352x288@15")
    install(pkg, sd)
    expected = plan_videomappings(user_text, "ForaNav", "ForaNavTrees", parse_mode("352x288@15")).text
    assert (sd / "config" / "videomappings.cfg").read_text() == expected


@needs_shell_tools
def test_that_the_postinstall_leaves_jevois_add_videomapping_alone_on_a_test_root(tmp_path):
    # jevois-add-videomapping only knows /jevois: with the root overridden, calling it would edit the wrong card.
    sd = make_card(tmp_path)
    _, pkg = build(tmp_path)
    tools = tmp_path / "bin"
    tools.mkdir()
    marker = tmp_path / "called"
    (tools / "jevois-add-videomapping").write_text("#!/bin/sh\necho \"$@\" > '%s'\n" % marker)
    (tools / "jevois-add-videomapping").chmod(0o755)
    subprocess.run("bzcat '%s' | tar xf -" % pkg, shell=True, cwd=str(sd), check=True)
    run_postinstall(sd, path=str(tools) + os.pathsep + os.environ.get("PATH", ""))
    assert not marker.exists()
    assert "NONE 0 0 0.0 YUYV 352 288 15.0 ForaNav ForaNavTrees" in (sd / "config" / "videomappings.cfg").read_text()


def test_that_the_real_module_folder_packages(tmp_path):
    folder = module_files.default_module_folder()
    if not (folder / module_files.DEFAULT_MODEL).is_file():
        pytest.skip("the default model %s is not trained yet" % module_files.DEFAULT_MODEL)
    out = tmp_path / "ForaNav-ForaNavTrees.jvpkg"
    assert cli.main(["package", "--out", str(out)]) == 0
    names = {m.name for m in members(out)}
    assert {MODULE + "/ForaNavTrees.py", MODULE + "/" + module_files.DEFAULT_MODEL, MODULE + "/postinstall"} <= names
    assert MODULE + "/__init__.py" not in names
