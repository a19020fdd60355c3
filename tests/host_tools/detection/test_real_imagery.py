"""Opt-in (-m realdata): the user's path on ../shared/data/real, split by image, as docs/detector.md runs it.

Trains once per session (2-8 minutes on 2 shared cores). The targets are issue 9's; those not reached
yet are expected failures with the measured figure as the reason (docs/detector.md has the table)."""
import json

import pytest

from host_tools.cli import main
from tests.conftest import REPO_ROOT

pytestmark = [pytest.mark.realdata, pytest.mark.slow]

REAL = REPO_ROOT.parent / "shared" / "data" / "real"
SOURCES = ("oilpalm_gearth_detectree2", "oilpalm_uav_kluang_narimt", "coconut_tonga_oam", "olive_kallk",
           "neon_deepforest")
# issue 9's targets on held-out images, thresholds chosen on the training side, with --crown-px given
GOOGLE_EARTH_F1 = 0.85
KLUANG_F1 = 0.65
COCONUT_FALSE_ALARMS_PER_CHIP = 0.05
PAPER = {"accuracy": 0.9291, "precision": 0.9037, "recall": 0.9606}


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    if not REAL.exists():
        pytest.skip("no shared real data")
    root = tmp_path_factory.mktemp("real")
    split = root / "split"
    assert main(["split", "--data"] + [str(REAL / s / "boxes.csv") for s in SOURCES]
                + ["--held-out", "0.25", "--seed", "0", "--out", str(split)]) == 0
    model = str(root / "real_oil_palm.npz")
    assert main(["train", "--species", "oil_palm", "--seed", "0", "--out", model, "--quiet", "--data"]
                + [str(split / "train" / s / "boxes.csv") for s in SOURCES]) == 0
    return model, {s: str(split / "test" / s / "boxes.csv") for s in SOURCES}


def evaluate(capsys, model, *args):
    capsys.readouterr()
    assert main(["evaluate", "--model", model, "--json"] + list(args)) == 0
    return json.loads(capsys.readouterr().out)


def test_that_coconut_chips_give_at_most_the_target_false_alarms_per_chip(trained, capsys):
    model, test = trained
    coconut = evaluate(capsys, model, "--data", test["coconut_tonga_oam"], "--crown-px", "24")
    assert coconut["frames"]["false_alarms_per_image"] <= COCONUT_FALSE_ALARMS_PER_CHIP


@pytest.mark.xfail(reason="measured F1 84.00 % on the one held-out image (docs/detector.md)", strict=False)
def test_that_google_earth_oil_palm_reaches_the_target_f1(trained, capsys):
    model, test = trained
    google = evaluate(capsys, model, "--data", test["oilpalm_gearth_detectree2"], "--crown-px", "160", "--hull")
    assert google["frames"]["f1"] >= GOOGLE_EARTH_F1


@pytest.mark.xfail(reason="measured F1 64.89 %; the Kluang labels miss crowns (docs/detector.md)", strict=False)
def test_that_kluang_uav_oil_palm_reaches_the_target_f1(trained, capsys):
    model, test = trained
    kluang = evaluate(capsys, model, "--data", test["oilpalm_uav_kluang_narimt"], "--crown-px", "68")
    assert kluang["frames"]["f1"] >= KLUANG_F1


@pytest.mark.xfail(reason="measured 92.5 / 91.1 / 94.2 %: precision reached, accuracy and recall not (docs/detector.md)", strict=False)
def test_that_the_crop_protocol_on_held_out_images_reaches_the_paper(trained, capsys):
    model, test = trained
    crops = evaluate(capsys, model, "--data", *test.values(), "--crown-px", "boxes", "--hull")
    for figure, paper in PAPER.items():
        assert crops[figure] >= paper, figure
