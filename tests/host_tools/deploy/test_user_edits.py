"""A redeploy keeps what the user edited on the card: params.cfg values (checked by the module itself) and
script.cfg commands; ForaNav's own lines are recomputed; refused and obsolete settings are handled visibly."""
import pytest

from .conftest import BAD_INPUT_EXIT, MODULE, MODULE_SOURCE, deploy, make_card, make_module_folder, tree_digest

PARAMS = MODULE + "/params.cfg"
SCRIPT = MODULE + "/script.cfg"
# A module whose step parameter refuses values outside 1..24 through a JeVois parameter callback.
STEP_LINE = '        self.add(pc, "step", "int", "window step", foranav_helper.STEP)\n'
assert STEP_LINE in MODULE_SOURCE
CHECKED_SOURCE = MODULE_SOURCE.replace(STEP_LINE, STEP_LINE + '        self.step.setCallback(check_step)\n') + '''

def check_step(value):
    if not 1 <= value <= 24:
        raise ValueError("step out of range (1 to 24)")
'''


def active_lines(path):
    return [line for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]


def edit(path, old, new):
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))


@pytest.fixture
def deployed(tmp_path):
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src", source=CHECKED_SOURCE)
    assert deploy(sd, module_dir) == 0
    return sd, module_dir


def test_that_a_redeploy_keeps_the_users_params_cfg_values_and_says_so(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#svmthresh=0.5", "svmthresh=0.25")
    edit(sd / PARAMS, "#framemark=true", "framemark=false")
    capsys.readouterr()
    assert deploy(sd, module_dir) == 0
    assert active_lines(sd / PARAMS) == ["svmthresh=0.25", "framemark=false"]
    out = capsys.readouterr().out
    assert "kept your svmthresh=0.25" in out and "kept your framemark=false" in out


def test_that_a_redeploy_keeps_the_users_script_cfg_commands(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / SCRIPT, "setpar serlog None", "setpar serlog USB")
    edit(sd / SCRIPT, "#setcam autoexp 1", "setcam autoexp 1")
    (sd / SCRIPT).write_text((sd / SCRIPT).read_text() + "setcam absexp 120\ninfo\n")
    assert deploy(sd, module_dir) == 0
    commands = active_lines(sd / SCRIPT)
    assert "setpar serlog USB" in commands and "setpar serlog None" not in commands
    assert "setcam autoexp 1" in commands and "setcam absexp 120" in commands and "info" in commands
    assert "setpar serout Hard" in commands
    assert "kept your 'setpar serlog USB'" in capsys.readouterr().out


def test_that_a_new_parameter_of_the_new_release_is_added_and_reported(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#svmthresh=0.5", "svmthresh=0.25")
    edit(module_dir / "ForaNavTrees.py", '        self.add(pc, "hsthresh"',
         '        self.add(pc, "minarea", "int", "smallest crown in px", 40)\n        self.add(pc, "hsthresh"')
    capsys.readouterr()
    assert deploy(sd, module_dir) == 0
    text = (sd / PARAMS).read_text()
    assert "#minarea=40" in text.splitlines() and "svmthresh=0.25" in text.splitlines()
    assert "new in this module release: minarea" in capsys.readouterr().out


def test_that_foranavs_lines_are_recomputed_when_the_mode_changes_but_user_lines_are_not(deployed):
    sd, module_dir = deployed
    edit(sd / SCRIPT, "#setcam absexp 200", "setcam absexp 150")
    assert deploy(sd, module_dir, "--mode", "352x288@60") == 0
    commands = active_lines(sd / SCRIPT)
    assert "setpar serlimit 10" in commands and "setpar serlimit 40" not in commands
    assert "setcam absexp 150" in commands


def test_that_a_deploy_after_a_merge_changes_nothing(deployed):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#step=8", "step=4")
    edit(sd / SCRIPT, "setpar serlog None", "setpar serlog USB")
    assert deploy(sd, module_dir) == 0
    before = tree_digest(sd)
    assert deploy(sd, module_dir) == 0
    assert tree_digest(sd) == before


def test_that_a_value_the_module_refuses_stops_the_deploy_with_one_line_naming_the_file(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#step=8", "step=99")
    before = tree_digest(sd)
    capsys.readouterr()
    assert deploy(sd, module_dir) == BAD_INPUT_EXIT
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "params.cfg line" in err[0] and "step=99" in err[0] and "out of range" in err[0]
    assert tree_digest(sd) == before


def test_that_force_comments_out_a_refused_value_and_keeps_the_rest(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#step=8", "step=abc")
    edit(sd / PARAMS, "#svmthresh=0.5", "svmthresh=0.25")
    assert deploy(sd, module_dir, "--force") == 0
    lines = (sd / PARAMS).read_text().splitlines()
    assert active_lines(sd / PARAMS) == ["svmthresh=0.25"]
    assert "#foranav-refused# step=abc" in lines and "#step=8" in lines
    assert (sd / (PARAMS + ".foranav-bak-1")).read_text().count("step=abc") == 1  # the user's file, backed up


def test_that_a_parameter_the_new_release_dropped_is_kept_as_a_comment(deployed, capsys):
    sd, module_dir = deployed
    (sd / PARAMS).write_text((sd / PARAMS).read_text() + "oldgain=3\n")
    capsys.readouterr()
    assert deploy(sd, module_dir) == 0
    assert "oldgain=3" not in active_lines(sd / PARAMS)  # the camera refuses an unknown parameter
    assert "#foranav-obsolete# oldgain=3" in (sd / PARAMS).read_text().splitlines()
    assert "no parameter oldgain" in capsys.readouterr().out


def test_that_a_params_cfg_written_before_the_markers_is_read_as_foranavs(tmp_path):
    # Fixture: the card as the previous deploy left it at 120 fps (maxtrees forced, no `ForaNav sets:` marker).
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src")
    (sd / MODULE).mkdir(parents=True)
    (sd / PARAMS).write_text("# ForaNav/ForaNavTrees params.cfg, generated by ForaNav: name=value lines ...\n"
                             "# Set by ForaNav for this camera mode: at 120.0 fps the serial port carries 5 ...\n"
                             "maxtrees=4\n#svmthresh=0.5\n")
    (sd / SCRIPT).write_text("# ForaNav/ForaNavTrees script.cfg, generated by ForaNav for 176x144@120.0: ...\n"
                             "setpar serout Hard\nsetpar serlog None\n"
                             "# At most this many serial lines per frame: what 115200 baud carries at 120.0 ...\n"
                             "setpar serlimit 5\n")
    # Test
    assert deploy(sd, module_dir) == 0
    # Assert: recomputed for 15 fps, nothing kept as the user's
    assert active_lines(sd / PARAMS) == []
    assert active_lines(sd / SCRIPT) == ["setpar serout Hard", "setpar serlog None", "setpar serlimit 40"]


def test_that_a_redeploy_keeps_the_users_comment_lines_above_what_they_describe(deployed, capsys):
    sd, module_dir = deployed
    edit(sd / PARAMS, "#svmthresh=0.5", "# lower threshold: the canopy is dark here\nsvmthresh=0.25")
    edit(sd / PARAMS, "#step=8", "# step: try 4 if trees are missed\n#step=8")
    (sd / PARAMS).write_text((sd / PARAMS).read_text() + "# card of drone 3, 2026-11\n")
    edit(sd / SCRIPT, "setpar serlog None", "# logs on USB while testing\nsetpar serlog USB")
    (sd / SCRIPT).write_text((sd / SCRIPT).read_text() + "# show the module's info at start\ninfo\n")
    assert deploy(sd, module_dir, "--mode", "352x288@30") == 0
    params = (sd / PARAMS).read_text().splitlines()
    assert params.index("# lower threshold: the canopy is dark here") < params.index("svmthresh=0.25")
    assert params.index("# step: try 4 if trees are missed") < params.index("#step=8")
    assert params[-2:] == ["# Your comments, kept by foranav deploy:", "# card of drone 3, 2026-11"]
    script = (sd / SCRIPT).read_text().splitlines()
    assert script.index("# logs on USB while testing") < script.index("setpar serlog USB")
    assert script.index("# show the module's info at start") == script.index("info") - 1
    # Each comment once, and a further deploy changes nothing.
    assert params.count("# lower threshold: the canopy is dark here") == 1
    before = tree_digest(sd)
    assert deploy(sd, module_dir, "--mode", "352x288@30") == 0
    assert tree_digest(sd) == before


def test_that_foranavs_own_comments_are_not_taken_for_the_users(deployed):
    sd, module_dir = deployed
    fresh = (sd / PARAMS).read_text()
    assert deploy(sd, module_dir, "--mode", "352x288@60") == 0
    assert "# Your comments" not in (sd / PARAMS).read_text() + (sd / SCRIPT).read_text()
    assert (sd / PARAMS).read_text().count("\n") == fresh.count("\n")


def test_that_the_reason_foranav_gave_for_another_mode_is_not_kept_as_a_users_comment(tmp_path):
    # A module reporting up to 8 trees: at 120 fps ForaNav caps maxtrees and says why; back at 15 fps it does not.
    sd, module_dir = make_card(tmp_path), make_module_folder(tmp_path / "src")
    source = (module_dir / "ForaNavTrees.py").read_text()
    (module_dir / "ForaNavTrees.py").write_text(source.replace(
        '"window step", foranav_helper.STEP)', '"window step", foranav_helper.STEP)\n'
        '        self.add(pc, "maxtrees", "int", "trees per frame", 8)'))
    assert deploy(sd, module_dir, "--mode", "176x144@120") == 0
    assert "fps the serial port carries" in (sd / PARAMS).read_text()
    assert deploy(sd, module_dir) == 0
    text = (sd / PARAMS).read_text()
    assert "fps the serial port carries" not in text and "# Your comments" not in text
