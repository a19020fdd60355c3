"""No state left behind between flights in one process: the same vision flight, flown again after another one,
gives the same bytes (a sweep worker flies thousands in a row with one libjevois stand-in)."""
import json

from host_tools import cli

# two trees on one straight leg: a vision flight of ~26 simulated seconds, about a second of CPU
MINI_MAP = {"name": "mini", "altitude_m": 1.25, "waypoints": [[0.3, 0.0], [1.5, 0.0]], "seed": 7,
            "trees": [{"id": 1, "x": 0.8, "y": 0.0, "species": "oil_palm", "crown_m": 0.38},
                      {"id": 2, "x": 1.3, "y": 0.02, "species": "oil_palm", "crown_m": 0.36}]}
OUTPUT_PATH_KEYS = ("tlog", "plot", "summary", "detections_csv")


def fly(map_path, out_dir, *options):
    assert cli.main(["fly", "--map", str(map_path), "--camera", "sim", "--out", str(out_dir), *options]) == 0
    summary = json.loads((out_dir / "summary.json").read_text())
    for key in OUTPUT_PATH_KEYS:  # where the files went, not what the flight did
        summary.pop(key, None)
    return summary, (out_dir / "flight.tlog").read_bytes(), (out_dir / "detections.csv").read_bytes()


def test_that_a_vision_flight_gives_the_same_bytes_after_another_flight_in_the_same_process(tmp_path, capsys):
    # Fixture
    map_path = tmp_path / "mini.json"
    map_path.write_text(json.dumps(MINI_MAP))
    # Test: fly, fly something else (other seed, frame rate and latency), fly the first one again
    first = fly(map_path, tmp_path / "first")
    other = fly(map_path, tmp_path / "other", "--seed", "5", "--fps", "6", "--latency-ms", "200")
    again = fly(map_path, tmp_path / "again")
    capsys.readouterr()
    # Assert
    assert first[0]["success"] and len(first[0]["reached"]) == 2
    assert other[1] != first[1]
    assert again == first
