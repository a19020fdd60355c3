"""`foranav deploy` on a fake JEVOIS partition: fresh and repeated deploys, user lines and backups, dry run,
refusals (bad PATH, bad module), headless boot, mode changes."""
import subprocess
import sys

import pytest

from host_tools import cli
from host_tools.deploy import card, card_fs, module_files
from host_tools.deploy.videomappings import parse_mappings

from .conftest import (BAD_INPUT_EXIT, HELPER_SOURCE, MODULE, USER_INITSCRIPT, USER_VIDEOMAPPINGS, deploy, make_card,
                       make_module_folder, tree_digest)

USB_LINE = "YUYV 352 288 15.0 YUYV 352 288 15.0 ForaNav ForaNavTrees"
NONE_LINE = "NONE 0 0 0.0 YUYV 352 288 15.0 ForaNav ForaNavTrees"
HEADLESS_COMMANDS = ["setmapping2 YUYV 352 288 15.0 ForaNav ForaNavTrees", "setpar serlog None",
                     "setpar serout Hard", "streamon"]


def read(sd, relative):
    return (sd / relative).read_text()


def test_that_a_fresh_deploy_installs_the_module_files_and_nothing_host_only(card_and_module):
    sd, module_dir = card_and_module
    assert deploy(sd, module_dir) == 0
    installed = sorted(p.name for p in (sd / MODULE).iterdir())
    assert installed == ["ForaNavTrees.py", "foranav_helper.py", "foranav_oil_palm.npz", "params.cfg", "script.cfg"]
    assert (sd / MODULE / "ForaNavTrees.py").read_bytes() == (module_dir / "ForaNavTrees.py").read_bytes()
    assert (sd / MODULE / "foranav_oil_palm.npz").read_bytes() == (module_dir / "foranav_oil_palm.npz").read_bytes()


def test_that_the_script_cfg_routes_serial_output_to_the_hardware_port(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir)
    commands = [line for line in read(sd, MODULE + "/script.cfg").splitlines() if not line.startswith("#")]
    assert "setpar serout Hard" in commands
    assert "setpar serlog None" in commands
    assert any(line.startswith("setpar serlimit ") and int(line.split()[2]) >= 2 for line in commands)


def test_that_params_cfg_lists_the_module_parameters_commented_out(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir)
    lines = read(sd, MODULE + "/params.cfg").splitlines()
    # JeVois stops loading the module on a line that is neither a comment nor name=value.
    assert all(line.startswith("#") or "=" in line for line in lines if line.strip())
    assert "#svmthresh=0.5" in lines
    assert "#framemark=true" in lines
    assert "#step=8" in lines  # a named constant of a helper file, through a parameter-making helper method
    # Set at load time from the model file (3 weights): only loading the module can tell.
    assert "#hsthresh=0.30000000000000004" in lines
    assert any(line.startswith("# hsthresh (float): colour test threshold") for line in lines)


def test_that_a_fresh_deploy_adds_one_usb_and_one_headless_mapping_and_keeps_every_user_line(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir)
    text = read(sd, "config/videomappings.cfg")
    assert text.startswith(USER_VIDEOMAPPINGS)
    lines = text.splitlines()
    assert lines.count(USB_LINE) == 1
    assert lines.count(NONE_LINE) == 1
    assert sum(line.split()[-1:] == ["*"] for line in lines) == 1  # the user's default stays the only one


def test_that_a_changed_config_file_is_backed_up_with_its_old_bytes(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir)
    assert read(sd, "config/videomappings.cfg.foranav-bak-1") == USER_VIDEOMAPPINGS


def test_that_a_second_deploy_changes_nothing(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir, "--headless")
    before = tree_digest(sd)
    assert deploy(sd, module_dir, "--headless") == 0
    assert tree_digest(sd) == before
    lines = read(sd, "config/videomappings.cfg").splitlines()
    assert (lines.count(USB_LINE), lines.count(NONE_LINE)) == (1, 1)


def test_that_a_dry_run_prints_the_plan_and_writes_nothing(card_and_module, capsys):
    sd, module_dir = card_and_module
    before = tree_digest(sd)
    assert deploy(sd, module_dir, "--headless", "--dry-run") == 0
    assert tree_digest(sd) == before
    out = capsys.readouterr().out
    assert USB_LINE in out and NONE_LINE in out and HEADLESS_COMMANDS[0] in out
    assert "nothing was written" in out


