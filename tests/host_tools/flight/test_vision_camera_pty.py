"""The pty is real: what the JeVois module sends arrives through pyserial on the other end, and the vision
camera's pieces (hidden trees, detection scoring) do what they say."""
import os

import numpy as np
import serial

from host_tools.flight.vision_camera import DetectionScore, VisionCamera, parse_detections
from host_tools.flight.wire import PtyWire
from host_tools.jevois_host import ModuleRunner
from host_tools.maps import load_map
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import World
from jevois_module.ForaNavTrees import foranav_serial

READ_TIMEOUT_S = 2.0


def _read_lines(port, count):
    assembler = foranav_serial.LineAssembler()
    lines = []
    while len(lines) < count:
        data = port.read(256)
        assert data, "pty: nothing arrived within %.1f s (have %r)" % (READ_TIMEOUT_S, lines)
        lines.extend(assembler.feed(data))
    return lines


def test_that_module_output_crosses_the_pty_into_pyserial():
    # Fixture: Map 1 seen from right above tree 2, the module writing into the pty master
    pmap = load_map("map1")
    tree = pmap.tree(2)
    image = World.from_map(pmap).render(CameraModel(), Pose(tree.x, tree.y, pmap.altitude_m)).image
    with PtyWire(lockstep=False) as wire:
        master = os.fdopen(os.dup(wire.master_fd), "wb", buffering=0)
        runner = ModuleRunner(serial_stream=master, params={"species": "oil_palm"})
        port = serial.serial_for_url(wire.slave_path, baudrate=115200, timeout=READ_TIMEOUT_S)
        try:
            # Test
            sent = runner.process_frame(image)
            received = _read_lines(port, len(sent))
        finally:
            port.close()
            master.close()
    # Assert: the same lines, byte for byte, and the frame ends with MARK STOP
    assert [line.decode("ascii") for line in received] == sent
    assert sent[-1] == foranav_serial.FRAME_STOP
    (u, v), = parse_detections(sent, 352, 288)[:1]
    assert abs(u - 176) < 0.5 * 0.35 / 0.003875 and abs(v - 144) < 0.5 * 0.35 / 0.003875  # on tree 2


def test_that_a_hidden_tree_is_gone_from_the_frame_the_module_sees():
    pmap = load_map("map1")
    tree = pmap.tree(2)
    camera = VisionCamera(pmap, effects="none")
    pose = (tree.x, tree.y, pmap.altitude_m, 0.0)
    seen = camera.capture(0, pose)
    hidden = camera.capture(111, pose, hidden=frozenset([2]))
    near_centre = lambda lines: [p for p in parse_detections(lines, 352, 288)  # noqa: E731
                                 if np.hypot(p[0] - 176, p[1] - 144) < 40]
    assert near_centre(seen) and not near_centre(hidden)
    assert hidden[-1] == foranav_serial.FRAME_STOP  # the camera still reports the (empty) frame


def test_that_detections_are_scored_against_the_truth():
    score = DetectionScore()
    truth = [(100.0, 100.0, 90.0), (250.0, 150.0, 90.0)]
    score.add(0, [(105.0, 98.0), (20.0, 20.0)], truth)  # one hit (error ~5.4 px), one false, one missed
    score.add(111, [], [])
    report = score.report()
    assert (report["true_positives"], report["false_positives"], report["missed"]) == (1, 1, 1)
    assert report["frames"] == 2 and report["detections_per_frame"] == 1.0
    assert abs(report["mean_pixel_error"] - np.hypot(5, 2)) < 0.01
