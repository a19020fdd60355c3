"""The tlog as ground stations read it (issue 45), checked with pymavlink's own tools run as programs: one id per
STATUSTEXT line, a global track (GLOBAL_POSITION_INT, GPS_RAW_INT) from the geo-reference, the phase by name."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

from crazyflie_app.app.nav_types import PHASE_NAMES
from host_tools import cli
from host_tools.flight.telemetry import COPTER_MODES, DEFAULT_GEO, GeoReference

TOOLS = Path(sys.executable).parent


def _tool(name, *args, cwd=None):
    script = TOOLS / name
    if not script.exists():
        pytest.skip("%s not installed next to the interpreter" % name)
    out = subprocess.run([sys.executable, str(script)] + [str(a) for a in args], capture_output=True, text=True,
                         timeout=120, cwd=cwd)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.fixture(scope="module")
def tlog(tmp_path_factory):
    out = tmp_path_factory.mktemp("flight")
    assert cli.main(["fly", "--map", "map1", "--camera", "oracle", "--out", str(out), "--json"]) == 0
    return out / "flight.tlog"


def test_that_every_statustext_line_has_its_own_id(tlog):
    dump = _tool("mavlogdump.py", "--types", "STATUSTEXT", tlog)
    records = re.findall(r"text : (.*?), id : (\d+), chunk_seq : (\d+)}", dump)
    first_chunks = [int(i) for _text, i, seq in records if seq == "0"]
    assert len(first_chunks) > 10 and 0 not in first_chunks
    assert len(set(first_chunks)) == len(first_chunks)  # boot line and tree_reached events no longer merge
    continued = [(int(i), int(seq)) for _text, i, seq in records if seq != "0"]
    assert continued and all(i in first_chunks for i, _seq in continued)


def test_that_mavtogpx_writes_the_track_on_the_globe(tlog):
    _tool("mavtogpx.py", tlog.name, cwd=tlog.parent)
    gpx = (tlog.parent / (tlog.name + ".gpx")).read_text()
    points = [(float(a), float(b)) for a, b in re.findall(r'<trkpt lat="([-\d.]+)" lon="([-\d.]+)"', gpx)]
    assert len(points) > 100
    assert all(abs(lat - DEFAULT_GEO.lat_deg) < 1e-3 and abs(lon - DEFAULT_GEO.lon_deg) < 1e-3 for lat, lon in points)
    assert max(lat for lat, _ in points) - min(lat for lat, _ in points) > 2e-5  # the 3.6 m column, north


def test_that_mavflighttime_finds_the_time_in_air(tlog):
    # the MAV flies at 0.1 m/s: below mavflighttime's default 3 m/s threshold, hence --groundspeed
    text = _tool("mavflighttime.py", "--groundspeed", "0.05", tlog)
    minutes, seconds = re.search(r"Total time in air: (\d+):(\d+)", text).groups()
    assert 60 * int(minutes) + int(seconds) > 30
    assert float(re.search(r"Total distance travelled: ([\d.]+) meters", text).group(1)) > 5


def test_that_the_phases_show_by_name(tlog):
    text = _tool("mavflightmodes.py", tlog)
    for name in ("GUIDED", "AUTO", "LAND"):
        assert name in text
    assert "RTL" not in text


def test_that_every_phase_has_a_mode_and_the_geo_reference_turns_with_its_heading():
    assert set(COPTER_MODES) == set(PHASE_NAMES)
    east = GeoReference(0.0, 0.0, heading_deg=90.0).to_global(100.0, 0.0)
    assert east[0] == pytest.approx(0.0, abs=1e-9) and east[1] == pytest.approx(100.0 / 111195.0, rel=1e-3)
    north = GeoReference(0.0, 0.0, heading_deg=0.0).to_global(0.0, -100.0)  # map right = east
    assert north[1] > 0