def test_that_a_missing_final_newline_does_not_glue_our_line_to_the_users(tmp_path):
    sd = make_card(tmp_path, videomappings=USER_VIDEOMAPPINGS.rstrip("\n"))
    deploy(sd, make_module_folder(tmp_path / "src"))
    lines = read(sd, "config/videomappings.cfg").splitlines()
    assert lines[:len(USER_VIDEOMAPPINGS.splitlines())] == USER_VIDEOMAPPINGS.splitlines()
    assert USB_LINE in lines and NONE_LINE in lines


def test_that_a_taken_usb_mode_moves_our_usb_rate_down_and_says_so(tmp_path, capsys):
    other = "YUYV 352 288 15.0 YUYV 352 288 15.0 JeVois PassThrough\n"
    sd = make_card(tmp_path, videomappings=USER_VIDEOMAPPINGS + other)
    deploy(sd, make_module_folder(tmp_path / "src"))
    usb = [m for m in parse_mappings(read(sd, "config/videomappings.cfg")) if m.usb_format == "YUYV"
           and (m.usb_width, m.usb_height) == (352, 288)]
    assert sorted((m.module, m.usb_fps, m.cam_fps) for m in usb) == [
        ("ForaNavTrees", 14.0, 15.0), ("PassThrough", 15.0, 15.0)]
    assert "14.0 fps" in capsys.readouterr().out


def _not_a_jevois_partition(root, kind):
    if kind == "missing":
        return root / "missing"
    if kind == "boot":  # the card's other FAT partition
        (root / "BOOT").mkdir()
        (root / "BOOT" / "uImage").write_bytes(b"kernel")
        return root / "BOOT"
    (root / "empty" / "config").mkdir(parents=True)  # config/ but no modules/
    return root / "empty"


@pytest.mark.parametrize("kind", ["missing", "boot", "no_modules"])
def test_that_a_path_that_is_not_a_jevois_partition_is_refused_with_one_line(tmp_path, capsys, kind):
    module_dir = make_module_folder(tmp_path / "src")
    sd = _not_a_jevois_partition(tmp_path, kind)
    before = tree_digest(tmp_path)
    assert deploy(sd, module_dir) == BAD_INPUT_EXIT
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--sd" in err
    assert tree_digest(tmp_path) == before


@pytest.mark.parametrize("breakage,expected", [
    ("walrus", "not valid Python 3.7"),
    ("no_model", "foranav_oil_palm.npz"),
    ("lfs_pointer", "not a .npz"),
    ("no_class", "no top-level class"),
])
def test_that_a_module_that_would_not_load_on_the_camera_is_refused_before_writing(tmp_path, capsys, breakage,
                                                                                   expected):
    sd = make_card(tmp_path)
    module_dir = make_module_folder(tmp_path / "src", model=breakage != "no_model")
    if breakage == "walrus":
        (module_dir / "foranav_helper.py").write_text("def line():\n    if (n := 1):\n        return n\n")
    elif breakage == "lfs_pointer":
        (module_dir / "foranav_oil_palm.npz").write_text("version https://git-lfs.github.com/spec/v1\n")
    elif breakage == "no_class":
        source = (module_dir / "ForaNavTrees.py").read_text()
        (module_dir / "ForaNavTrees.py").write_text(source.replace("class ForaNavTrees", "class Trees"))
    before = tree_digest(sd)
    assert deploy(sd, module_dir) == BAD_INPUT_EXIT
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and expected in err
    assert tree_digest(sd) == before


def test_that_a_species_model_named_in_the_code_but_missing_is_reported_not_refused(tmp_path, capsys):
    # The module runs on its default model; only selecting that species on the camera would fail.
    sd = make_card(tmp_path)
    module_dir = make_module_folder(tmp_path / "src")
    (module_dir / "foranav_helper.py").write_text(HELPER_SOURCE + 'CITRUS = "foranav_citrus.npz"\n')
    assert deploy(sd, module_dir) == 0
    assert "foranav_citrus.npz" in capsys.readouterr().out


