"""Bad input never gives a traceback (issue #11, docs/errors.md): a table of bad inputs across every command.

Each row runs `foranav <command> ...` in-process through host_tools.cli.main and checks: exit status 2; stderr
exactly one line, naming the option or file; no traceback; nothing written or left half-written where the
command writes (the scratch folder, holding pre-existing outputs, keeps every name and byte). A few rows run
a real subprocess; a broken stdout pipe (`foranav train ... | head`) must not stop the work.
"""
import copy
import json
import os
import random
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from host_tools import cli, fileio, images
from host_tools.annotations import read_boxes
from host_tools.errors import ForaNavError
from host_tools.maps import map_from_dict
from host_tools.sim.clip import clip_from_dict, read_clip
from tests.conftest import FIXTURES, MAP3_SHORT_SENSOR_CLIP

FIXTURE_CLIP = MAP3_SHORT_SENSOR_CLIP
OLD_BYTES = b"an output from an earlier run\n"
CSV_HEADER = "image,x_center,y_center,width,height,label\n"
FIELD_LIMIT = 128 * 1024  # csv.field_size_limit() default
DEEP = 100000  # nesting levels: far beyond the interpreter's recursion limit


def write_map(path, **changes):
    data = json.loads((Path(cli.__file__).parent / "data" / "maps" / "map1.json").read_text())
    data.update(changes)
    path.write_text(json.dumps(data))


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Bad input files, made once."""
    root = tmp_path_factory.mktemp("bad_inputs")
    (root / "latin1.json").write_bytes(json.dumps({"name": "x"}).encode()[:-1] + b', "note": "caf\xe9"}')
    (root / "deep.json").write_text("[" * DEEP + "]" * DEEP)
    (root / "truncated.json").write_text('{"name": "map", "altitude_m": 1.2')
    write_map(root / "nan_altitude.json", altitude_m=float("nan"))
    write_map(root / "no_trees_field.json", trees="none")
    write_map(root / "negative_seed.json", seed=-4)
    text = (Path(cli.__file__).parent / "data" / "maps" / "map1.json").read_text()
    (root / "big_int.json").write_text(text.replace('"altitude_m": 1.25', '"altitude_m": 1' + "0" * 400))
    (root / "huge_int.json").write_text(text.replace('"altitude_m": 1.25', '"altitude_m": 1' + "0" * 5000))
    (root / "folder.json").mkdir()
    sidecar = json.loads((FIXTURE_CLIP / "clip.json").read_text())
    sidecar["frames"][3]["t_s"] = sidecar["frames"][1]["t_s"]  # time running backwards
    (root / "backwards").mkdir()
    (root / "backwards" / "clip.json").write_text(json.dumps(sidecar))
    (root / "latin1_clip").mkdir()
    (root / "latin1_clip" / "clip.json").write_bytes(b'{"format": "foranav-clip", "name": "\xff"}')
    (root / "deep_clip").mkdir()
    (root / "deep_clip" / "clip.json").write_text('{"format": ' + "[" * DEEP + "]" * DEEP + "}")
    (root / "cut_video").mkdir()
    (root / "cut_video" / "clip.json").write_bytes((FIXTURE_CLIP / "clip.json").read_bytes())
    video = (FIXTURE_CLIP / "clip.avi").read_bytes()
    (root / "cut_video" / "clip.avi").write_bytes(video[:len(video) // 2])
    # issue 45: another map's video (map1's, same size, more frames) beside this clip's sidecar
    (root / "swapped_video").mkdir()
    (root / "swapped_video" / "clip.json").write_bytes((FIXTURE_CLIP / "clip.json").read_bytes())
    (root / "swapped_video" / "clip.avi").write_bytes((FIXTURES / "clips" / "map1_full" / "clip.avi").read_bytes())
    (root / "frames_not_list").mkdir()
    sidecar["frames"] = 7
    (root / "frames_not_list" / "clip.json").write_text(json.dumps(sidecar))
    # issue 32: a map far beyond any flight (simulator and app), boxes CSVs that must be named as what they are
    write_map(root / "altitude_1e6.json", altitude_m=1e6)
    write_map(root / "altitude_0p1.json", altitude_m=0.1)
    write_map(root / "path_900m.json", waypoints=[[0.0, 0.0], [900.0, 0.0]])
    write_map(root / "path_400m.json", waypoints=[[0.0, 0.0], [0.0, 400.0]], altitude_m=0.5)
    data = json.loads((Path(cli.__file__).parent / "data" / "maps" / "map1.json").read_text())
    data["trees"][0]["crown_m"] = 1e6
    (root / "crown_1e6.json").write_text(json.dumps(data))
    data["trees"][0]["crown_m"], data["trees"][1]["x"] = 0.4, 1e7
    (root / "tree_x_1e7.json").write_text(json.dumps(data))
    (root / "empty.png").write_bytes(b"")
    (root / "nul_rows.csv").write_bytes(CSV_HEADER.encode() + (b"\x00" * 40 + b"\n") * 3)
    (root / "nul_file.csv").write_bytes(b"\x00" * 300)
    (root / "huge_box.csv").write_text(CSV_HEADER + "a.png,100,100,1e300,1e300,oil_palm\n")
    (root / "duplicated_rows.csv").write_text(CSV_HEADER + "a.png,100,100,60,60,oil_palm\n" * 3)
    (root / "duplicated_crops.csv").write_text("image,class,category\n" + "pos/1.png,pos,oil_palm\n" * 2)
    (root / "big_field.csv").write_text(CSV_HEADER + "a.png,1,1,1,1," + "x" * (FIELD_LIMIT + 10) + "\n")
    # issue 45: sizes beyond what the program can do, files that hang a reader, clips the app cannot fly
    (root / "zero_box.csv").write_text(CSV_HEADER + "a.png,10,10,60,60,oil_palm\na.png,90,90,0,60,oil_palm\n")
    cv2.imwrite(str(root / "one_px.png"), np.zeros((1, 1, 3), np.uint8))
    (root / "one_px.csv").write_text(CSV_HEADER + "one_px.png,0,0,1,1,oil_palm\n")
    cv2.imwrite(str(root / "strip.png"), np.zeros((1, 100000, 3), np.uint8))
    write_map(root / "long_name.json", name="x" * 5 * 1024 * 1024)
    write_map(root / "many_trees.json", trees=[{"id": i, "x": 1.0 + i * 1e-5, "y": 0.0, "species": "oil_palm",
                                               "crown_m": 0.3} for i in range(1, 100001)])
    os.mkfifo(root / "fifo.json")
    for name, change in (("slow_clip", lambda d: d.update(fps=0.5)),
                         ("z0_clip", lambda d: d["frames"][2]["pose"].update(z=0)),
                         ("zneg_clip", lambda d: d["frames"][2]["pose"].update(z=-1.0)),
                         ("offset_nan_clip", lambda d: d["camera"].update(mount_offset=[float("nan"), 0.0]))):
        data = json.loads((FIXTURE_CLIP / "clip.json").read_text())
        change(data)
        (root / name).mkdir()
        (root / name / "clip.json").write_text(json.dumps(data))
    # a Latin-1 name far down a long CSV (past any reader's first buffer)
    rows = "".join("f%04d.png,10,10,5,5,oil_palm\n" % i for i in range(600))
    (root / "latin1.csv").write_bytes((CSV_HEADER + rows).encode() + b"caf\xe9.png,10,10,5,5,oil_palm\n")
    return root


def _make_read_only(folder):
    """chmod 555; root ignores that, so also the immutable flag where the filesystem has it. True if it holds."""
    folder.chmod(0o555)
    if fileio.writable_reason(folder) and os.geteuid() != 0:
        return True
    if shutil.which("chattr"):
        subprocess.run(["chattr", "+i", str(folder)], capture_output=True)
    return bool(fileio.writable_reason(folder))


def _release(folder):
    if shutil.which("chattr"):
        subprocess.run(["chattr", "-i", str(folder)], capture_output=True)
    folder.chmod(0o755)


@pytest.fixture(scope="module")
def scratch(tmp_path_factory):
    """The folder every row writes in (its working directory), with outputs of an earlier run."""
    root = tmp_path_factory.mktemp("scratch")
    for name in ("keep.png", "keep.npz", "keep.jvpkg", "afile"):
        (root / name).write_bytes(OLD_BYTES)
    (root / "existing_dir").mkdir()
    (root / "existing_dir" / "old.txt").write_bytes(OLD_BYTES)
    (root / "dir.jvpkg").mkdir()
    (root / "ro").mkdir()
    read_only = _make_read_only(root / "ro")
    yield root, read_only
    _release(root / "ro")


def snapshot(root):
    return {str(p.relative_to(root)): (p.read_bytes() if p.is_file() else None) for p in sorted(root.rglob("*"))}


MAP_ROWS = [  # map inputs, the same for every command that reads a map
    ("{in}/latin1.json", "latin1.json"), ("{in}/deep.json", "deep.json"), ("{in}/truncated.json", "truncated.json"),
    ("{in}/nan_altitude.json", "altitude_m"), ("{in}/no_trees_field.json", "trees"),
    ("{in}/folder.json", "folder.json"), ("no_such_map", "no_such_map"), ("{in}/negative_seed.json", "seed"),
    ("{in}/big_int.json", "altitude_m"), ("{in}/huge_int.json", "huge_int.json"),
    ("{in}/altitude_1e6.json", "altitude_1e6.json: altitude_m: must be from 0.4 to 4.5 m"),
    ("{in}/altitude_0p1.json", "altitude_m"), ("{in}/crown_1e6.json", "trees[0].crown_m: must be at most"),
    ("{in}/tree_x_1e7.json", "trees[1].x: must lie within")]
CSV_ROWS = [  # boxes CSVs, the same for every command that reads one (host_tools/annotations.py)
    ("{in}/nul_rows.csv", "nul_rows.csv: line 2: NUL bytes"), ("{in}/nul_file.csv", "nul_file.csv: line 1: NUL"),
    ("{in}/huge_box.csv", "huge_box.csv: line 2: width 1e+300 px is beyond any image"),
    ("{in}/duplicated_rows.csv", "duplicated_rows.csv: line 3: the same box of a.png as line 2")]
RENDER = ["render", "--map", "map1", "--x", "1", "--y", "0"]
RECORD = ["record", "--map", "map1"]
FLY = ["fly", "--map", "map1", "--camera", "oracle"]
CLIP = str(FIXTURE_CLIP)

# (argv, what the one line must name); "{in}" is the inputs folder; paths without it are in the scratch folder
CASES = [
    # render
    (RENDER[:4] + ["--x", "nan", "--y", "0", "--out", "keep.png"], "--x"),
    (RENDER[:4] + ["--x", "inf", "--y", "0", "--out", "keep.png"], "--x"),
    (RENDER + ["--yaw", "nan", "--out", "keep.png"], "--yaw"),
    (RENDER + ["--z", "0", "--out", "keep.png"], "--z"),
    (RENDER + ["--z", "-1", "--out", "keep.png"], "--z"),
    (RENDER + ["--z", "1e9", "--out", "keep.png"], "--z"),
    (RENDER + ["--seed", "-1", "--out", "keep.png"], "--seed"),
    (RENDER + ["--mount-offset", "nan", "0", "--out", "keep.png"], "--mount-offset"),
    (RENDER + ["--mount-offset", "0", "0", "--mount-offset", "0.1", "0", "--out", "keep.png"], "--mount-offset"),
    (RENDER + ["--width", "100", "--height", "100", "--out", "keep.png"], "--width"),
    (RENDER + ["--effects", "fog", "--out", "keep.png"], "--effects"),
    (RENDER + ["--out", "afile/x.png"], "--out"),
    (RENDER + ["--out", "no_dir/x.png"], "--out"),
    (RENDER + ["--out", "existing_dir"], "--out"),
    (RENDER + ["--out", "ro/x.png"], "--out"),
    (RENDER[:4] + ["--y", "0", "--out", "keep.png"], "--x"),
    (["render", "--map", "{in}/path_400m.json", "--x", "0", "--y", "1", "--out", "keep.png"],
     "path_400m.json: its ground"),
] + [(["render", "--map", path, "--x", "1", "--y", "0", "--out", "keep.png"], named) for path, named in MAP_ROWS] + [
    # record
    (RECORD + ["--out", "clip", "--fps", "1e9"], "--fps"),
    (RECORD + ["--out", "clip", "--fps", "0"], "--fps"),
    (RECORD + ["--out", "clip", "--fps", "nan"], "--fps"),
    (RECORD + ["--out", "clip", "--speed", "0"], "--speed"),
    (RECORD + ["--out", "clip", "--speed", "1e-9"], "--speed"),
    (RECORD + ["--out", "clip", "--seed", "-1"], "--seed"),
    (RECORD + ["--out", "clip", "--quality", "0"], "--quality"),
    (RECORD + ["--out", "clip", "--duration", "-1"], "--duration"),
    (RECORD + ["--out", "clip", "--start", "-1"], "--start"),
    (RECORD + ["--out", "clip", "--start", "1000"], "--start"),
    (RECORD + ["--out", "clip", "--z", "nan"], "--z"),
    (RECORD + ["--out", "clip", "--fps", "100", "--speed", "0.01", "--duration", "10000"], "--fps"),
    (["record", "--map", "{in}/altitude_1e6.json", "--out", "clip"], "altitude_m"),
    (["record", "--map", "{in}/path_400m.json", "--out", "clip"], "path_400m.json: its ground"),
    (RECORD + ["--out", "afile"], "--out"),
    (RECORD + ["--out", "afile/clip"], "--out"),
    (RECORD + ["--out", "ro"], "--out"),
    (["record", "--map", "{in}/latin1.json", "--out", "clip"], "latin1.json"),
    # synth
    (["synth", "--out", "data", "--count", "0"], "--count"),
    (["synth", "--out", "data", "--count", "1e3"], "--count"),
    (["synth", "--out", "data", "--count", "5", "--frames", "-1"], "--frames"),
    (["synth", "--out", "data", "--count", "5", "--seed", "-1"], "--seed"),
    (["synth", "--out", "data", "--count", "5", "--species", "oil_palm", "--species", "pine"], "--species"),
    (["synth", "--out", "data", "--count", "5", "--touching", "1.5"], "--touching"),
    (["synth", "--out", "afile", "--count", "5"], "--out"),
    (["synth", "--out", "ro", "--count", "5"], "--out"),
    # fly
    (FLY + ["--latency-ms", "70000"], "--latency-ms"),
    (["fly", "--map", "map1", "--fps", "0.01"], "--fps"),
    # crazyflie (each refused before any drone starts)
    (["crazyflie", "--count", "0"], "--count"),
    (["crazyflie", "--count", "11"], "--count"),
    (["crazyflie", "--crtp", "127.0.0.1:65535", "--count", "2"], "--crtp"),
    (["crazyflie", "--crtp", "nope"], "--crtp"),
    (["crazyflie", "--plant", "quantum"], "--plant"),
    (["crazyflie", "--max-time-s", "nan"], "--max-time-s"),
    (["crazyflie", "--map", "{in}/deep.json"], "deep.json"),
    (FLY + ["--seed", "-1"], "--seed"),
    (FLY + ["--hide-tree", "999"], "--hide-tree"),
    (FLY + ["--wind", "nan"], "--wind"),
    (FLY + ["--pixel-noise", "inf"], "--pixel-noise"),
    (FLY + ["--cam-offset", "nan", "0"], "--cam-offset"),
    (FLY + ["--cam-offset", "0", "0", "--cam-offset", "0.1", "0"], "--cam-offset"),
    (FLY + ["--dropout", "1.5"], "--dropout"),
    (FLY + ["--garbage-rate", "inf"], "--garbage-rate"),
    (FLY + ["--silence", "nan:5"], "--silence"),
    (FLY + ["--silence", "5"], "--silence"),
    (FLY + ["--speed", "0"], "--speed"),
    (FLY + ["--out", "afile"], "--out"),
    (FLY + ["--out", "ro"], "--out"),
    (["fly", "--map", "map1", "--camera", "thermal"], "--camera"),
    (FLY + ["--flow-scale", "1.1"], "--flow-scale: models the firmware plant"),
    (FLY + ["--ground-texture", "1.5"], "--ground-texture"),
    (["sweep", "--count", "2", "--out", "{in}/sweep-out", "--condition", "flow_scale=0.1:3"], "flow_scale"),
    (["fly", "--map", "{in}/deep.json", "--camera", "oracle"], "deep.json"),
    (FLY + ["--crtp", "abc"], "--crtp"),
    (FLY + ["--crtp", "127.0.0.1:70000"], "--crtp"),
    (FLY + ["--crtp", "0"], "--crtp"),
    (FLY + ["--crtp", "192.0.2.1:19850"], "--crtp"),  # an address of no interface here: cannot bind
    (["fly", "--map", "{in}/altitude_1e6.json", "--camera", "oracle"], "altitude_m"),
    (["fly", "--map", "{in}/altitude_1e6.json"], "altitude_m"),
    (["fly", "--map", "{in}/path_900m.json", "--camera", "oracle"], "path_900m.json: waypoints: the path F is 900 m"),
    (["fly", "--map", "{in}/crown_1e6.json"], "crown_m"),
    (["fly", "--map", "{in}/tree_x_1e7.json", "--camera", "oracle"], "trees[1].x"),
    # paper-tests, demo
    (["paper-tests", "--out", "afile"], "--out"),
    (["paper-tests", "--jobs", "0", "--out", "paper"], "--jobs"),
    (["paper-tests", "--tests", "42", "--out", "paper"], "--tests"),
    (["paper-tests", "--crtp", "localhost:", "--out", "paper"], "--crtp"),
    (["paper-tests", "--crtp", "65530", "--out", "paper"], "--crtp"),  # 9 tests: ports past 65535
    (["demo", "--out", "afile"], "--out"),
    (["demo", "--out", "ro"], "--out"),
    (["demo", "--seed", "-1"], "--seed"),
    (["demo", "--crtp", "-5"], "--crtp"),
    # replay
    (["replay", "{in}/backwards"], "t_s"),
    (["replay", "{in}/latin1_clip"], "clip.json"),
    (["replay", "{in}/deep_clip"], "clip.json"),
    (["replay", "{in}/frames_not_list"], "frames"),
    (["replay", "no_such_clip"], "no_such_clip"),
    (["replay", "{in}/cut_video"], "clip.avi"),
    (["replay", "{in}/swapped_video"], "video_sha256"),
    (["replay", CLIP, "--latency-ms", "-1"], "--latency-ms"),
    (["replay", CLIP, "--latency-ms", "70000"], "--latency-ms"),
    (["replay", CLIP, "--map", "{in}/latin1.json"], "latin1.json"),
    # bench, serial-check
    (["bench", "sim", "--seed", "-1"], "--seed"),
    (["bench", "gpu"], "target"),
    (["bench", "recall", "--model", "no_such_model.npz", "--count", "1"], "no_such_model.npz"),
    (["bench", "recall", "--count", "0"], "--count"),
    (["serial-check", "/dev/null", "--seconds", "-1"], "--seconds"),
    (["serial-check", "/dev/null", "--seconds", "inf"], "--seconds"),
    (["serial-check", "/dev/null", "--seconds", "nan"], "--seconds"),
    (["serial-check", "/dev/null", "--mode", "bogus"], "--mode"),
    # detector commands: arguments and the CSVs they read
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "afile/m.npz"], "--out"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "existing_dir"], "--out"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "ro/m.npz"], "--out"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "keep.npz"], "big_field.csv"),
    (["train", "--species", "oil_palm", "--data", "{in}/latin1.csv", "--out", "keep.npz"], "latin1.csv"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--seed", "-1", "--out", "keep.npz"],
     "--seed"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/big_field.csv", "--seed", "-1"], "--seed"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/big_field.csv"], "big_field.csv"),
    (["detect", "--window", "10", "{in}/big_field.csv"], "--window"),
    (["detect", "{in}/empty.png"], "empty.png: empty file (0 bytes)"),
    (["detect", "{in}/empty.png", "--crown-px", "60"], "empty.png"),
    (["detect", "{in}/empty.png", "--gsd", "1e9", "--crown-m", "0.4"], "--gsd"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/big_field.csv", "--gsd", "1e9", "--crown-m", "0.4"],
     "--gsd"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/duplicated_crops.csv"],
     "duplicated_crops.csv: line 3: crop pos/1.png already listed on line 2"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--windows", "24,1000000000",
      "--out", "keep.npz"], "--windows"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--windows", "9" * 30,
      "--out", "keep.npz"], "--windows"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--reference-width", "1",
      "--out", "keep.npz"], "--reference-width"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--margin", "1e300",
      "--out", "keep.npz"], "--margin"),
    (["synth", "--out", "data", "--count", "2", "--ground", "{in}/empty.png", "--ground-gsd", "0.01"],
     "empty.png: empty file"),
    # package, deploy
    (["package", "--out", "afile/x.jvpkg"], "--out"),
    (["package", "--out", "dir.jvpkg"], "--out"),
    (["package", "--out", "no_dir/x.jvpkg"], "--out"),
    (["package", "--out", "keep.png"], "--out"),
    (["deploy", "--sd", "no_such_card"], "--sd"),
    # split, plantation, sweep
    (["split", "--data", "{in}/big_field.csv", "--held-out", "2", "--out", "s"], "--held-out"),
    (["split", "--data", "{in}/big_field.csv", "--seed", "-1", "--out", "s"], "--seed"),
    (["split", "--data", "{in}/big_field.csv", "--out", "keep.png"], "--out"),
    (["plantation", "--seed", "-1"], "--seed"),
    (["plantation", "--columns", "0:0"], "--columns"),
    (["plantation", "--out", "afile/x.json"], "--out"),
    (["plantation", "--columns", "1000000000"], "--columns"),
    (["plantation", "--altitude-m", "1e6"], "--altitude-m"),
    (["plantation", "--heading-deg", "nan"], "--heading-deg"),
    (["plantation", "--column-length-m", "1e300"], "--column-length-m"),
    (["plantation", "--bend-deg", "40", "--column-bends", "3"], "--bend-deg"),
    (["plantation", "--profile", "paper"], "--profile"),
    (["sweep", "--count", "2", "--altitude-m", "0.1", "--out", "sw"], "--altitude-m"),
    (["sweep", "--count", "2", "--crowns", "{in}/duplicated_rows.csv", "--out", "sw"], "duplicated_rows.csv: line 3"),
    (["sweep", "--count", "0", "--out", "sw"], "--count"),
    (["sweep", "--count", "2", "--workers", "0", "--out", "sw"], "--workers"),
    (["sweep", "--count", "2", "--out", "keep.png"], "--out"),
    (["sweep", "--count", "2", "--faults", "extreme", "--out", "sw"], "--faults"),
    (["sweep", "--count", "2", "--seed", "nan", "--out", "sw"], "--seed"),
    (["sweep", "--count", "2", "--model", "{in}/big_field.csv", "--out", "sw"], "--model"),
    (["sweep", "--count", "2", "--camera", "oracle", "--model", "oil_palm.npz", "--out", "sw"], "--model"),
    (["sweep", "--count", "2", "--app", "rust", "--out", "sw"], "--app"),
] + [(["train", "--species", "oil_palm", "--data", path, "--out", "keep.npz"], named) for path, named in CSV_ROWS] + [
    (["evaluate", "--model", "oil_palm", "--data", path], named) for path, named in CSV_ROWS] + [
    (["split", "--data", path, "--out", "s"], named) for path, named in CSV_ROWS] + [
    (["synth", "--out", "data", "--count", "2", "--crowns", path], named) for path, named in CSV_ROWS] + [
    (["fly", "--map", "map1", "--crowns", path], named) for path, named in CSV_ROWS] + [
    # issue 45: each class once per command that has it
    (["train", "--species", "oil_palm", "--data", "{in}/zero_box.csv", "--out", "keep.npz"],
     "zero_box.csv: line 3: a 0 x 60 px box"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv"], "one_px.png: a 1x1 px image"),
    (["detect", "{in}/one_px.png"], "one_px.png: a 1x1 px image"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--crown-px", "1e9"], "--crown-px"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--crops", "1000000000"], "--crops"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--plot", "pr.bmpx"], "--plot"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--plot", "afile/pr.png"], "--plot"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--plot", "existing_dir"], "--plot"),
    (["evaluate", "--model", "oil_palm", "--data", "{in}/one_px.csv", "--plot", "ro/pr.png"], "--plot"),
    (["detect", "{in}/one_px.png", "--step", "0"], "--step"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "keep.npz", "--report", "afile"],
     "--report"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "keep.npz", "--report", "ro/r"],
     "--report"),
    (["train", "--species", "oil_palm", "--data", "{in}/big_field.csv", "--out", "n" * 300 + ".npz"], "--out"),
    (["render", "--map", "map1", "--x", "1", "--y", "0", "--out", "n" * 300 + ".png"], "a name of 304 bytes"),
    (["package", "--vendor", "V" * 300, "--out", "x.jvpkg"], "--vendor"),
    (["deploy", "--sd", "no_such_card", "--vendor", "V" * 300], "--vendor"),
    (FLY + ["--mavlink", "udpout:127.0.0.1:99999", "--out", "fo"], "--mavlink"),
    (FLY + ["--mavlink", "udpout:256.0.0.1:14550", "--out", "fo"], "--mavlink"),
    (FLY + ["--mavlink", "14550", "--out", "fo"], "--mavlink"),
    (FLY + ["--out", ""], "--out"),
    (["paper-tests", "--tests", "", "--out", "paper"], "--tests"),
    (["plantation", "--column-length-m", "0", "--out", "p.json"], "--column-length-m"),
    (["fly", "--map", "{in}/long_name.json", "--camera", "oracle"], "long_name.json: name: a name of"),
    (["fly", "--map", "{in}/many_trees.json", "--camera", "oracle"], "many_trees.json: trees: 100000 trees"),
    (["fly", "--map", "{in}/fifo.json", "--camera", "oracle"], "fifo.json: not a regular file"),
    (["render", "--map", "{in}/fifo.json", "--x", "1", "--y", "0", "--out", "keep.png"], "fifo.json"),
    (["replay", "{in}/slow_clip"], "slow_clip/clip.json: fps: a clip at 0.5 fps"),
    (["replay", "{in}/z0_clip"], "frames[2].pose.z"),
    (["replay", "{in}/zneg_clip"], "frames[2].pose.z"),
    (["replay", "{in}/offset_nan_clip"], "mount_offset"),
    (["sweep", "--count", "2", "--condition", "wind_mps2=nan:nan", "--out", "sw"], "--condition wind_mps2"),
    (["sweep", "--count", "2", "--condition", "latency_frames=0:inf", "--out", "sw"], "--condition latency_frames"),
    (["sweep", "--count", "2", "--condition", "pixel_noise_px=0:1e9", "--out", "sw"], "--condition pixel_noise_px"),
    (["sweep", "--count", "2", "--condition", "cam_offset_m=nan:0", "--out", "sw"], "--condition cam_offset_m"),
    (["sweep", "--count", "2", "--condition", "fps=1e9:1e9", "--out", "sw"], "--condition fps"),
    (["bench", "sim", "--model", "oil_palm"], "--model: only with bench detector or recall"),
    # the command itself
    (["nosuch"], "nosuch"),
    ([], "command"),
]


def _case_id(case):
    argv, named = case
    return "-".join(a.replace("{in}/", "") for a in argv)[:60] or "no-command"


def test_that_the_table_holds_at_least_60_bad_inputs_across_every_command():
    commands = {argv[0] for argv, _ in CASES if argv and argv[0] in cli.COMMANDS}
    assert len(CASES) >= 60
    assert commands == set(cli.COMMANDS)


@pytest.mark.timeout(60)  # a row that starts real work instead of refusing fails here, not after minutes
@pytest.mark.parametrize("case", CASES, ids=[_case_id(c) for c in CASES])
def test_that_bad_input_gives_one_line_naming_it_exit_2_and_writes_nothing(case, inputs, scratch, capsys,
                                                                           monkeypatch):
    # Fixture
    argv, named = case
    root, read_only = scratch
    if "ro" in argv or any(a.startswith("ro/") for a in argv):
        if not read_only:
            pytest.skip("cannot make a read-only folder here")
    monkeypatch.chdir(root)
    argv = [a.replace("{in}", str(inputs)) for a in argv]
    before = snapshot(root)
    # Test
    code = cli.main(argv)
    # Assert
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert code == 2, captured.err
    assert len(lines) == 1, captured.err
    assert named in lines[0]
    assert "Traceback" not in captured.err and captured.out == ""
    assert snapshot(root) == before


def run_foranav(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "host_tools.cli"] + [str(a) for a in args], text=True, **kwargs)


def test_that_a_real_process_prints_one_line_and_exits_2(tmp_path, inputs):
    # a real stderr: OpenCV's and FFmpeg's own warnings (missing image, damaged video) would show here
    for args, named in ((RENDER + ["--x", "nan", "--out", tmp_path / "f.png"], "--x"),
                        (["record", "--map", "map1", "--out", tmp_path / "c", "--fps", "1e9"], "--fps"),
                        (["replay", inputs / "cut_video"], "clip.avi"),
                        (["detect", tmp_path / "missing.png"], "missing.png")):
        proc = run_foranav(*args, capture_output=True)
        assert proc.returncode == 2
        assert len(proc.stderr.splitlines()) == 1 and named in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_that_a_reader_going_away_does_not_stop_training(tmp_path):
    # Fixture: a tiny data set, and a stdout pipe whose reader is already gone (`| head` after it exited)
    assert cli.main(["synth", "--out", str(tmp_path / "data"), "--count", "4", "--frames", "4", "--seed", "1"]) == 0
    model = tmp_path / "m.npz"
    read_end, write_end = os.pipe()
    os.close(read_end)
    # Test
    try:
        proc = run_foranav("train", "--species", "oil_palm", "--data", tmp_path / "data" / "frames" / "boxes.csv",
                           "--out", model, stdout=write_end, stderr=subprocess.PIPE)
    finally:
        os.close(write_end)
    # Assert
    assert proc.returncode == 0, proc.stderr
    assert all(line.startswith("train [") for line in proc.stderr.splitlines()), proc.stderr  # the progress bar only
    assert model.stat().st_size > 0


def test_that_the_same_reader_going_away_inside_main_keeps_the_exit_status(tmp_path, monkeypatch):
    class GonePipe(object):
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", GonePipe())
    out = tmp_path / "frame.png"
    assert cli.main(RENDER + ["--out", str(out)]) == 0  # prints the trees in view after writing
    assert out.stat().st_size > 0


def test_that_repeated_species_options_add_up(tmp_path, capsys):
    for name, argv in (("joined", ["--species", "oil_palm", "olive"]),
                       ("repeated", ["--species", "oil_palm", "--species", "olive"])):
        assert cli.main(["synth", "--out", str(tmp_path / name), "--count", "2", "--frames", "0"] + argv) == 0
        assert "(target oil_palm, olive)" in capsys.readouterr().out
    assert (tmp_path / "joined" / "crops" / "crops.csv").read_bytes() == \
        (tmp_path / "repeated" / "crops" / "crops.csv").read_bytes()


def test_that_the_readers_name_the_file_for_every_way_it_can_be_bad(inputs):
    for reader, path, named in ((read_boxes, inputs / "latin1.csv", "not UTF-8"),
                                (read_boxes, inputs / "big_field.csv", "field larger"),
                                (read_clip, inputs / "backwards", "t_s"),
                                (read_clip, inputs / "deep_clip", "nested too deeply"),
                                (fileio.read_json, inputs / "folder.json", "is a folder")):
        with pytest.raises(ForaNavError, match=named) as caught:
            reader(path)
        assert path.name in str(caught.value) and "\n" not in str(caught.value)


def test_that_output_checks_refuse_wrong_types_and_accept_new_folders(tmp_path):
    (tmp_path / "afile").write_bytes(OLD_BYTES)
    fileio.check_output_dir(tmp_path / "new" / "deeper")  # created later by the writer
    fileio.check_output_file(tmp_path / "afile")  # replaced atomically later
    for check, path in ((fileio.check_output_dir, tmp_path / "afile"),
                        (fileio.check_output_dir, tmp_path / "afile" / "sub"),
                        (fileio.check_output_file, tmp_path),
                        (fileio.check_output_file, tmp_path / "missing" / "x.png"),
                        (fileio.check_output_file, tmp_path / "afile" / "x.png")):
        with pytest.raises(ForaNavError, match="--out"):
            check(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_that_images_claiming_huge_sizes_or_cut_short_are_refused_before_decoding(tmp_path):
    # Fixture: a real frame as PNG and JPEG, then damaged copies
    image = (np.random.RandomState(0).rand(288, 352, 3) * 255).astype(np.uint8)
    png, jpeg = (cv2.imencode(ext, image)[1].tobytes() for ext in (".png", ".jpg"))
    files = {"ok.png": png, "ok.jpg": jpeg, "cut.jpg": jpeg[:len(jpeg) // 2], "cut.png": png[:len(png) // 2],
             "huge.png": png[:16] + struct.pack(">II", 30000, 30000) + png[24:], "text.png": b"not an image\n"}
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    # Test / Assert
    assert images.read_image(tmp_path / "ok.png").shape == image.shape
    assert images.read_image(tmp_path / "ok.jpg").shape == image.shape
    for name, reason in (("cut.jpg", "truncated JPEG"), ("cut.png", "truncated PNG"), ("huge.png", "30000x30000"),
                         ("text.png", "not an image"), ("missing.png", "cannot read")):
        with pytest.raises(ForaNavError, match=reason) as caught:
            images.read_image(tmp_path / name)
        assert name in str(caught.value)


FUZZ_VALUES = [None, "x", "", [], {}, -1, 0, 1e308, -1e308, 10 ** 20, True, [1, 2], [[1]], {"a": 1}, 3.5,
               float("nan"), float("inf"), 2 ** 63, "oil_palm"]
FUZZ_SAMPLES = 600


def _json_paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for key, value in obj.items():
            yield from _json_paths(value, prefix + (key,))
    elif isinstance(obj, list):
        for index, value in enumerate(obj[:3]):
            yield from _json_paths(value, prefix + (index,))


def _mutated(obj, rng):
    """A copy of obj with one value replaced by a value of another type, or one field removed."""
    obj = copy.deepcopy(obj)
    path = rng.choice(list(_json_paths(obj))[1:])
    target = obj
    for key in path[:-1]:
        target = target[key]
    if isinstance(target, dict) and rng.random() < 0.2:
        del target[path[-1]]
    else:
        target[path[-1]] = rng.choice(FUZZ_VALUES)
    return obj


def test_that_map_and_clip_validators_raise_only_foranav_errors_on_damaged_files():
    rng = random.Random(11)
    map_data = json.loads((Path(cli.__file__).parent / "data" / "maps" / "map1.json").read_text())
    clip_data = json.loads((FIXTURE_CLIP / "clip.json").read_text())
    refused = 0
    for _ in range(FUZZ_SAMPLES):
        for validate, data in ((lambda d: map_from_dict(d, "m.json"), map_data),
                               (lambda d: clip_from_dict(d, FIXTURE_CLIP, "clip.json"), clip_data)):
            try:
                validate(_mutated(data, rng))
            except ForaNavError as err:
                refused += 1
                assert "\n" not in str(err)
    assert refused > FUZZ_SAMPLES  # most damage is caught, none of it as another exception


def test_that_detect_refuses_a_truncated_jpeg_and_a_non_utf8_crops_csv(tmp_path, capsys):
    # Fixture: a real JPEG cut in half (OpenCV decodes it with only a warning), a crops CSV in Latin-1
    image = np.full((64, 64, 3), 90, np.uint8)
    jpeg = cv2.imencode(".jpg", image)[1].tobytes()
    (tmp_path / "cut.jpg").write_bytes(jpeg[:len(jpeg) // 2])
    (tmp_path / "crops.csv").write_bytes(b"image,class,category\ncaf\xe9.png,pos,oil_palm\n")
    # Test / Assert
    for argv, named in ((["detect", str(tmp_path / "cut.jpg")], "cut.jpg"),
                        (["evaluate", "--model", "oil_palm", "--data", str(tmp_path / "crops.csv")], "not UTF-8")):
        assert cli.main(argv) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and named in err[0], err


ERRORS_DOC = Path(__file__).resolve().parents[2] / "docs" / "errors.md"
TALLY_START, TALLY_END = "<!-- bad-input tally: start -->", "<!-- bad-input tally: end -->"


def bad_input_tally() -> str:
    """docs/errors.md's table: the bad inputs of CASES per command; each must end as the test above asserts
    (refused: exit 2, one line naming the option or file, nothing written). `python -m
    tests.cross_cutting.test_cli_bad_inputs` prints it."""
    counts = {}
    for argv, _named in CASES:
        command = argv[0] if argv and argv[0] in cli.COMMANDS else "(no or unknown command)"
        counts[command] = counts.get(command, 0) + 1
    rows = ["| command | bad inputs | refused in one line, exit 2, nothing written |", "|---|---:|---:|"]
    rows += ["| %s | %d | %d |" % (command, count, count) for command, count in sorted(counts.items())]
    rows.append("| all | %d | %d |" % (len(CASES), len(CASES)))
    return "\n".join([TALLY_START] + rows + [TALLY_END])


def test_that_the_tally_in_errors_md_is_the_table_of_this_file():
    text = ERRORS_DOC.read_text()
    assert bad_input_tally() in text, "run: python -m tests.cross_cutting.test_cli_bad_inputs --write"


if __name__ == "__main__":
    tally = bad_input_tally()
    if "--write" in sys.argv:
        text = ERRORS_DOC.read_text()
        start, end = text.index(TALLY_START), text.index(TALLY_END) + len(TALLY_END)
        ERRORS_DOC.write_text(text[:start] + tally + text[end:])
    print(tally)
