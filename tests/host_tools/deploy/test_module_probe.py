"""Deploy reads the camera module's parameters by loading the module through the libjevois stand-in (names,
types, the values after init(), the module's own checks), not by reading its source."""
import pytest

from host_tools import cli
from host_tools.deploy import module_files
from host_tools.deploy.modes import parse_mode
from host_tools.deploy.module_probe import probe_module
from host_tools.errors import ForaNavError

from .conftest import BAD_INPUT_EXIT, MODULE, MODULE_SOURCE, make_card, make_module_folder, tree_digest

def patched(source, old, new):
    assert old in source
    return source.replace(old, new)


# Parameters made in a loop from a table of a helper, with defaults computed at load: no pattern in the source
# names them.
TABLE_HELPER = '''STEP = 8
SETTINGS = [(name, "int", "pass %d" % i, 10 * i) for i, name in enumerate(["gaina", "gainb"], 1)]


def line():
    return "MARK STOP"
'''
TABLE_SOURCE = patched(
    MODULE_SOURCE,
    '        self.add(pc, "step", "int", "window step", foranav_helper.STEP)\n',
    '        self.add(pc, "step", "int", "window step", foranav_helper.STEP)\n'
    '        for name, kind, description, default in foranav_helper.SETTINGS:\n'
    '            self.add(pc, name, kind, description, default)\n')


def module_payload_files(folder):
    files = module_files.read_module_folder(folder)
    return {name: data for name, data in files.items() if module_files.is_deployed_file(name)}


def test_that_parameters_made_at_run_time_are_listed_with_their_values(tmp_path):
    sd = make_card(tmp_path)
    module_dir = make_module_folder(tmp_path / "src", source=TABLE_SOURCE)
    (module_dir / "foranav_helper.py").write_text(TABLE_HELPER)
    assert cli.main(["deploy", "--sd", str(sd), "--module-dir", str(module_dir)]) == 0
    lines = (sd / MODULE / "params.cfg").read_text().splitlines()
    assert "#gaina=10" in lines and "#gainb=20" in lines
    assert "# gainb (int): pass 2" in lines


def test_that_a_module_whose_init_fails_is_refused_with_one_line_before_writing(tmp_path, capsys):
    sd = make_card(tmp_path)
    module_dir = make_module_folder(tmp_path / "src", source=patched(
        MODULE_SOURCE, "        self.model = None\n", "        self.model = None\n        self.broken = 1 / 0\n"))
    before = tree_digest(sd)
    assert cli.main(["deploy", "--sd", str(sd), "--module-dir", str(module_dir)]) == BAD_INPUT_EXIT
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ForaNavTrees.py" in err[0] and "ZeroDivisionError" in err[0]
    assert tree_digest(sd) == before


def test_that_two_module_folders_probed_in_a_row_each_report_their_own_parameters(tmp_path):
    first = make_module_folder(tmp_path / "a")
    second = make_module_folder(tmp_path / "b", source=patched(MODULE_SOURCE, '"svmthresh"', '"scorethresh"'))
    names = [[p.name for p in probe_module(module_payload_files(folder), "ForaNavTrees").parameters]
             for folder in (first, second, first)]
    assert names[0] == names[2] and "svmthresh" in names[0]
    assert "scorethresh" in names[1] and "svmthresh" not in names[1]


def test_that_the_probe_reports_the_values_the_module_refuses(tmp_path):
    folder = make_module_folder(tmp_path / "src")
    probe = probe_module(module_payload_files(folder), "ForaNavTrees", [("step", "abc"), ("step", "4")])
    assert ("step", "abc") in probe.refusals and ("step", "4") not in probe.refusals
    assert probe.parameter("step").default == 8 and probe.parameter("framemark").default is True


def test_that_a_module_that_prints_while_loading_still_probes(tmp_path):
    folder = make_module_folder(tmp_path / "src", source=patched(
        MODULE_SOURCE, "    def init(self):\n", "    def init(self):\n        print('hello from init')\n"))
    assert probe_module(module_payload_files(folder), "ForaNavTrees").parameter("svmthresh").default == 0.5


def test_that_the_real_modules_params_cfg_lists_every_parameter_at_its_loaded_value(tmp_path):
    folder = module_files.default_module_folder()
    if not (folder / module_files.DEFAULT_MODEL).is_file():
        pytest.skip("the default model %s is not trained yet" % module_files.DEFAULT_MODEL)
    jevois_host = pytest.importorskip("host_tools.jevois_host")
    runner = jevois_host.ModuleRunner(module_dir=str(folder))
    sd = make_card(tmp_path)
    assert cli.main(["deploy", "--sd", str(sd)]) == 0
    lines = (sd / MODULE / "params.cfg").read_text().splitlines()
    loaded = jevois_host.libjevois.parameters(runner.instance)
    assert loaded
    for name in loaded:
        value = runner.getpar(name)
        text = ("true" if value else "false") if isinstance(value, bool) else str(value)
        assert "#%s=%s" % (name, text) in lines


def test_that_a_module_folders_own_params_cfg_naming_no_parameter_is_refused(tmp_path):
    folder = make_module_folder(tmp_path / "src")
    (folder / "params.cfg").write_text("nosuchpar=1\n")
    with pytest.raises(ForaNavError, match="no parameter nosuchpar"):
        module_files.build_module_payload(module_files.read_module_folder(folder), "ForaNav",
                                          parse_mode("352x288@15"))