@pytest.mark.parametrize("option", [["--mode", "400x300@15"], ["--mode", "352x288@61"], ["--mode", "fast"],
                                    ["--vendor", "foranav"], ["--vendor", "Fora/Nav"]])
def test_that_a_bad_mode_or_vendor_is_refused(card_and_module, capsys, option):
    sd, module_dir = card_and_module
    before = tree_digest(sd)
    assert deploy(sd, module_dir, *option) == BAD_INPUT_EXIT
    assert option[1] in capsys.readouterr().err
    assert tree_digest(sd) == before


def test_that_headless_appends_the_boot_commands_after_the_users_lines(card_and_module):
    sd, module_dir = card_and_module
    assert deploy(sd, module_dir, "--headless") == 0
    text = read(sd, "config/initscript.cfg")
    assert text.startswith(USER_INITSCRIPT)
    commands = [line for line in text.splitlines() if line.strip() and not line.startswith("#")]
    assert commands == HEADLESS_COMMANDS
    assert read(sd, "config/initscript.cfg.foranav-bak-1") == USER_INITSCRIPT


def test_that_headless_creates_a_missing_initscript(tmp_path):
    sd = make_card(tmp_path, initscript=None)
    deploy(sd, make_module_folder(tmp_path / "src"), "--headless")
    commands = [line for line in read(sd, "config/initscript.cfg").splitlines() if not line.startswith("#")]
    assert commands == HEADLESS_COMMANDS


def test_that_headless_disables_another_modules_boot_mapping_but_keeps_its_text(tmp_path, capsys):
    user = "setpar camturbo true\nsetmapping2 YUYV 320 240 30.0 JeVois DemoArUco\nstreamon\nsetpar serlog USB\n"
    sd = make_card(tmp_path, initscript=user)
    deploy(sd, make_module_folder(tmp_path / "src"), "--headless")
    lines = read(sd, "config/initscript.cfg").splitlines()
    assert lines[0] == "setpar camturbo true"
    assert lines[1].endswith("setmapping2 YUYV 320 240 30.0 JeVois DemoArUco") and lines[1].startswith("#")
    assert lines[2].startswith("#") and lines[2].endswith("streamon")
    assert lines[3] == "setpar serlog USB"
    assert [line for line in lines if not line.startswith("#")][-4:] == HEADLESS_COMMANDS
    assert "DemoArUco" in capsys.readouterr().out


def test_that_a_new_mode_adds_its_mappings_keeps_the_old_ones_and_moves_the_boot_mapping(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir, "--headless")
    deploy(sd, module_dir, "--headless", "--mode", "352x288@8.5")
    lines = read(sd, "config/videomappings.cfg").splitlines()
    assert USB_LINE in lines and NONE_LINE in lines
    assert "NONE 0 0 0.0 YUYV 352 288 8.5 ForaNav ForaNavTrees" in lines
    commands = [line for line in read(sd, "config/initscript.cfg").splitlines() if not line.startswith("#")]
    assert commands == ["setmapping2 YUYV 352 288 8.5 ForaNav ForaNavTrees"] + HEADLESS_COMMANDS[1:]
    assert (sd / "config" / "videomappings.cfg.foranav-bak-2").is_file()


def test_that_an_updated_module_file_is_backed_up_before_it_is_replaced(card_and_module):
    sd, module_dir = card_and_module
    deploy(sd, module_dir)
    old = (sd / MODULE / "foranav_helper.py").read_bytes()
    (module_dir / "foranav_helper.py").write_text(HELPER_SOURCE.replace('"MARK STOP"', '"MARK STOP "'))
    deploy(sd, module_dir)
    assert (sd / MODULE / "foranav_helper.py.foranav-bak-1").read_bytes() == old
    assert (sd / MODULE / "foranav_helper.py").read_bytes() == (module_dir / "foranav_helper.py").read_bytes()


def test_that_the_real_module_folder_deploys(tmp_path):
    folder = module_files.default_module_folder()
    if not (folder / module_files.DEFAULT_MODEL).is_file():
        pytest.skip("the default model %s is not trained yet" % module_files.DEFAULT_MODEL)
    sd = make_card(tmp_path)
    assert cli.main(["deploy", "--sd", str(sd), "--headless"]) == 0
    installed = {p.name for p in (sd / MODULE).iterdir()}
    assert {"ForaNavTrees.py", module_files.DEFAULT_MODEL, "script.cfg", "params.cfg"} <= installed
    assert "__init__.py" not in installed


