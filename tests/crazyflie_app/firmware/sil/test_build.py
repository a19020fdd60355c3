"""make firmware-sil: what is missing is named in one line, with how to get it; nothing half-built stays."""
import tarfile

from crazyflie_app.firmware.sil import build


def test_that_a_missing_firmware_is_named_with_how_to_get_it(tmp_path, capsys):
    # Test
    code = build.main(["--firmware", str(tmp_path / "crazyflie-firmware.tar.gz")])
    # Assert
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "crazyflie-firmware.tar.gz" in err[0] and "git clone https://github.com/bitcraze/crazyflie-firmware" in err[0]


def test_that_a_tarball_without_the_firmware_is_refused(tmp_path, capsys, monkeypatch):
    # Fixture: a real tarball of something else; the build folder is a scratch one
    monkeypatch.setattr(build, "BUILD_DIR", tmp_path / "build")
    monkeypatch.setattr(build, "LIBRARY", tmp_path / "build" / "libforanav_sil.so")
    monkeypatch.setattr(build, "STAMP", tmp_path / "build" / "stamp.txt")
    (tmp_path / "notes.txt").write_text("not a firmware")
    with tarfile.open(tmp_path / "other.tar.gz", "w:gz") as archive:
        archive.add(tmp_path / "notes.txt", arcname="other/notes.txt")
    # Test
    code = build.main(["--firmware", str(tmp_path / "other.tar.gz")])
    # Assert
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "no crazyflie-firmware source tree inside" in err[0]
    assert not (tmp_path / "build" / "libforanav_sil.so").exists()


def test_that_setup_goes_on_without_a_firmware_source(tmp_path, capsys, monkeypatch):
    # Fixture: no FORANAV_FIRMWARE, an empty vendor folder
    monkeypatch.delenv("FORANAV_FIRMWARE", raising=False)
    monkeypatch.setattr(build, "DEFAULT_VENDOR", tmp_path)
    # Test
    code = build.main(["--if-available"])
    # Assert: make setup must work for a user without the firmware; it says what it skipped
    assert code == 0
    assert "firmware plant: not built" in capsys.readouterr().out
