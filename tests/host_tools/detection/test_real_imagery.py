"""Opt-in (-m realdata): the user's path on ../shared/data/real, as docs/detector.md runs it.

Issue 35's figures: every shared set at once, split by group / region (seed 0), trained with the network
(`--cnn`; needs PyTorch, skipped without it; 15-25 minutes on 2 shared cores), scored on the held-out groups.
Targets not reached are expected failures carrying the measured figure (docs/detector.md has the table).
The last test keeps issue 9's texture-cap check on its image split of the older sources."""
import json

import pytest

from host_tools.cli import main
from tests.conftest import REPO_ROOT

pytestmark = [pytest.mark.realdata, pytest.mark.slow]

REAL = REPO_ROOT.parent / "shared" / "data" / "real"
ESTATE, ORTHO = "oilpalm_uav_globalpro_id", "oilpalm_uav_muchsin_id"
GOOGLE_EARTH, KLUANG, COCONUT = "oilpalm_gearth_detectree2", "oilpalm_uav_kluang_narimt", "coconut_tonga_oam"
ISSUE_9_SOURCES = (GOOGLE_EARTH, KLUANG, COCONUT, "olive_kallk", "neon_deepforest")
# issue 35's targets on held-out groups, thresholds chosen on the training side, crown size from the boxes
ESTATE_F1 = 0.92
ORTHO_F1 = 0.85
COCONUT_FALSE_ALARMS_PER_CHIP = 0.05
PAPER = {"accuracy": 0.9291, "precision": 0.9037, "recall": 0.9606}
# issue 9's, re-measured with the larger pool
GOOGLE_EARTH_F1 = 0.85
KLUANG_F1 = 0.65


def _sources():
    if not REAL.exists():
        pytest.skip("no shared real data")
    return sorted(p.parent.name for p in REAL.glob("*/boxes.csv"))


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    sources = _sources()
    pytest.importorskip("torch")
    root = tmp_path_factory.mktemp("real")
    assert main(["split", "--data"] + [str(REAL / s / "boxes.csv") for s in sources]
                + ["--by", "group", "--seed", "0", "--out", str(root / "split")]) == 0
    model = str(root / "real_cnn.npz")
    assert main(["train", "--species", "oil_palm", "--seed", "0", "--cnn", "--out", model, "--quiet", "--data"]
                + [str(root / "split" / "train" / s / "boxes.csv") for s in sources]) == 0
    return model, {s: str(root / "split" / "test" / s / "boxes.csv") for s in sources}


def evaluate(capsys, model, *args):
    capsys.readouterr()
    assert main(["evaluate", "--model", model, "--json"] + list(args)) == 0
    return json.loads(capsys.readouterr().out)


def test_that_the_held_out_estate_photos_reach_the_target_f1(trained, capsys):
    model, test = trained
    estate = evaluate(capsys, model, "--data", test[ESTATE], "--crown-px", "boxes")
    assert estate["frames"]["f1"] >= ESTATE_F1, estate["frames"]


def test_that_the_held_out_orthophoto_region_reaches_the_target_f1(trained, capsys):
    model, test = trained
    ortho = evaluate(capsys, model, "--data", test[ORTHO], "--crown-px", "boxes")
    assert ortho["frames"]["f1"] >= ORTHO_F1, ortho["frames"]


def test_that_coconut_chips_give_at_most_the_target_false_alarms_per_chip(trained, capsys):
    model, test = trained
    coconut = evaluate(capsys, model, "--data", test[COCONUT], "--crown-px", "24")
    assert coconut["frames"]["false_alarms_per_image"] <= COCONUT_FALSE_ALARMS_PER_CHIP


def test_that_the_crop_protocol_on_held_out_images_reaches_the_paper(trained, capsys):
    model, test = trained
    crops = evaluate(capsys, model, "--data", *test.values(), "--crown-px", "boxes", "--hull")
    for figure, paper in PAPER.items():
        assert crops[figure] >= paper, figure


@pytest.mark.xfail(reason="measured F1 84.62 % on the one held-out image (docs/detector.md)", strict=False)
def test_that_google_earth_oil_palm_reaches_issue_9s_f1(trained, capsys):
    model, test = trained
    google = evaluate(capsys, model, "--data", test[GOOGLE_EARTH], "--crown-px", "160", "--hull")
    assert google["frames"]["f1"] >= GOOGLE_EARTH_F1


def test_that_kluang_uav_oil_palm_reaches_issue_9s_f1(trained, capsys):
    model, test = trained
    kluang = evaluate(capsys, model, "--data", test[KLUANG], "--crown-px", "68")
    assert kluang["frames"]["f1"] >= KLUANG_F1


def test_that_a_training_seed_that_calibrates_on_the_sharpest_image_still_finds_the_palms(tmp_path, capsys):
    # issue 9: seed 1 holds back the sharpest Google Earth image to calibrate on; before the texture cap its
    # texture threshold rejected every crown of the held-out image (F1 0)
    _sources()
    assert main(["split", "--data"] + [str(REAL / s / "boxes.csv") for s in ISSUE_9_SOURCES]
                + ["--held-out", "0.25", "--seed", "0", "--out", str(tmp_path / "split")]) == 0
    model = str(tmp_path / "seed1.npz")
    assert main(["train", "--species", "oil_palm", "--seed", "1", "--out", model, "--quiet", "--data"]
                + [str(tmp_path / "split" / "train" / s / "boxes.csv") for s in ISSUE_9_SOURCES]) == 0
    google = evaluate(capsys, model, "--data", str(tmp_path / "split" / "test" / GOOGLE_EARTH / "boxes.csv"),
                      "--crown-px", "160", "--hull")
    assert google["frames"]["recall"] >= 0.6 and google["frames"]["precision"] >= 0.6, google["frames"]