def test_that_a_fast_mode_caps_the_trees_per_frame_to_what_the_serial_port_carries(tmp_path, capsys):
    # Fixture: a module reporting up to 8 trees per frame, deployed at 120 fps (5 lines per frame at 115200 baud).
    sd = make_card(tmp_path)
    module_dir = make_module_folder(tmp_path / "src")
    source = (module_dir / "ForaNavTrees.py").read_text()
    (module_dir / "ForaNavTrees.py").write_text(source.replace(
        '"window step", foranav_helper.STEP)', '"window step", foranav_helper.STEP)\n'
        '        self.add(pc, "maxtrees", "int", "trees per frame", 8)'))
    # Test
    assert deploy(sd, module_dir, "--mode", "176x144@120") == 0
    # Assert
    active = [line for line in read(sd, MODULE + "/params.cfg").splitlines() if not line.startswith("#")]
    limit = [line for line in read(sd, MODULE + "/script.cfg").splitlines() if line.startswith("setpar serlimit")]
    assert active == ["maxtrees=4"] and limit == ["setpar serlimit 5"]
    assert "maxtrees=4" in capsys.readouterr().out
    # At 15 fps 8 trees fit: nothing is forced.
    deploy(sd, module_dir)
    assert [line for line in read(sd, MODULE + "/params.cfg").splitlines() if not line.startswith("#")] == []


LOAD_FROM_CARD = r"""
import sys
import numpy as np
from host_tools.jevois_host import ModuleRunner
folder = sys.argv[1]
# What the camera does at load: params.cfg's active name=value lines, after init().
params = dict(line.strip().split("=", 1) for line in open(folder + "/params.cfg")
              if line.strip() and not line.startswith("#"))
runner = ModuleRunner(module_dir=folder, params=params)
import ForaNavTrees
print(ForaNavTrees.__file__)
print(runner.process_frame(np.zeros((288, 352, 3), np.uint8))[-1])
"""
LOAD_TIMEOUT_S = 120


def test_that_the_deployed_real_module_loads_from_the_card_folder_alone(tmp_path):
    # The card's folder must be self-contained: sibling imports by plain name, the model found next to the code.
    folder = module_files.default_module_folder()
    if not (folder / module_files.DEFAULT_MODEL).is_file():
        pytest.skip("the default model %s is not trained yet" % module_files.DEFAULT_MODEL)
    if not hasattr(pytest.importorskip("host_tools.jevois_host"), "ModuleRunner"):
        pytest.skip("the libjevois host stand-in has no ModuleRunner")
    sd = make_card(tmp_path)
    assert cli.main(["deploy", "--sd", str(sd)]) == 0
    card_folder = str(sd / MODULE)
    result = subprocess.run([sys.executable, "-c", LOAD_FROM_CARD, card_folder], capture_output=True, text=True,
                            timeout=LOAD_TIMEOUT_S, cwd=str(tmp_path))
    assert result.returncode == 0, result.stderr[-2000:]
    loaded_from, last_line = result.stdout.split("\n")[:2]
    assert loaded_from.startswith(card_folder)
    assert last_line == "MARK STOP"


def test_that_rewritten_files_keep_their_permissions_and_new_ones_are_world_readable(card_and_module):
    sd, module_dir = card_and_module
    (sd / "config" / "videomappings.cfg").chmod(0o664)
    deploy(sd, module_dir)
    assert (sd / "config" / "videomappings.cfg").stat().st_mode & 0o777 == 0o664
    assert (sd / MODULE / "ForaNavTrees.py").stat().st_mode & 0o777 == 0o644


def test_that_the_fake_card_reads_like_a_jevois_partition(tmp_path):
    # Fixture
    sd = make_card(tmp_path)
    # Test
    state = card.read_card(sd, "ForaNav", "ForaNavTrees")
    # Assert
    assert set(state.files) == {card.VIDEOMAPPINGS, card.INITSCRIPT}
    assert "config/params.cfg" in state.names
    assert [m.module for m in parse_mappings(USER_VIDEOMAPPINGS)] == [
        "DNN", "SaveVideo", "SaveVideo", "JeVoisIntro", "JeVoisIntro"]
