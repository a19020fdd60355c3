"""What the deploy tests share: fake JEVOIS partitions and fake module folders (built in tmp_path), and a digest of
a folder tree to show that a refused deploy changed nothing."""
import hashlib
import io
import textwrap
import zipfile

import numpy as np
import pytest

from host_tools import cli

FIXED_ZIP_TIME = (2024, 1, 1, 0, 0, 0)
MODULE = "modules/ForaNav/ForaNavTrees"  # where deploy puts the module on the card
BAD_INPUT_EXIT = 2

# An excerpt of a real JeVois-A33 videomappings.cfg: comments, blank lines, a commented-out mapping, a mapping with
# a trailing comment and relative USB size, the single default (*), a NONE mapping, and a USB mode that clashes
# with nothing of ours.
USER_VIDEOMAPPINGS = textwrap.dedent("""\
    # JeVois smart camera operation modes and video mappings
    #
    # Format is: <USBmode> <USBw> <USBh> <USBfps> <CAMmode> <CAMw> <CAMh> <CAMfps> <Vendor> <Module> [*]

    YUYV 320 240 30.0 YUYV 320 240 30.0 JeVois DNN
    YUYV +0 +0 24.0 YUYV 800 600 24.0 JeVois SaveVideo # OV2640 sensor only
    #YUYV 352 288 30.0 YUYV 352 288 30.0 JeVois PassThrough

    NONE 0 0 0 YUYV 320 240 60.0 JeVois SaveVideo
    YUYV 640 360 30.0 YUYV 320 240 30.0 JeVois JeVoisIntro *
    YUYV 640 480 30.0 YUYV 320 240 30.0 JeVois JeVoisIntro
    """)

# The A33 image's default initscript.cfg: comments only.
USER_INITSCRIPT = textwrap.dedent("""\
    # JeVois initialization script
    #
    #setmapping 0
    #setpar serlog Hard
    #setpar serout Hard
    #streamon
    """)

MODULE_SOURCE = textwrap.dedent('''\
    """Fake ForaNavTrees for deploy tests."""
    import os

    import libjevois as jevois
    import numpy as np
    import foranav_helper

    MODEL = "foranav_oil_palm.npz"


    class ForaNavTrees:
        def __init__(self):
            self.model = None

        def init(self):
            pc = jevois.ParameterCategory("ForaNav", "tree detector")
            self.thresh = jevois.Parameter(self, "svmthresh", "float", "SVM score threshold", 0.5, pc)
            self.marks = jevois.Parameter(self, "framemark", "bool", "send MARK STOP after each frame", True, pc)
            self.add(pc, "step", "int", "window step", foranav_helper.STEP)
            self.add(pc, "hsthresh", "float", "colour test threshold", self.model_threshold())

        def model_threshold(self):
            # A default only known once the module runs: it comes from the model file.
            folder = os.path.dirname(os.path.abspath(__file__))
            return 0.1 * len(np.load(os.path.join(folder, MODEL))["weights"])

        def add(self, category, name, kind, description, default):
            setattr(self, name, jevois.Parameter(self, name, kind, description, default, category))

        def processNoUSB(self, inframe):
            jevois.sendSerial(foranav_helper.line())
    ''')

HELPER_SOURCE = 'STEP = 8\n\n\ndef line():\n    return "MARK STOP"\n'


def npz_bytes(**arrays):
    """An .npz archive (what np.savez writes) with a fixed member time, so the same arrays give the same bytes."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, array in sorted((arrays or {"weights": np.zeros(3)}).items()):
            member = io.BytesIO()
            np.save(member, array)
            archive.writestr(zipfile.ZipInfo(name + ".npy", date_time=FIXED_ZIP_TIME), member.getvalue())
    return buffer.getvalue()


def make_module_folder(root, model=True, source=MODULE_SOURCE):
    """A module folder as the repository has it, with the host-only extras that must not be deployed."""
    folder = root / "ForaNavTrees"
    (folder / "__pycache__").mkdir(parents=True)
    (folder / "ForaNavTrees.py").write_text(source)
    (folder / "foranav_helper.py").write_text(HELPER_SOURCE)
    (folder / "__init__.py").write_text("")
    (folder / "__pycache__" / "foranav_helper.cpython-311.pyc").write_bytes(b"\x00pyc")
    (folder / "test_helper.py").write_text("def test_x():\n    pass\n")
    if model:
        (folder / "foranav_oil_palm.npz").write_bytes(npz_bytes())
    return folder


def make_card(root, videomappings=USER_VIDEOMAPPINGS, initscript=USER_INITSCRIPT):
    """A JEVOIS partition: config/ with the user's files, modules/ with a bundled module."""
    sd = root / "JEVOIS"
    (sd / "config").mkdir(parents=True)
    (sd / "modules" / "JeVois" / "DNN").mkdir(parents=True)
    (sd / "modules" / "JeVois" / "DNN" / "DNN.so").write_bytes(b"\x7fELF")
    (sd / "config" / "videomappings.cfg").write_text(videomappings)
    if initscript is not None:
        (sd / "config" / "initscript.cfg").write_text(initscript)
    (sd / "config" / "params.cfg").write_text("camturbo=true\n")
    return sd


def tree_digest(root):
    """One hash of every file's path and bytes under root."""
    digest = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def deploy(sd, module_dir, *extra):
    """``foranav deploy`` in-process; returns its exit status."""
    return cli.main(["deploy", "--sd", str(sd), "--module-dir", str(module_dir)] + list(extra))


@pytest.fixture
def card_and_module(tmp_path):
    """A fake card and a fake module folder to deploy onto it."""
    return make_card(tmp_path), make_module_folder(tmp_path / "src")
