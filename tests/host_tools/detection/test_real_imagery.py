"""Opt-in (-m realdata): the user's path on ../shared/data/real, split by image, as docs/detector.md runs it.

Trains twice per session (seeds 0 and 1; 3-8 minutes each on 2 shared cores). The targets are issue 9's; those not reached
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
def split(tmp_path_factory):
    if not REAL.exists():
        pytest.skip("no shared real data")
    root = tmp_path_factory.mktemp("real")
    assert main(["split", "--data"] + [str(REAL / s / "boxes.csv") for s in SOURCES]
                + ["--held-out", "0.25", "--seed", "0", "--out", str(root / "split")]) == 0
    return root


def train_on(root, seed):
    model = str(root / ("real_oil_palm_seed%d.npz" % seed))
    assert main(["train", "--species", "oil_palm", "--seed", str(seed), "--out", model, "--quiet", "--data"]
                + [str(root / "split" / "train" / s / "boxes.csv") for s in SOURCES]) == 0
    return model, {s: str(root / "split" / "test" / s / "boxes.csv") for s in SOURCES}


@pytest.fixture(scope="module")
def trained(split):
    return train_on(split, 0)


def evaluate(capsys, model, *args):
    capsys.readouterr()
    assert main(["evaluate", "--model", model, "--json"] + list(args)) == 0
    return json.loads(capsys.readouterr().out)


def test_that_coconut_chips_give_at_most_the_target_false_alarms_per_chip(trained, capsys):
    model, test = trained
    coconut = evaluate(capsys, model, "--data", test["coconut_tonga_oam"], "--crown-px", "24")
    assert coconut["frames"]["false_alarms_per_image"] <= COCONUT_FALSE_ALARMS_PER_CHIP


@pytest.mark.xfail(reason="measured F1 80.37 % on the one held-out image; 72.9-80.4 % over seeds 0-2 (docs/detector.md)", strict=False)
def test_that_google_earth_oil_palm_reaches_the_target_f1(trained, capsys):
    model, test = trained
    google = evaluate(capsys, model, "--data", test["oilpalm_gearth_detectree2"], "--crown-px", "160", "--hull")
    assert google["frames"]["f1"] >= GOOGLE_EARTH_F1


@pytest.mark.xfail(reason="measured F1 64.06 %; the Kluang labels miss crowns (docs/detector.md)", strict=False)
def test_that_kluang_uav_oil_palm_reaches_the_target_f1(trained, capsys):
    model, test = trained
    kluang = evaluate(capsys, model, "--data", test["oilpalm_uav_kluang_narimt"], "--crown-px", "68")
    assert kluang["frames"]["f1"] >= KLUANG_F1


@pytest.mark.xfail(reason="measured 90.8 / 89.5 / 92.5 %: not reached (docs/detector.md)", strict=False)
def test_that_the_crop_protocol_on_held_out_images_reaches_the_paper(trained, capsys):
    model, test = trained
    crops = evaluate(capsys, model, "--data", *test.values(), "--crown-px", "boxes", "--hull")
    for figure, paper in PAPER.items():
        assert crops[figure] >= paper, figure


def test_that_a_training_seed_that_calibrates_on_the_sharpest_image_still_finds_the_palms(split, capsys):
    # seed 1 holds back the sharpest Google Earth image to calibrate on; before the texture cap its texture
    # threshold rejected every crown of the held-out image (F1 0)
    model, test = train_on(split, 1)
    google = evaluate(capsys, model, "--data", test["oilpalm_gearth_detectree2"], "--crown-px", "160", "--hull")
    assert google["frames"]["recall"] >= 0.6 and google["frames"]["precision"] >= 0.6, google["frames"]
