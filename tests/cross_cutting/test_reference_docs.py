"""docs/reference/*.md are generated from the code (python -m host_tools.docs_gen, make docs) and kept current."""
import subprocess
import sys

from crazyflie_app.app import navigation
from host_tools import cli, docs_gen
from host_tools.jevois_host import libjevois, load_module

REPO_ROOT = docs_gen.REPO_ROOT
GENERATOR_TIMEOUT_S = 120


def test_that_the_committed_reference_tables_are_current():
    stale = docs_gen.stale_files()
    assert stale == [], "stale docs/reference/%s: run make docs (python -m host_tools.docs_gen)" % ", ".join(stale)


def test_that_the_readme_command_table_is_generated_and_current():
    text = docs_gen.README.read_text(encoding="utf-8")
    assert docs_gen.README_BEGIN in text and docs_gen.README_END in text
    assert not docs_gen.readme_is_stale(), "stale README.md command table: run make docs"
    for name in cli.COMMANDS:
        assert "| `foranav %s` |" % name in text


def test_that_the_design_picture_is_what_the_code_draws():
    text = docs_gen.DESIGN.read_text(encoding="utf-8")
    assert docs_gen.PICTURE_BEGIN in text and "NavigationCore.step" in text
    assert not docs_gen.design_is_stale(), "stale docs/DESIGN.md picture: run make docs"


def test_that_the_readme_demo_output_is_what_the_demo_prints():
    # Fixture: the README as committed
    text = docs_gen.README.read_text(encoding="utf-8")
    # Test: the demo's own flight, formatted as foranav demo prints it
    block = docs_gen.demo_output()
    # Assert: the committed copy is that output, and an edited copy counts as stale
    assert block in text, "stale README.md demo output: run make docs"
    edited = text.replace(block, block.replace("SUCCESS", "NOT COMPLETED"))
    assert docs_gen.readme_with_table(edited) == text


def test_that_every_command_and_option_is_in_the_command_table():
    text = docs_gen.commands_markdown()
    for name, (module_name, help_text) in cli.COMMANDS.items():
        assert "## foranav %s\n" % name in text and help_text in text
        parser, _doc = docs_gen.command_parser(name, module_name)
        for option in parser._option_string_actions:
            if option not in ("-h", "--help"):
                assert "`%s`" % option in text, "foranav %s %s missing" % (name, option)


def test_that_every_app_param_is_listed_with_its_default():
    text = docs_gen.params_markdown()
    defaults = navigation.NavigationParams()
    for entry in navigation.PARAM_TABLE.entries:
        assert "| `app.%s` | %s | %s |" % (entry.name, entry.type, getattr(defaults, entry.attribute)) in text


def test_that_every_camera_parameter_is_listed_as_the_module_creates_it():
    text = docs_gen.camera_params_markdown()
    instance, _standin = load_module()
    for name, parameter in libjevois.parameters(instance).items():
        assert "| `%s` | %s | %s |" % (name, parameter.type_str, parameter.get()) in text


def test_that_a_new_command_makes_the_committed_copy_stale(monkeypatch, tmp_path):
    for name, text in docs_gen.render_all().items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    assert docs_gen.stale_files(tmp_path) == []
    monkeypatch.setitem(cli.COMMANDS, "frobnicate", (cli.COMMANDS["render"][0], "a command added after the docs"))
    assert docs_gen.stale_files(tmp_path) == ["commands.md"]


def test_that_the_generator_writes_the_files_and_check_then_passes(tmp_path):
    def run(*args):
        return subprocess.run([sys.executable, "-m", "host_tools.docs_gen", "--out", str(tmp_path), *args],
                              capture_output=True, text=True, timeout=GENERATOR_TIMEOUT_S, cwd=str(REPO_ROOT))

    assert run("--check").returncode == 1
    assert run().returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["camera-params.md", "commands.md", "firmware-plant.md",
                                                          "params.md"]
    assert run("--check").returncode == 0
