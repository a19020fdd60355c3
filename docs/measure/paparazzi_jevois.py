"""What an autopilot's JeVois parser receives from the ForaNav camera module: Paparazzi's parser
(sw/airborne/modules/sensors/cameras/jevois.c and .h, GPL, NOT in this repository) compiled unmodified with
our harness (docs/measure/jevois_parser_harness/: stand-ins for the few Paparazzi headers it includes, and a
main that feeds it bytes and prints what it publishes). docs/hardware.md, "Other autopilots".

    .venv/bin/python docs/measure/paparazzi_jevois.py PAPARAZZI_AIRBORNE_DIR [CLIP ...]

PAPARAZZI_AIRBORNE_DIR holds modules/sensors/cameras/jevois.c and jevois.h (Paparazzi's sw/airborne). The
module's real serial output comes from running it (the unchanged jevois_module/ForaNavTrees through the
libjevois stand-in) on every frame of the clips (default: the two committed CI clips), once per setting of
maxtrees x framemark x serstyle, with the camera's line ending (CRLF; and LF, shown as a check). For each setting it
prints the trees the module sent, the trees the parser published (and whether each published message's
coordinates equal the line it came from), and the frames in which every tree, and the best tree, arrived.
"""
import subprocess
import sys
import tempfile
from pathlib import Path

from host_tools.jevois_host import ModuleRunner, NullLog
from host_tools.sim.clip import read_clip

HERE = Path(__file__).resolve().parent / "jevois_parser_harness"
REPO = Path(__file__).resolve().parents[2]
DEFAULT_CLIPS = [REPO / "tests/fixtures/clips/map1_full", REPO / "tests/fixtures/clips/map3_short_sensor"]
SETTINGS = [(trees, mark, style) for style in ("Terse", "Normal") for mark in ("Stop", "None")
            for trees in (1, 2, 3, 8)]
TREE_TYPES = {"T2": 20, "N2": 21}  # jevois.h JEVOIS_MSG_T2, JEVOIS_MSG_N2


def build_harness(airborne: Path, out: Path) -> Path:
    source = airborne / "modules" / "sensors" / "cameras" / "jevois.c"
    if not source.is_file():
        sys.exit("%s: no such file (give the folder that holds modules/sensors/cameras/jevois.c)" % source)
    binary = out / "jevois_parser_harness"
    subprocess.run(["cc", "-std=gnu99", "-O1", "-I", str(HERE / "include"), "-I", str(airborne),
                    "-DJEVOIS_DEV=jevois_harness_uart", "-DSITL", str(HERE / "harness.c"), str(source),
                    "-o", str(binary)], check=True, stderr=subprocess.DEVNULL)
    return binary


def module_lines(clips: list, maxtrees: int, framemark: str, serstyle: str) -> list:
    """[(frame number, line)] the module sent over every frame of the clips, in order."""
    sent = []
    frame_number = 0
    for clip in clips:
        runner = ModuleRunner(params={"maxtrees": maxtrees, "framemark": framemark, "serstyle": serstyle},
                              log_stream=NullLog())
        for image in clip.images():
            sent += [(frame_number, line) for line in runner.process_frame(image)]
            frame_number += 1
    return sent


def parse_published(output: str) -> list:
    rows = []
    for line in output.splitlines():
        offset, kind, ident, nb, *coords = line.split()
        rows.append((int(offset), int(kind), ident, [int(c) for c in coords]))
    return rows


def measure(binary: Path, sent: list, ending: str) -> dict:
    stream, ends = b"", []
    for _, line in sent:
        stream += (line + ending).encode("ascii")
        ends.append(len(stream))  # offset one past the line's last byte
    published = parse_published(subprocess.run([str(binary)], input=stream, capture_output=True,
                                               check=True).stdout.decode())
    received, exact = set(), 0
    for offset, kind, ident, coords in published:
        # the message came from the last line that ended at or before the byte that published it
        index = max(i for i, end in enumerate(ends) if end <= offset + 1)
        words = sent[index][1].split()
        numbers = [int(w) for w in words[1:] if w.lstrip("-").isdigit()]
        exact += TREE_TYPES.get(words[0]) == kind and numbers[:len(coords)] == coords
        received.add(index)
    trees = [i for i, (_, line) in enumerate(sent) if line.split()[0] in TREE_TYPES]
    frames = {}
    for i in trees:
        frames.setdefault(sent[i][0], []).append(i)
    by_count = {}  # trees sent in a frame -> [trees received in each such frame]
    for rows in frames.values():
        by_count.setdefault(len(rows), []).append(sum(i in received for i in rows))
    return {"sent": len(trees), "received": sum(i in received for i in trees), "published": len(published),
            "exact": exact, "frames": len(frames),
            "frames_whole": sum(all(i in received for i in rows) for rows in frames.values()),
            "frames_best": sum(rows[0] in received for rows in frames.values()),
            "per_frame": " ".join("%d:%.2f" % (k, sum(v) / len(v)) for k, v in sorted(by_count.items()))}


def main() -> None:
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    clips = [read_clip(path) for path in (sys.argv[2:] or DEFAULT_CLIPS)]
    with tempfile.TemporaryDirectory() as scratch:
        binary = build_harness(Path(sys.argv[1]), Path(scratch))
        print("%-8s %-9s %-7s %10s %12s %8s %13s %13s  %s" % (
            "maxtrees", "framemark", "style", "trees sent", "received", "(LF)", "frames whole", "best arrived",
            "trees sent in a frame: mean received"))
        for maxtrees, framemark, serstyle in SETTINGS:
            sent = module_lines(clips, maxtrees, framemark, serstyle)
            crlf, lf = measure(binary, sent, "\r\n"), measure(binary, sent, "\n")
            for r in (crlf, lf):  # every published message is its line, coordinate for coordinate
                assert r["exact"] == r["published"], r
            print("%-8d %-9s %-7s %10d %5d (%3.0f%%) %8d %6d of %3d %6d of %3d  %s" % (
                maxtrees, framemark, serstyle, crlf["sent"], crlf["received"],
                100.0 * crlf["received"] / max(1, crlf["sent"]), lf["received"], crlf["frames_whole"], crlf["frames"],
                crlf["frames_best"], crlf["frames"], crlf["per_frame"]))

if __name__ == "__main__":
    main()
